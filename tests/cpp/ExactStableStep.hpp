// The exact largest stable step of the linearised leapfrog update of a small
// system, for the stable-step tests: the amplification matrix's spectral
// radius (dashpots lagged half a step, as every phase and YADE's
// NewtonIntegrator integrate them,
//     v' = v + dt M^-1 (-K x - C v),   x' = x + dt v'),
// bisected in dt; element stiffness and viscous matrices by central
// differences of the law's stress (not from the stable-step code).
#pragma once
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "element/ElementKernel.hpp"
#include "element/MaterialLaw.hpp"
#include "world/World.hpp"

namespace qdem::exact_step {

using MatX = Eigen::MatrixXd;
using VecX = Eigen::VectorXd;

// Spectral radius of the update of (x, v) over one step.
inline double spectralRadius(const VecX& invMass, const MatX& K, const MatX& C, double dt) {
    const auto n = K.rows();
    const MatX MK = invMass.asDiagonal() * K, MC = invMass.asDiagonal() * C;
    const MatX I = MatX::Identity(n, n);
    MatX T(2 * n, 2 * n);
    const MatX vRow = I - dt * MC;  // v' from v
    T.topLeftCorner(n, n) = I - dt * dt * MK;
    T.topRightCorner(n, n) = dt * vRow;
    T.bottomLeftCorner(n, n) = -dt * MK;
    T.bottomRightCorner(n, n) = vRow;
    // Zero modes (rigid motions of a free piece, directions without
    // stiffness) are eigenvalue 1 in Jordan blocks, whose computed values
    // scatter by sqrt(rounding) around it: they neither grow nor limit the step.
    const Eigen::VectorXcd ev = Eigen::EigenSolver<MatX>(T, false).eigenvalues();
    double r = 0;
    for (Eigen::Index i = 0; i < ev.size(); ++i)
        if (std::abs(ev[i] - 1.0) > 1e-4) r = std::max(r, std::abs(ev[i]));
    return r;
}

// Largest stable step: bisection between a stable and an unstable step
// found from the hint by halving and doubling (the stable steps of the
// leapfrog update are an interval from 0).
inline double exactStableStep(const VecX& invMass, const MatX& K, const MatX& C, double hint) {
    const auto stable = [&](double dt) { return spectralRadius(invMass, K, C, dt) <= 1 + 1e-6; };
    double lo = hint, hi = hint;
    while (!stable(lo)) lo *= 0.5;
    if (lo < hint) hi = 2 * lo;
    for (int k = 0; stable(hi); ++k) {
        if (k == 60) return std::numeric_limits<double>::infinity();  // nothing limits it
        hi *= 2;
    }
    for (int k = 0; k < 30; ++k) {
        const double mid = 0.5 * (lo + hi);
        (stable(mid) ? lo : hi) = mid;
    }
    return lo;
}

// K's positive part; eigenvalues within the differences' rounding of zero
// (1e-8 of the largest) are zero.
inline MatX positivePart(const MatX& K) {
    Eigen::SelfAdjointEigenSolver<MatX> es(0.5 * (K + K.transpose()));
    VecX l = es.eigenvalues();
    const double floor = 1e-8 * l.cwiseAbs().maxCoeff();
    for (Eigen::Index i = 0; i < l.size(); ++i) l[i] = l[i] > floor ? l[i] : 0.0;
    return es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
}

// Nodal forces of one element (12) at node positions x (12), node velocities
// v (12), from the law's first Piola stress and the Kelvin-Voigt stress.
template <class Law>
inline Eigen::Matrix<double, 12, 1> elementForce(const Law& law, const Mat3& B, double V0, const ElementParams& prm,
                                          const Eigen::Matrix<double, 12, 1>& x, const Eigen::Matrix<double, 12, 1>& v,
                                          bool elastic) {
    const Mat3 F = edgeMatrix(&x[0], &x[3], &x[6], &x[9]) * B;
    const Mat3 Fdot = edgeMatrix(&v[0], &v[3], &v[6], &v[9]) * B;
    const Mat3 P = elastic ? law.piola(F) : Mat3(F * viscousStress(F, Fdot, prm));
    double f[4][3];
    nodalForces(P, B, V0, f);
    Eigen::Matrix<double, 12, 1> r;
    for (int a = 0; a < 4; ++a)
        for (int i = 0; i < 3; ++i) r[3 * a + i] = f[a][i];
    return r;
}

// Element stiffness -df/dx by central differences of the elastic forces, and
// the viscous matrix -df/dv (the viscous force is linear in v: one column per
// unit velocity).
template <class Law>
inline void elementMatrices(const Law& law, const Mat3& B, double V0, const ElementParams& prm,
                     const Eigen::Matrix<double, 12, 1>& x, double scale, MatX& K, MatX& C) {
    K.setZero(12, 12);
    C.setZero(12, 12);
    const Eigen::Matrix<double, 12, 1> zero = Eigen::Matrix<double, 12, 1>::Zero();
    const double h = 1e-6 * scale;
    for (int j = 0; j < 12; ++j) {
        Eigen::Matrix<double, 12, 1> xp = x, xm = x, u = zero;
        xp[j] += h, xm[j] -= h, u[j] = 1;
        K.col(j) = -(elementForce(law, B, V0, prm, xp, zero, true) - elementForce(law, B, V0, prm, xm, zero, true)) /
                   (2 * h);
        if (prm.beta > 0) C.col(j) = -elementForce(law, B, V0, prm, x, u, false);
    }
    K = 0.5 * (K + K.transpose());
    C = 0.5 * (C + C.transpose());
}

// Assembled elastic stiffness and viscous matrix of every element of world w
// on its current shape (3 DOF per node).
inline void assembleElements(const World& w, MatX& K, MatX& C) {
    const auto n = static_cast<Eigen::Index>(3 * w.nNodes());
    K.setZero(n, n);
    C.setZero(n, n);
    for (std::size_t e = 0; e < w.nTets(); ++e) {
        const Material& m = w.materials[w.pieces[w.tetPiece[e]].material];
        const ElementParams prm{m.lambda(), m.mu(), m.beta()};
        const int32_t* c = &w.tetNodes[4 * e];
        Eigen::Matrix<double, 12, 1> x;
        for (int a = 0; a < 4; ++a)
            for (int i = 0; i < 3; ++i) x[3 * a + i] = w.pos[3 * c[a] + i];
        MatX Ke, Ce;
        withLaw(m, [&](const auto& law) {
            elementMatrices(law, loadRowMajor(&w.tetB[9 * e]), w.tetVol0[e], prm, x, std::cbrt(w.tetVol0[e]), Ke, Ce);
        });
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                K.block<3, 3>(3 * c[a], 3 * c[b]) += Ke.block<3, 3>(3 * a, 3 * b);
                C.block<3, 3>(3 * c[a], 3 * c[b]) += Ce.block<3, 3>(3 * a, 3 * b);
            }
    }
}

// Adds k g g' to K for a constraint row g.
inline void addSpring(MatX& K, const VecX& g, double k) { K += k * g * g.transpose(); }

// A fixed floor under the scene: a one-sided wall facing +z at height z.
inline void addFloor(World& w, double z) {
    Obstacle floor;
    floor.kind = ObstacleKind::Wall;
    floor.axis = 2;
    floor.sense = 1;
    floor.pos = Eigen::Vector3d(0, 0, z);
    floor.updateDerived();
    w.setObstacles({floor});
}

}  // namespace qdem::exact_step
