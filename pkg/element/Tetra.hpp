// The QDEM element: a constant-strain tetrahedron whose four nodes are the
// particles of the quadruple.  What every material law shares: the
// deformation gradient F = Ds * B, the Kelvin-Voigt viscous stress on the
// Green-Lagrange strain rate, and the nodal forces of a first Piola stress.
// The laws themselves live in laws/ (doc/formulation.md, "Material laws").
#pragma once
#include <Eigen/Core>

namespace qdem {

// Small-strain (Hooke) constants of the material and its viscous time
// constant; every law is built from (lambda, mu) and equals Hooke's law with
// them at small strain.
struct ElementParams {
    double lambda, mu;  // Lame constants [Pa]
    double beta;        // viscous time constant eta/mu [s]; 0 = purely elastic
};

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
// dP/dF as a 9x9 matrix: row 3*i+J is P_iJ, column 3*k+L is F_kL.
using Mat9 = Eigen::Matrix<double, 9, 9>;

// Edge matrix Ds (columns p1-p0, p2-p0, p3-p0); F = Ds * B with B the
// inverse of the reference edge matrix, stored row-major.
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

// Kelvin-Voigt viscous second Piola stress S_v = beta (2 mu dE/dt + lambda
// tr(dE/dt) I) on the Green-Lagrange strain rate dE/dt = sym(F^T dF/dt):
// zero under any rigid spin (objective), whatever the elastic law.
inline Mat3 viscousStress(const Mat3& F, const Mat3& Fdot, const ElementParams& p, Mat3* Edot = nullptr) {
    const Mat3 G = F.transpose() * Fdot;
    const Mat3 Ed = 0.5 * (G + G.transpose());
    Mat3 Sv = (2 * p.beta * p.mu) * Ed;
    Sv.diagonal().array() += p.beta * p.lambda * Ed.trace();
    if (Edot) *Edot = Ed;
    return Sv;
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
