// Which elements set a piece's element step, and by how much they cut it
// against the piece's median element (StepReport.hpp).  Element step: the
// leapfrog limit of the element's highest frequency on its own lumped mass
// (Irons' element eigenvalue theorem, doc/formulation.md "Stable time step");
// every comparison here is between those frequencies, at rest.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../element/MaterialLaw.hpp"
#include "../element/Tetra.hpp"
#include "World.hpp"

namespace qdem {

namespace {

// Smallest height over longest edge of a tetrahedron: 3V / (largest face
// area) / (longest edge).  0.816 for a regular one; a sliver (four nearly
// coplanar nodes) goes to 0 whatever its edges.
double shapeQuality(const double* x0, const double* x1, const double* x2, const double* x3) {
    const Eigen::Vector3d p[4] = {Eigen::Vector3d(x0), Eigen::Vector3d(x1), Eigen::Vector3d(x2), Eigen::Vector3d(x3)};
    const double vol6 = std::fabs((p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]));
    double faceMax = 0, edgeMax = 0;
    for (int a = 0; a < 4; ++a) {
        for (int b = a + 1; b < 4; ++b) edgeMax = std::max(edgeMax, (p[b] - p[a]).norm());
        const Eigen::Vector3d& u = p[(a + 1) % 4];
        const Eigen::Vector3d& v = p[(a + 2) % 4];
        const Eigen::Vector3d& w = p[(a + 3) % 4];
        faceMax = std::max(faceMax, 0.5 * (v - u).cross(w - u).norm());
    }
    return faceMax > 0 && edgeMax > 0 ? 0.5 * vol6 / faceMax / edgeMax : 0.0;  // h = 3V / A, V = vol6 / 6
}

}  // namespace

void World::setTetIds(int piece, const std::vector<int32_t>& ids) {
    if (piece < 0 || piece >= static_cast<int>(pieces.size()))
        throw InputError(cat("setTetIds: no piece ", piece));
    const PieceInfo& p = pieces[piece];
    if (ids.size() != static_cast<std::size_t>(p.tetEnd - p.tetBegin))
        throw InputError(cat("setTetIds: piece ", piece, " has ", p.tetEnd - p.tetBegin, " tetrahedra, got ",
                             ids.size(), " ids"));
    if (tetIds_.size() < nTets()) tetIds_.resize(nTets(), -1);
    std::copy(ids.begin(), ids.end(), tetIds_.begin() + p.tetBegin);
}

const PieceStepReport& World::pieceStepReport(std::size_t i) const {
    if (stepReports_.size() < pieces.size()) {
        stepReports_.resize(pieces.size());
        stepReportDone_.resize(pieces.size(), 0);
    }
    PieceStepReport& r = stepReports_[i];
    if (stepReportDone_[i]) return r;
    const PieceInfo& p = pieces[i];
    // Each element's Lame constants at rest (as elementOmegaMax; a bonded
    // piece's elements each with their own material).
    auto lameAtRest = [&](int32_t e, double& lam, double& mu) {
        const Material& m = tetMat(e);
        lam = m.lambda(), mu = m.mu();
        withLaw(m, [&](const auto& law) { law.lameAtRest(lam, mu); });
    };
    const int32_t n = p.tetEnd - p.tetBegin;
    // Identical shapes (structured meshes) are solved once.
    // Selective mass scaling (MassScaling.cpp) adds mass per tet: the
    // element's own mass is rho V + added, its effective density below.
    auto density = [&](int32_t e) { return tetMat(e).density + tetAddedMass[e] / tetVol0[e]; };
    std::map<std::array<double, 11>, double> solved;
    auto exact = [&](int32_t local) {
        const int32_t e = p.tetBegin + local;
        std::array<double, 11> key;
        std::copy(&tetB[9 * e], &tetB[9 * e] + 9, key.begin());
        key[9] = tetAddedMass[e];
        key[10] = tetMaterial[e];
        const auto it = solved.find(key);
        if (it != solved.end()) return it->second;
        double lam, mu;
        lameAtRest(e, lam, mu);
        const double w2 = restElementOmega2(&tetB[9 * e], tetVol0[e], lam, mu, density(e));
        solved.emplace(key, w2);
        return w2;
    };
    // The stiffest elements: by the cheap upper bound (elementOmegaMax's)
    // first, exact frequencies for every element whose bound reaches a
    // quarter of the largest exact one found (omega within 2x).
    std::vector<double> bound(n);
    for (int32_t e = 0; e < n; ++e) {
        double lam, mu;
        lameAtRest(p.tetBegin + e, lam, mu);
        const double c = 4.0 * (std::max(lam, 0.0) + 2 * mu);
        const Mat3 B = loadRowMajor(&tetB[9 * (p.tetBegin + e)]);
        bound[e] = c / density(p.tetBegin + e) * (B.squaredNorm() + (B.row(0) + B.row(1) + B.row(2)).squaredNorm());
    }
    std::vector<int32_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return bound[a] > bound[b]; });
    double best = 0;
    std::vector<std::pair<double, int32_t>> near;  // (omega^2, local tet)
    for (int32_t k = 0; k < n && bound[order[k]] >= 0.25 * best; ++k) {
        const double w2 = exact(order[k]);
        best = std::max(best, w2);
        near.emplace_back(w2, order[k]);
    }
    std::erase_if(near, [&](const auto& a) { return a.first < 0.25 * best; });
    std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) {
        return a.first > b.first || (a.first == b.first && a.second < b.second);
    });
    // The median element: exact frequencies of every element up to kSample
    // of them, else of kSample at an even stride (its step to well under 1 %).
    // In a bonded piece of several materials, of the elements of the
    // stiffest one's material: the others' steps differ by their material,
    // which is no defect of the mesh.
    std::vector<int32_t> same;
    if (p.materialCount > 1 && !near.empty())
        for (int32_t e = 0; e < n; ++e)
            if (tetMaterial[p.tetBegin + e] == tetMaterial[p.tetBegin + near.front().second]) same.push_back(e);
    const auto nm = same.empty() ? n : static_cast<int32_t>(same.size());
    auto member = [&](int32_t k) { return same.empty() ? k : same[k]; };
    constexpr int32_t kSample = 4096;
    const int32_t ns = std::min(nm, kSample);
    std::vector<double> sample(ns);
    for (int32_t k = 0; k < ns; ++k) sample[k] = exact(member(nm <= kSample ? k : int32_t(int64_t(k) * nm / kSample)));
    if (ns > 0) {
        // The median step is the ns/2-th smallest step: the ns/2-th largest frequency.
        std::nth_element(sample.begin(), sample.begin() + ns / 2, sample.end(), std::greater<double>());
        r.omegaMedian = std::sqrt(sample[ns / 2]);
    }
    r.omegaMax = std::sqrt(best);
    r.nearLimit = static_cast<int64_t>(near.size());
    for (const auto& [w2, local] : near) {
        const int32_t* t = &tetNodes[4 * (p.tetBegin + local)];
        const double q = shapeQuality(&refPos[3 * t[0]], &refPos[3 * t[1]], &refPos[3 * t[2]], &refPos[3 * t[3]]);
        if (!(q >= r.worstQuality)) r.worstQuality = q;  // (NaN at first)
        if (static_cast<int>(r.worst.size()) < PieceStepReport::kListed) r.worst.push_back(local);
    }
    stepReportDone_[i] = 1;
    return r;
}

std::string World::describeElementLimit(const StableDt& s) const {
    if (s.piece < 0) return {};
    const bool viscous = s.pieceViscous < s.pieceElastic;
    const double step = viscous ? s.pieceViscous : s.pieceElastic;
    const double median = viscous ? s.medianViscous : s.medianElastic;
    std::string ids;
    for (std::size_t k = 0; k < s.elements.size(); ++k) ids += cat(k ? ", " : "", s.elements[k]);
    if (s.elementsNearLimit > static_cast<int64_t>(s.elements.size())) ids += ", ...";
    return cat("piece ", s.piece, ", tetrahedra ", ids, " (its mesh's numbering; ", s.elementsNearLimit,
               s.elementsNearLimit == 1 ? " element" : " elements", " within 2x of its step ", step,
               " s, worst shape quality ", s.worstQuality, " as min height / longest edge, 0.816 regular): ",
               median / step, "x below the ", median, " s its median element allows",
               // Good meshes reach ~4.5 (qdem.meshchecks.SLIVER_FACTOR): name remedies above 5.
               s.medianElastic / s.pieceElastic > 5 ? " (slivers: qdem.improveMesh(mesh) remeshes them away, "
                                   "qdem.addPiece(..., targetDt=...) adds mass to them alone, or mesh again with "
                                   "TetGen -q or gmsh's optimiser)"
                                 : "");
}

}  // namespace qdem
