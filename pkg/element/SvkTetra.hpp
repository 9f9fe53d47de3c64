// The QDEM element: a constant-strain tetrahedron whose four nodes are the
// particles of the quadruple.  Green-Lagrange strain with a Saint-Venant-
// Kirchhoff (Lame) stress makes the element objective: a rigid rotation of
// any size gives exactly zero strain, hence zero stress.  Kelvin-Voigt
// viscosity adds a stress proportional to the Green-Lagrange strain *rate*,
// also objective.  Derivation: doc/formulation.md.
#pragma once
#include <Eigen/Core>

namespace qdem {

struct ElementParams {
    double lambda, mu;  // Lame constants [Pa]
    double beta;        // viscous time constant eta/mu [s]; 0 = purely elastic
};

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

// Deformation gradient F = Ds * B and its rate from node positions/velocities.
// B is the inverse of the reference edge matrix, stored row-major.
inline Mat3 edgeMatrix(const double* p0, const double* p1, const double* p2, const double* p3) {
    Mat3 D;
    for (int i = 0; i < 3; ++i) {
        D(i, 0) = p1[i] - p0[i];
        D(i, 1) = p2[i] - p0[i];
        D(i, 2) = p3[i] - p0[i];
    }
    return D;
}

inline Mat3 loadRowMajor(const double* B) {
    Mat3 M;
    M << B[0], B[1], B[2], B[3], B[4], B[5], B[6], B[7], B[8];
    return M;
}

// Second Piola-Kirchhoff stress S (elastic + viscous) and the pieces of it
// that the energy bookkeeping needs.
struct TetStress {
    Mat3 F;        // deformation gradient
    Mat3 S;        // total second Piola-Kirchhoff stress
    double wElastic;   // strain energy density
    double dissRate;   // viscous dissipation density rate  S_v : dE/dt
};

template <bool Viscous, bool Energy>
inline TetStress svkStress(const Mat3& F, const Mat3& Fdot, const ElementParams& p) {
    TetStress r;
    r.F = F;
    Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double trE = E.trace();
    r.S = 2 * p.mu * E;
    r.S.diagonal().array() += p.lambda * trE;
    r.wElastic = 0;
    r.dissRate = 0;
    if constexpr (Energy) r.wElastic = 0.5 * p.lambda * trE * trE + p.mu * E.squaredNorm();
    if constexpr (Viscous) {
        const Mat3 G = F.transpose() * Fdot;
        const Mat3 Ed = 0.5 * (G + G.transpose());
        Mat3 Sv = (2 * p.beta * p.mu) * Ed;
        Sv.diagonal().array() += p.beta * p.lambda * Ed.trace();
        r.S += Sv;
        if constexpr (Energy) r.dissRate = (Sv.array() * Ed.array()).sum();
    }
    return r;
}

// Nodal forces of one element: H = -V0 * P * B^T gives the forces on nodes
// 1..3 as columns; node 0 takes minus their sum (the element is in balance).
inline void nodalForces(const Mat3& P, const Mat3& B, double V0, double f[4][3]) {
    const Mat3 H = -V0 * P * B.transpose();
    for (int i = 0; i < 3; ++i) {
        f[1][i] = H(i, 0);
        f[2][i] = H(i, 1);
        f[3][i] = H(i, 2);
        f[0][i] = -(H(i, 0) + H(i, 1) + H(i, 2));
    }
}

}  // namespace qdem
