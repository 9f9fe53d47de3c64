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
#include "Phases.hpp"
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
// solver is inlined here: a false positive, silenced for the solvers below only.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif
__attribute__((noinline)) double largestEigenvalue(const Mat12& K) {
    Eigen::SelfAdjointEigenSolver<Mat12> es(K, Eigen::EigenvaluesOnly);
    return es.eigenvalues().maxCoeff();
}

// sigma_max(G)^2 = lambda_max(G'G) of the 4x3 shape-function gradients: the
// largest |grad u|^2 a unit nodal displacement field makes.
double gradientNorm2(const Mat3& B) {
    const Eigen::Matrix<double, 4, 3> G = shapeGradients(B);
    Eigen::SelfAdjointEigenSolver<Mat3> es;
    es.computeDirect(G.transpose() * G, Eigen::EigenvaluesOnly);
    return es.eigenvalues()(2);
}

// The explicit viscous operator of one element on its current shape: the
// nodal forces of the Kelvin-Voigt stress S_v = beta D0[F' dF/dt], D0[Y] =
// lambda tr(Y) I + 2 mu sym(Y), P_v = F S_v, are -C v (ViscousOperator.hpp).
Mat12 viscousMatrix(const Mat3& F, const Mat3& B, double V, double lambda, double mu, double beta) {
    const Eigen::Matrix<double, 4, 3> G = shapeGradients(B);
    Mat12 Cm;
    for (int b = 0; b < 4; ++b)
        for (int k = 0; k < 3; ++k) {
            Mat3 Fdot = Mat3::Zero();
            Fdot.row(k) = G.row(b);
            const Mat3 Y = F.transpose() * Fdot;
            Mat3 S = beta * mu * (Y + Y.transpose());
            S.diagonal().array() += beta * lambda * Y.trace();
            const Mat3 P = F * S;
            for (int a = 0; a < 4; ++a) Cm.block<3, 1>(3 * a, 3 * b + k) = V * P * G.row(a).transpose();
        }
    return 0.5 * (Cm + Cm.transpose());
}

// K with its negative eigenvalues set to zero: a softening direction grows
// whatever the step (a buckling element); the step limits the others.
Mat12 positivePart(const Mat12& K) {
    Eigen::SelfAdjointEigenSolver<Mat12> es(0.5 * (K + K.transpose()));
    return es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
}

#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
#pragma GCC diagnostic pop
#endif

// Largest step at which one element's leapfrog update with lagged dashpots
// is stable by the energy condition M - dt/2 C - dt^2/4 K > 0 (doc/
// formulation.md, "Stable time step"), its node masses 1, with a node's
// contact damping rate cRate and frequency squared w2c added: bisection.
double leapfrogStep(const Mat12& Kpm, const Mat12& Cpm, double cRate, double w2c, double dt) {
    auto stable = [&](double h) {
        return 0.5 * h * cRate + 0.25 * h * h * w2c + largestEigenvalue(0.5 * h * Cpm + 0.25 * h * h * Kpm) < 1.0;
    };
    double lo = 0, hi = dt;
    for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (stable(mid) ? lo : hi) = mid;
    }
    return lo;
}

}  // namespace

double hookeStiffnessMax(const Mat3& B, double V, double lambda, double mu) {
    return largestEigenvalue(hookeStiffness(B, V, lambda, mu));
}

// The exact largest frequency squared of one element at rest on its own
// lumped mass density V / 4 per node (StepReport.cpp; the density includes
// the mass selective mass scaling added to the element).
double restElementOmega2(const double* B9, double V, double lambda, double mu, double density) {
    const Mat3 B = loadRowMajor(B9);
    return largestEigenvalue(hookeStiffness(B, V, lambda, mu)) / (density * V / 4.0);
}

double World::elementOmegaMax(const PieceInfo& p) const {
    const int32_t n = p.tetEnd - p.tetBegin;
    std::vector<double> bound(n);
    for (int32_t e = 0; e < n; ++e) {
        const Material& m = tetMat(p.tetBegin + e);  // (a bonded piece: each element its own)
        const double lam = m.lambda(), mu = m.mu();
        const Mat3 B = loadRowMajor(&tetB[9 * (p.tetBegin + e)]);
        const double sumG2 = B.squaredNorm() + (B.row(0) + B.row(1) + B.row(2)).squaredNorm();
        // omega^2 = lambda_max(K) / (rho V / 4); V cancels.  Mass added by
        // selective mass scaling counts as density (added / V) on top of rho.
        const int32_t t = p.tetBegin + e;
        bound[e] = 4.0 * (std::max(lam, 0.0) + 2 * mu) * sumG2 / (m.density + tetAddedMass[t] / tetVol0[t]);
    }
    if (omega2Tet_.size() < nTets()) omega2Tet_.resize(nTets(), 0.0);
    for (int32_t e = 0; e < n; ++e) omega2Tet_[p.tetBegin + e] = bound[e];
    std::vector<int32_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return bound[a] > bound[b]; });
    double best = 0;  // exact omega^2 maximum found so far
    // Structured meshes repeat a few element shapes thousands of times: the
    // eigenvalue depends only on B, so identical B are solved once.
    // (The key holds the added mass and the material too: two such elements
    // may differ in them.)
    std::map<std::array<double, 11>, double> solved;
    for (int32_t k = 0; k < n && bound[order[k]] > best; ++k) {
        const int32_t e = p.tetBegin + order[k];
        const Material& m = tetMat(e);
        // The reference stiffness is the law's tangent at F = I, which every law
        // makes Hooke's with the material's (lambda, mu) (lameAtRest; checked
        // against tangent(I) in tests/cpp/test_laws.cpp): the closed form.
        double lam0 = m.lambda(), mu0 = m.mu();
        withLaw(m, [&](const auto& law) { law.lameAtRest(lam0, mu0); });
        std::array<double, 11> key;
        std::copy(&tetB[9 * e], &tetB[9 * e] + 9, key.begin());
        key[9] = tetAddedMass[e];
        key[10] = tetMaterial[e];
        if (solved.count(key)) {
            omega2Tet_[e] = solved[key];
            continue;
        }
        const Mat3 B = loadRowMajor(&tetB[9 * e]);
        const Mat12 K = hookeStiffness(B, tetVol0[e], lam0, mu0);
        const double w2 = largestEigenvalue(K) / elementNodeMass(e, m);
        solved[key] = w2;
        omega2Tet_[e] = w2;
        best = std::max(best, w2);
    }
    return std::sqrt(best);
}

// A step that is not a positive finite number, with the likely cause named:
// stableTimeStep() is inf while no piece is there, and 0.8 x inf is inf.
static void requirePositiveFinite(double dt) {
    if (dt > 0 && std::isfinite(dt)) return;
    if (std::isinf(dt) && dt > 0)
        throw StabilityError(
            "QDEM: time step inf is not a positive number. A stable time step computed before any piece was added "
            "is inf (nothing limits it): set O.dt from QdemEngine.stableTimeStep() after qdem.addPiece, or give it "
            "a number.");
    throw StabilityError(cat("QDEM: time step ", dt, " is not a positive number"));
}

void World::checkCurrentDt(double dt) const {
    requirePositiveFinite(dt);
    requireGathered("checkCurrentDt");
    stableDt();  // fills the reference frequencies
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        if (asleep(i)) continue;  // does not move: checked while it was awake, and again when it wakes
        const PieceInfo& p = pieces[i];
        // Implicit viscosity damps without limiting the step (stableDt()).
        const bool implicit = settings.viscousIntegration == ViscousIntegration::Implicit;
        double wc = 0, xic = 0;
        contactMode(i, wc, xic);  // as in stableDt()
        // The contact springs and dashpots on a node, as a share of its mass
        // (doc/formulation.md, "Stable time step"): what an element may use
        // of the leapfrog condition M - dt/2 C - dt^2/4 K > 0 is what they leave.
        const double room = 1.0 - 0.5 * dt * 2 * xic * wc - 0.25 * dt * dt * wc * wc;
        if (!(room > 0)) continue;  // the contact limit alone: checkDt's business
        for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) {
            const Material& m = tetMat(e);  // (a bonded piece: each element its own)
            const double beta = settings.viscosityOn && !implicit ? m.beta() : 0.0;
            const double lam = m.lambda(), mu = m.mu();
            const double d0 = std::max(3 * lam + 2 * mu, 2 * mu);  // ||D0||, the Kelvin-Voigt stress per strain rate
            withLaw(m, [&](const auto& law) {
                const int32_t* c = &tetNodes[4 * e];
                const Mat3 B = loadRowMajor(&tetB[9 * e]);
                const Mat3 F = edgeMatrix(&pos[3 * c[0]], &pos[3 * c[1]], &pos[3 * c[2]], &pos[3 * c[3]]) * B;
                const Mat3 C = F.transpose() * F;
                Eigen::SelfAdjointEigenSolver<Mat3> ec;
                ec.computeDirect(C, Eigen::EigenvaluesOnly);
                const double s2 = ec.eigenvalues()(2);  // largest principal stretch, squared
                // Filter: bounds of the element's omega^2 and damping rate on
                // its current shape, from the reference ones by Weyl's
                // inequality (the change of the tangent, and of the viscous
                // operator F D0[F' .], times sigma_max(G)^2 per unit mass).
                const double perMass = 4.0 / (m.density + tetAddedMass[e] / tetVol0[e]) * gradientNorm2(B);
                const double h = (F - Mat3::Identity()).norm(), s1 = std::sqrt(std::max(s2, 0.0));
                const double w2 = omega2Tet_[e] + perMass * law.tangentChangeBound(F, s1);
                const double rate = beta * (omega2Tet_[e] + perMass * d0 * h * (s1 + 1.0));
                if (0.5 * dt * rate + 0.25 * dt * dt * w2 < room) return;  // (NaN: checkFinite's)
                // The exact condition on the element's own matrices.
                const double nodeMass = elementNodeMass(e, m);
                const Mat12 K = elementStiffness(B, law.tangent(F), tetVol0[e]);
                const Mat12 Cv = beta > 0 ? viscousMatrix(F, B, tetVol0[e], lam, mu, beta) : Mat12::Zero();
                const Mat12 Kp = positivePart(K);
                if (largestEigenvalue(0.5 * dt * Cv + 0.25 * dt * dt * Kp) / nodeMass < room) return;
                const double now = leapfrogStep(Kp / nodeMass, Cv / nodeMass, 2 * xic * wc, wc * wc, dt);
                const double J = F.determinant();
                const std::string where = cat("QDEM: at step ", iter, " tetrahedron ", e - p.tetBegin, " of piece ", i);
                const double we = omegaCache_[i];
                const std::string limit =
                    cat("the stable time step on the current shape is ", now, " s, below dt=", dt, " s by a factor ",
                        dt / now, " (reference shape: ",
                        leapfrogLimit(std::sqrt(we * we + wc * wc),
                                      (beta * we * we + 2 * xic * wc) / (2 * std::max(std::sqrt(we * we + wc * wc), 1e-300))),
                        " s)");
                if (J <= 0)
                    throw StabilityError(cat(
                        where, " is inverted (volume ratio ", J, ", law ", lawName(m.law), ") and ", limit,
                        ". The element was crushed through itself: use law='stableNeoHookean' (the default), a "
                        "stiffer material or a smaller impact speed; or lower O.dt."));
                throw StabilityError(cat(where, " is strained (largest stretch ", s1, ", volume ratio ", J,
                                         ") and has stiffened: ", limit, ". Lower O.dt, or use a mesh without slivers."));
            });
        }
    }
}

// Whether contacts carry a tangential spring: friction on, with the spring
// law (the regularised law's drag is implicit, no spring).
bool World::tangentialSprings() const {
    return settings.frictionOn && settings.frictionModel == FrictionModel::Spring;
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
        // A node of a coarse piece also carries, through its triangles'
        // barycentric weights, the reactions of every node of a finer piece
        // pressing on them: about (its area A_i) / (the finer piece's mean
        // area per node) of them, so its weight is taken as A_i over the
        // smallest mean area per node of the pieces it can meet, when that
        // is smaller than its own (Gershgorin on the corner's row: doc/
        // contacts.md §7).  A 1-cell cube under an 8x8x8-cell one gained
        // energy without bound at 0.9 x the former step (found by a tester).
        if (shareCacheN_ != pieces.size()) {
            shareMin1_ = shareMin2_ = std::numeric_limits<double>::infinity();
            for (std::size_t j = 0; j < pieces.size(); ++j) {
                const double a = pieces[j].meanSurfaceShare;
                if (!(a > 0)) continue;
                if (a < shareMin1_) shareMin2_ = shareMin1_, shareMin1_ = a, shareArgMin_ = j;
                else if (a < shareMin2_) shareMin2_ = a;
            }
            shareCacheN_ = pieces.size();
        }
        const double finest = std::min(p.meanSurfaceShare, i == shareArgMin_ ? shareMin2_ : shareMin1_);
        // A node's normal spring kn and tangential spring kt act on it in
        // different directions: the stiffer one sets the mode (kt > kn for
        // Poisson ratios below 0, Mindlin's ratio up to 4/3).  Both dashpots
        // keep the pair's damping ratio (ContactModel.hpp).
        // (No friction, or the regularised law's implicit drag: no tangential spring.)
        const bool spring = tangentialSprings() && std::max(m.frictionWall, m.frictionPiece) > 0;
        wc = std::sqrt((spring ? std::max(pair.kn, pair.kt) : pair.kn) /
                       (p.minSurfaceMassPerWeight * (finest / p.meanSurfaceShare)));
        xic = pair.xi;
    }
    const SphereSet::StepBound& sb = spheres.bound[tangentialSprings() ? 1 : 0];
    if (i < sb.pieceK.size() && sb.pieceK[i] > 0) {
        // YADE spheres near the piece: their springs on its lightest node and
        // on the sphere's own mass (two masses on one spring), their dashpots'
        // largest rate (SpherePhase::setSpheres).
        const double ws = std::sqrt(sb.pieceK[i] / p.minSurfaceNodeMass + sb.pieceSphereW2[i]);
        if (ws > wc) wc = ws, xic = std::max(xic, sb.pieceSphereRate[i] / (2 * ws));
    }
}

// A dynamic YADE obstacle (a Box, Facet or Wall that YADE moves; doc/contacts.md
// §7): the springs of the surface nodes touching it act on its mass and moment
// of inertia as on the nodes'.  A 2 g box dropped on a block with O.dt at 0.8
// of the pieces' limit was kicked to 4.9 m/s in one step (its energy x800):
// the dashpots, sized for the nodes' masses, alone gave it c dt / m = 15.
// Its mode against the nodes: omega^2 <= g K + max(w k / m), g = 1/m_o +
// (R + armOffset)^2 / I_o the largest acceleration per unit force at its
// farthest point R (a rigid body on a spring; the node's own frequency added,
// as two masses on a spring: k/m1 + k/m2), K the stiffness of the springs
// that can touch it at once (k = max(kn, kt) per unit area weight); the
// dashpots alike (their mass the node's reduced with the obstacle's).  K:
// every surface node of every piece, or, when smaller, the nodes that fit on
// the obstacle's largest face (a facet's side) grown by the contact reach and a
// node spacing, at the reference density: what presses on a body resting on
// a piece or pressed into it.  Each step checks the springs actually on it
// (ObstaclePhase::checkDynamicObstacles): one wrapped deeper into a soft
// piece, or touching several, stops the run naming the O.dt that would do.
double World::dynamicObstacleLimit(const Obstacle& o) const {
    const double inf = std::numeric_limits<double>::infinity();
    if (!o.dynamic() || pieces.empty()) return inf;
    double R = o.extentRadius();
    if (o.invInertia > 0 && !std::isfinite(R)) {  // a wall: the farthest surface node now
        R = 0;
        for (std::size_t s = 0; s < surfNodes.size(); ++s)
            R = std::max(R, (Eigen::Map<const Eigen::Vector3d>(&pos[3 * surfNodes[s]]) - o.pos).norm());
    }
    const double g = o.mobilityAt(std::isfinite(R) ? R : 0.0);
    if (!std::isfinite(g)) return 0;  // a free DOF of zero mass or inertia: any touch is infinite acceleration
    double kSum = 0, kPerArea = 0, reach = 0, wn2 = 0, nodeRate = 0, cPerK = 0;
    for (const PieceInfo& p : pieces) {
        const Material& m = materials[p.material];
        const PairConst pc = mix(materialSide(m, m.frictionWall), obstacleSide(o.young, o.friction, m.radius));
        const double k = std::max(pc.kn, pc.kt);
        kSum += k * double(p.surfEnd - p.surfBegin);  // the weights sum to the number of surface nodes
        kPerArea = std::max(kPerArea, k / p.meanSurfaceShare);
        reach = std::max(reach, m.radius + std::sqrt(p.meanSurfaceShare));
        const double w2 = k / p.minSurfaceMassPerWeight;
        wn2 = std::max(wn2, w2);
        nodeRate = std::max(nodeRate, 2 * pc.xi * std::sqrt(w2));
        // c/k of a node: 2 xi sqrt(m/(w k)), m the node's mass reduced with
        // the obstacle's 1/g (ObstaclePhase.cpp), m/w at most the largest m/w
        // and 1/(g w_min).
        const double mw = std::min(p.maxSurfaceMassPerWeight, 1 / (g * p.minSurfaceWeight));
        cPerK = std::max(cPerK, 2 * pc.xi * std::sqrt(mw / k));
    }
    double area = inf;  // what can press on it at once: its largest face (or side) grown by the reach
    if (o.kind == ObstacleKind::Box) {
        Eigen::Vector3d e = o.halfExtents;
        std::sort(e.data(), e.data() + 3);
        area = 4 * (e[1] + reach) * (e[2] + reach);
    } else if (o.kind == ObstacleKind::Facet) {
        const Eigen::Vector3d* v = o.localVerts;
        const double a = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).norm();
        const double perimeter = (v[1] - v[0]).norm() + (v[2] - v[1]).norm() + (v[0] - v[2]).norm();
        area = a + perimeter * reach + M_PI * reach * reach;
    }
    const double K = std::min(kSum, area * kPerArea);
    const double w2 = g * K + wn2;
    if (!(w2 > 0)) return inf;
    const double w = std::sqrt(w2);
    return leapfrogLimit(w, (g * K * cPerK + nodeRate) / (2 * w));
}

void World::ensureElementOmegas() const {
    if (omegaCache_.size() == pieces.size()) return;
    omegaCache_.resize(pieces.size());
    pieceRateMax_.assign(pieces.size(), 0.0);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        omegaCache_[i] = elementOmegaMax(pieces[i]);
        // omega2Tet_ is exact or an upper bound at most the piece's maximum.
        for (int32_t e = pieces[i].tetBegin; e < pieces[i].tetEnd; ++e)
            pieceRateMax_[i] = std::max(pieceRateMax_[i], tetMat(e).beta() * omega2Tet_[e]);
    }
}

double World::pieceBeta(std::size_t i) const {
    const PieceInfo& p = pieces[i];
    if (p.materialCount == 1) return tetMat(p.tetBegin).beta();
    ensureElementOmegas();
    const double w2 = omegaCache_[i] * omegaCache_[i];
    return w2 > 0 ? pieceRateMax_[i] / w2 : 0.0;
}

// What each piece's elements put on a node of the leapfrog condition, for
// the piece-contact phase's step of the contacts as they are: by Irons'
// theorem (above) the element springs on a node's lumped mass are at most
// omega_e^2 per unit mass, their Kelvin-Voigt dashpots beta omega_e^2 (the
// viscous operator is beta times the stiffness at rest; implicit: none).
// O(pieces) a step; the frequencies themselves once per piece added.
void World::refreshElementModes() {
    if (pieces.empty()) return;
    ensureElementOmegas();
    pieceElementW2_.resize(pieces.size());
    pieceElementRate_.resize(pieces.size());
    const bool explicitViscosity = settings.viscosityOn && settings.viscousIntegration != ViscousIntegration::Implicit;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const double w2 = omegaCache_[i] * omegaCache_[i];
        pieceElementW2_[i] = w2;
        pieceElementRate_[i] = explicitViscosity ? pieceBeta(i) * w2 : 0.0;
    }
}

StableDt World::stableDt() const {
    const double inf = std::numeric_limits<double>::infinity();
    StableDt r{inf, inf, inf, inf, "none", inf, inf};
    ensureElementOmegas();
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const double we = omegaCache_[i];
        const double beta = settings.viscosityOn ? pieceBeta(i) : 0.0;
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
    if (const double ds = spheres.bound[tangentialSprings() ? 1 : 0].stableStep; std::isfinite(ds)) {
        // The same springs on the sphere side, its dashpots lagged half a step
        // as every dashpot (SpherePhase::setSpheres).
        r.contact = std::min(r.contact, ds);
        r.combined = std::min(r.combined, ds);
        r.combinedExplicit = std::min(r.combinedExplicit, ds);
        r.combinedImplicit = std::min(r.combinedImplicit, ds);
    }
    for (std::size_t i = 0; i < obstacles.size(); ++i) {
        const double d = dynamicObstacleLimit(obstacles[i]);
        if (d < r.obstacle) r.obstacle = d, r.obstacleIndex = static_cast<int>(i);
    }
    if (r.obstacleIndex >= 0) {  // its springs are contact springs
        r.contact = std::min(r.contact, r.obstacle);
        r.combined = std::min(r.combined, r.obstacle);
        r.combinedExplicit = std::min(r.combinedExplicit, r.obstacle);
        r.combinedImplicit = std::min(r.combinedImplicit, r.obstacle);
    }
    // The piece whose elements set the element step (the viscous one while
    // explicit viscosity limits it): its worst elements against its median.
    const bool viscousCounts = settings.viscosityOn && !implicit;
    double pieceLimit = inf;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        const double we = omegaCache_[i];
        const double beta = settings.viscosityOn ? pieceBeta(i) : 0.0;
        const double d = viscousCounts ? leapfrogLimit(we, 0.5 * beta * we) : leapfrogLimit(we, 0.0);
        if (d < pieceLimit) pieceLimit = d, r.piece = static_cast<int>(i);
    }
    if (r.piece >= 0) {
        const PieceStepReport& pr = pieceStepReport(r.piece);
        const PieceInfo& p = pieces[r.piece];
        const double beta = settings.viscosityOn ? pieceBeta(r.piece) : 0.0;
        const double we = omegaCache_[r.piece], wm = pr.omegaMedian;
        r.pieceElastic = leapfrogLimit(we, 0.0);
        r.pieceViscous = leapfrogLimit(we, 0.5 * beta * we);
        r.medianElastic = leapfrogLimit(wm, 0.0);
        r.medianViscous = leapfrogLimit(wm, 0.5 * beta * wm);
        for (int32_t local : pr.worst) r.elements.push_back(tetId(p.tetBegin + local));
        r.elementsNearLimit = pr.nearLimit;
        r.worstQuality = pr.worstQuality;
    }
    const double lim = std::min({r.elastic, implicit ? r.elastic : r.viscous, r.contact});
    if (std::isfinite(lim)) {
        if (r.obstacleIndex >= 0 && r.obstacle <= r.combined)
            r.limitedBy = cat("the dynamic ", describeDynamic(obstacles[r.obstacleIndex]), " on the contact springs");
        else if (r.contact == lim) r.limitedBy = "contact";
        else if (!implicit && r.viscous < r.elastic) r.limitedBy = "viscosity";
        else r.limitedBy = "elasticity (P-wave)";
    }
    // The piece-piece contacts as the last step found them (ContactLoad.hpp):
    // a node pressed on a face and carrying, as a corner of its own faces,
    // the reactions of the other piece's nodes, which the estimate above
    // counts once.  (Measured in the mode of viscous integration of that step.)
    if (const ContactStepLimit& pc = phases_->pieceContact.stepLimit(); pc.node >= 0) {
        r.pieceContact = pc.limit, r.pieceContactNode = pc.node - pieces[pc.piece].nodeBegin;
        r.pieceContactPiece = pc.piece, r.pieceContactStep = pc.step;
        double& mode = implicit ? r.combinedImplicit : r.combinedExplicit;
        mode = std::min(mode, pc.limit);
        if (pc.limit < r.combined)
            r.combined = pc.limit,
            r.limitedBy = cat("the contacts on node ", r.pieceContactNode, " of piece ", pc.piece,
                              " (as they were in step ", pc.step + 1, ")");
    }
    return r;
}

void World::checkDt(double dt) const {
    const StableDt s = stableDt();
    requirePositiveFinite(dt);
    if (!(dt <= s.combined) && s.obstacleIndex >= 0 && s.obstacle <= s.combined) {
        const Obstacle& o = obstacles[s.obstacleIndex];
        throw StabilityError(cat(
            "QDEM: O.dt=", dt, " s exceeds the stable time step ", s.combined, " s by a factor ", dt / s.combined,
            " (limited by the dynamic ", describeDynamic(o), ": the contact springs of the surface nodes that can ",
            "touch it act on its mass too, and a light body on stiff springs is launched; pieces alone: elastic ",
            s.elastic, " s, with viscosity ", s.viscous, " s). Lower O.dt, ",
            o.invMass == std::numeric_limits<double>::infinity() || o.invInertia == std::numeric_limits<double>::infinity()
                ? "give the body a mass and moment of inertia (b.state.mass, b.state.inertia)"
                : "make the body heavier",
            ", or fix it (fixed=True, or b.dynamic = False)."));
    }
    if (!(dt <= s.combined))  // (a NaN limit refuses too)
        throw StabilityError(cat("QDEM: O.dt=", dt, " s exceeds the stable time step ", s.combined,
                                 " s by a factor ", dt / s.combined, " (limited by ", s.limitedBy,
                                 "; elastic limit ", s.elastic, " s, with viscosity ", s.viscous,
                                 " s, contact ", s.contact, " s",
                                 s.limitedBy == "viscosity" || s.limitedBy == "elasticity (P-wave)"
                                     ? cat("; the smallest element steps: ", describeElementLimit(s))
                                     : std::string(),
                                 "). Lower O.dt, the viscosity or the stiffness",
                                 s.limitedBy == "viscosity"
                                     ? cat(", or set QdemEngine(viscousIntegration='implicit') (limit ",
                                           s.combinedImplicit, " s).")
                                     : std::string(".")));
}

}  // namespace qdem
