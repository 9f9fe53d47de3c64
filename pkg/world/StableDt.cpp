// Stable time step of the explicit scheme.  Derivation: doc/formulation.md,
// "Stable time step".
//
// Element: by Irons' element eigenvalue theorem the highest frequency of the
// assembled lumped-mass mesh is below the highest frequency of any single
// element with its own lumped mass rho*V/4 per node.  For each element a cheap
// upper bound of that frequency comes first (lambda_max(K_e) <=
// V (lambda + 2 mu) sum_a |grad N_a|^2); exact 12x12 eigenvalues are then
// computed only for the elements whose bound could still be the largest.
// Kelvin-Voigt viscosity here is stiffness-proportional (C_e = beta K_e), so
// each element mode of frequency w has damping ratio beta*w/2.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <limits>
#include <numeric>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../contact/ContactModel.hpp"
#include "../element/MaterialLaw.hpp"
#include "World.hpp"

namespace qdem {

namespace {

using Mat12 = Eigen::Matrix<double, 12, 12>;

// Small-strain stiffness of one element with Lame constants (lambda, mu),
// in closed form.
// Reference gradients of the four shape functions: rows of B for nodes
// 1..3, minus their sum for node 0.
Eigen::Matrix<double, 4, 3> shapeGradients(const Mat3& B) {
    Eigen::Matrix<double, 4, 3> G;
    G.row(1) = B.row(0);
    G.row(2) = B.row(1);
    G.row(3) = B.row(2);
    G.row(0) = -(B.row(0) + B.row(1) + B.row(2));
    return G;
}

Mat12 hookeStiffness(const Mat3& B, double V, double lambda, double mu) {
    const Eigen::Matrix<double, 4, 3> G = shapeGradients(B);
    Mat12 K;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            const double gg = G.row(a).dot(G.row(b));
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    K(3 * a + i, 3 * b + j) =
                        V * (lambda * G(a, i) * G(b, j) + mu * G(a, j) * G(b, i) + (i == j ? mu * gg : 0.0));
        }
    return K;
}

// Stiffness of one element from the law's tangent A = dP/dF at its current
// F: K_(a i)(b k) = V sum_JL g_aJ A_(iJ)(kL) g_bL, with g_a the reference
// gradients of the shape functions (rows of B for nodes 1..3, minus their sum
// for node 0).  At F = I this is the small-strain (Hooke) stiffness, the same
// for every law; on a strained shape it includes the geometric part.
Mat12 elementStiffness(const Mat3& B, const Mat9& A, double V) {
    const Eigen::Matrix<double, 4, 3> G = shapeGradients(B);
    Mat12 K;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
            for (int i = 0; i < 3; ++i)
                for (int k = 0; k < 3; ++k) {
                    double s = 0;
                    for (int J = 0; J < 3; ++J)
                        for (int L = 0; L < 3; ++L) s += G(a, J) * A(3 * i + J, 3 * k + L) * G(b, L);
                    K(3 * a + i, 3 * b + k) = V * s;
                }
    return K;
}

// Largest eigenvalue of an element matrix.  GCC 12 (bug 105593, see
// CMakeLists.txt) reports the deliberately undefined pass-through operand of
// _mm512_max_pd in avx512fintrin.h as "used uninitialized" once Eigen's
// solver is inlined here: a false positive, silenced for this function only.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif
__attribute__((noinline)) double largestEigenvalue(const Mat12& K) {
    Eigen::SelfAdjointEigenSolver<Mat12> es(K, Eigen::EigenvaluesOnly);
    return es.eigenvalues().maxCoeff();
}
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic pop
#endif

}  // namespace

double World::elementOmegaMax(const PieceInfo& p) const {
    const Material& m = materials[p.material];
    const double lam = m.lambda(), mu = m.mu();
    const int32_t n = p.tetEnd - p.tetBegin;
    std::vector<double> bound(n);
    for (int32_t e = 0; e < n; ++e) {
        const Mat3 B = loadRowMajor(&tetB[9 * (p.tetBegin + e)]);
        const double sumG2 = B.squaredNorm() + (B.row(0) + B.row(1) + B.row(2)).squaredNorm();
        // omega^2 = lambda_max(K) / (rho V / 4); V cancels.
        bound[e] = 4.0 * (std::max(lam, 0.0) + 2 * mu) * sumG2 / m.density;
    }
    if (omega2Tet_.size() < nTets()) omega2Tet_.resize(nTets(), 0.0);
    for (int32_t e = 0; e < n; ++e) omega2Tet_[p.tetBegin + e] = bound[e];
    std::vector<int32_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return bound[a] > bound[b]; });
    double best = 0;  // exact omega^2 maximum found so far
    // Structured meshes repeat a few element shapes thousands of times: the
    // eigenvalue depends only on B, so identical B are solved once.
    std::map<std::array<double, 9>, double> solved;
    // The reference stiffness is the law's tangent at F = I, which every law
    // makes Hooke's with the material's (lambda, mu) (lameAtRest; checked
    // against tangent(I) in tests/cpp/test_laws.cpp): the closed form.
    double lam0 = lam, mu0 = mu;
    withLaw(m, [&](const auto& law) { law.lameAtRest(lam0, mu0); });
    for (int32_t k = 0; k < n && bound[order[k]] > best; ++k) {
        const int32_t e = p.tetBegin + order[k];
        std::array<double, 9> key;
        std::copy(&tetB[9 * e], &tetB[9 * e] + 9, key.begin());
        if (solved.count(key)) {
            omega2Tet_[e] = solved[key];
            continue;
        }
        const Mat3 B = loadRowMajor(&tetB[9 * e]);
        const Mat12 K = hookeStiffness(B, tetVol0[e], lam0, mu0);
        const double w2 = largestEigenvalue(K) / (m.density * tetVol0[e] / 4.0);
        solved[key] = w2;
        omega2Tet_[e] = w2;
        best = std::max(best, w2);
    }
    return std::sqrt(best);
}

void World::checkCurrentDt(double dt) const {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError(cat("QDEM: time step ", dt, " is not a positive number"));
    requireGathered("checkCurrentDt");
    stableDt();  // fills the reference frequencies
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (asleep(i)) continue;  // does not move: checked while it was awake, and again when it wakes
        const PieceInfo& p = pieces[i];
        const Material& m = materials[p.material];
        // Implicit viscosity damps without limiting the step (stableDt()).
        const bool implicit = settings.viscousIntegration == ViscousIntegration::Implicit;
        const double beta = settings.viscosityOn && !implicit ? m.beta() : 0.0;
        double wc = 0, xic = 0;
        contactMode(i, wc, xic);  // as in stableDt()
        auto limitAt = [&](double we) {
            const double w = std::sqrt(we * we + wc * wc);
            const double c = beta * we * we + 2 * xic * wc;
            return leapfrogLimit(w, w > 0 ? c / (2 * w) : 0.0);
        };
        if (limitAt(0) < dt) continue;  // the contact limit alone: checkDt's business
        // Largest element frequency this dt allows (limitAt decreases with it).
        double lo = 0, hi = std::max(omegaCache_[i], 1e-300);
        for (int k = 0; k < 2000 && limitAt(hi) >= dt; ++k) hi *= 2;
        for (int k = 0; k < 100; ++k) {
            const double mid = 0.5 * (lo + hi);
            (limitAt(mid) >= dt ? lo : hi) = mid;
        }
        const double allow2 = lo * lo;
        withLaw(m, [&](const auto& law) {
            for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) {
                const int32_t* c = &tetNodes[4 * e];
                const Mat3 B = loadRowMajor(&tetB[9 * e]);
                const Mat3 F = edgeMatrix(&pos[3 * c[0]], &pos[3 * c[1]], &pos[3 * c[2]], &pos[3 * c[3]]) * B;
                const Mat3 C = F.transpose() * F;
                Eigen::SelfAdjointEigenSolver<Mat3> ec;
                ec.computeDirect(C, Eigen::EigenvaluesOnly);
                const double s2 = ec.eigenvalues()(2);  // largest principal stretch, squared
                // The law's estimate of the stiffening filters; the exact
                // eigenvalue of its tangent stiffness decides.
                if (!(omega2Tet_[e] * law.stiffening(C, s2) * 1.1 > allow2)) continue;  // (NaN: checkFinite's)
                const Mat12 K = elementStiffness(B, law.tangent(F), tetVol0[e]);
                const double w2 = largestEigenvalue(K) / (m.density * tetVol0[e] / 4.0);
                if (w2 <= allow2) continue;
                const double now = limitAt(std::sqrt(w2)), J = F.determinant();
                const std::string where = cat("QDEM: at step ", iter, " tetrahedron ", e - p.tetBegin, " of piece ", i);
                const std::string limit = cat("the stable time step on the current shape is ", now, " s, below dt=", dt,
                                              " s by a factor ", dt / now, " (reference shape: ",
                                              limitAt(omegaCache_[i]), " s)");
                if (J <= 0)
                    throw StabilityError(cat(
                        where, " is inverted (volume ratio ", J, ", law ", lawName(m.law), ") and ", limit,
                        ". The element was crushed through itself: use law='stableNeoHookean' (the default), a "
                        "stiffer material or a smaller impact speed; or lower O.dt."));
                throw StabilityError(cat(where, " is strained (largest stretch ", std::sqrt(s2), ", volume ratio ", J,
                                         ") and has stiffened: ", limit, ". Lower O.dt, or use a mesh without slivers."));
            }
        });
    }
}

// Stiffest contact spring of piece i over its surface nodes (largest
// w_i kn / m_i; YADE spheres' springs are not area-weighted: lightest node):
// its angular frequency wc and damping ratio xic (0, 0 when nothing can touch it).
void World::contactMode(std::size_t i, double& wc, double& xic) const {
    const PieceInfo& p = pieces[i];
    const Material& m = materials[p.material];
    wc = 0, xic = 0;
    if (!obstacles.empty() || pieces.size() > 1) {
        double stiffestObstacle = 0;  // Young of the stiffest obstacle; <= 0 means rigid
        bool rigid = false;
        for (const auto& o : obstacles) {
            if (o.young <= 0) rigid = true;
            stiffestObstacle = std::max(stiffestObstacle, o.young);
        }
        // The stiffest pair this piece can meet (ContactModel.hpp): a rigid
        // obstacle, or another piece (piece-piece springs are at most the
        // rigid-wall 2 E r too), else the stiffest elastic obstacle.
        const ContactSide other = (rigid || pieces.size() > 1) ? rigidSide()
                                                               : obstacleSide(stiffestObstacle, -1, m.radius);
        const PairConst pair = mix(materialSide(m, 0), other);
        // Each node's springs are scaled by its area weight w (surfWeight):
        // the stiffest mode is the largest w kn / m over the surface nodes.
        wc = std::sqrt(pair.kn / p.minSurfaceMassPerWeight);
        xic = pair.xi;
    }
    if (i < spheres.pieceKnMax.size() && spheres.pieceKnMax[i] > 0) {
        // YADE spheres near the piece: their springs on its lightest node.
        const double ws = std::sqrt(spheres.pieceKnMax[i] / p.minSurfaceNodeMass);
        if (ws > wc) wc = ws, xic = dampingRatioFromRestitution(m.restitution);
    }
}

StableDt World::stableDt() const {
    const double inf = std::numeric_limits<double>::infinity();
    StableDt r{inf, inf, inf, inf, "none", inf, inf};
    if (omegaCache_.size() != pieces.size()) {
        omegaCache_.resize(pieces.size());
        for (std::size_t i = 0; i < pieces.size(); ++i) omegaCache_[i] = elementOmegaMax(pieces[i]);
    }
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const PieceInfo& p = pieces[i];
        const Material& m = materials[p.material];
        const double we = omegaCache_[i];
        const double beta = settings.viscosityOn ? m.beta() : 0.0;
        r.elastic = std::min(r.elastic, leapfrogLimit(we, 0.0));
        r.viscous = std::min(r.viscous, leapfrogLimit(we, 0.5 * beta * we));
        double wc = 0, xic = 0;
        contactMode(i, wc, xic);
        if (wc > 0) r.contact = std::min(r.contact, leapfrogLimit(wc, xic));
        // Element and contact springs on the same node: frequencies add in
        // quadrature, damping rates (c/m) add.
        const double w = std::sqrt(we * we + wc * wc);
        const double c = beta * we * we + 2 * xic * wc;
        r.combinedExplicit = std::min(r.combinedExplicit, leapfrogLimit(w, w > 0 ? c / (2 * w) : 0.0));
        // Implicit viscosity: for one mode with explicit damping ratio xi_e
        // and implicit xi_i the limit is leapfrogLimit(w, xi_e - xi_i)
        // (doc/formulation.md 3), never below the undamped one.  Only the
        // explicit (contact) damping is counted: the implicit part would
        // raise the limit past 2/w only for modes that C damps as it damps
        // K (stiffness-proportional), which large strains do not ensure.
        const double ce = 2 * xic * wc;
        r.combinedImplicit = std::min(r.combinedImplicit, leapfrogLimit(w, w > 0 ? ce / (2 * w) : 0.0));
    }
    const bool implicit = settings.viscousIntegration == ViscousIntegration::Implicit;
    r.combined = implicit ? r.combinedImplicit : r.combinedExplicit;
    if (spheres.omegaMax > 0) {
        // The same springs on the sphere side (undamped: the conservative bound).
        const double ds = leapfrogLimit(spheres.omegaMax, 0.0);
        r.contact = std::min(r.contact, ds);
        r.combined = std::min(r.combined, ds);
        r.combinedExplicit = std::min(r.combinedExplicit, ds);
        r.combinedImplicit = std::min(r.combinedImplicit, ds);
    }
    const double lim = std::min({r.elastic, implicit ? r.elastic : r.viscous, r.contact});
    if (std::isfinite(lim)) {
        if (r.contact == lim) r.limitedBy = "contact";
        else if (!implicit && r.viscous < r.elastic) r.limitedBy = "viscosity";
        else r.limitedBy = "elasticity (P-wave)";
    }
    return r;
}

void World::checkDt(double dt) const {
    const StableDt s = stableDt();
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError(cat("QDEM: time step ", dt, " is not a positive number"));
    if (dt > s.combined)
        throw StabilityError(cat("QDEM: O.dt=", dt, " s exceeds the stable time step ", s.combined,
                                 " s by a factor ", dt / s.combined, " (limited by ", s.limitedBy,
                                 "; elastic limit ", s.elastic, " s, with viscosity ", s.viscous,
                                 " s, contact ", s.contact, " s). Lower O.dt, the viscosity or the stiffness",
                                 s.limitedBy == "viscosity"
                                     ? cat(", or set QdemEngine(viscousIntegration='implicit') (limit ",
                                           s.combinedImplicit, " s).")
                                     : std::string(".")));
}

}  // namespace qdem
