// The viscous operator C(x) of the Kelvin-Voigt stress on the current shape:
// the nodal viscous forces of a velocity field v are -C(x) v.  For the
// implicit viscous update (pkg/phases/ViscousSolve.cpp) C is applied to
// search directions, so it is evaluated with the element kernel itself
// (elementBatch, ElementKernel.hpp) and a "law" with no elastic stress: the
// same F, the same S_v(F^T dF/dt), the same H = -V0 F S_v B^T as the explicit
// viscous force, hence the same C, symmetric positive semi-definite
// (v^T C v = V0 S_v : dE/dt >= 0), zero on rigid motions, and its forces sum
// to zero per element.
#pragma once
#include <cmath>

#include "Tetra.hpp"

namespace qdem {

// elementBatch's law interface with zero elastic stress: sP = F (sS_v).
struct ViscousStressOnly {
    static constexpr bool kEnergyFinish = false;
    template <bool Viscous, bool Energy>
    inline void lane(const double (&F)[3][3], const double (&Sv)[3][3], double /*s*/, double (&P)[3][3],
                     double& /*w*/, double& /*aux*/) const {
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) P[i][j] = F[i][0] * Sv[0][j] + F[i][1] * Sv[1][j] + F[i][2] * Sv[2][j];
    }
    double energyFinish(double /*aux*/) const { return 0.0; }
};

// The gradients of the four nodes' shape functions, from the element's
// inverse reference edge matrix B (rows: nodes 1-3; node 0's closes the sum).
inline void shapeGradients(const Mat3& B, Vec3 g[4]) {
    g[1] = B.row(0).transpose();
    g[2] = B.row(1).transpose();
    g[3] = B.row(2).transpose();
    g[0] = -(g[1] + g[2] + g[3]);
}

// Diagonal of one element's C on its 12 DOFs (d[a][i]: node a, direction i).
// Velocity e_i at node a alone gives F^T dF/dt = phi g_a^T with phi = F^T e_i
// (row i of F) and g_a the gradient of node a's shape function, so
// dE/dt = sym(phi g_a^T), tr = phi.g_a, dE/dt:dE/dt = (|phi|^2 |g_a|^2 + (phi.g_a)^2)/2 and
//     C_(ai)(ai) = V0 beta (lambda (phi.g_a)^2 + mu (|phi|^2 |g_a|^2 + (phi.g_a)^2)).
inline void viscousDiagonal(const Mat3& F, const Mat3& B, double V0, const ElementParams& p, double d[4][3]) {
    Vec3 g[4];
    shapeGradients(B, g);
    const double bl = V0 * p.beta * p.lambda, bm = V0 * p.beta * p.mu;
    for (int i = 0; i < 3; ++i) {
        const Vec3 phi = F.row(i).transpose();
        const double pp = phi.squaredNorm();
        for (int a = 0; a < 4; ++a) {
            const double pg = phi.dot(g[a]);
            d[a][i] = bl * pg * pg + bm * (pp * g[a].squaredNorm() + pg * pg);
        }
    }
}

// One element's C on its 12 DOFs in the reference shape (F = I), the
// matrix the co-rotated preconditioner factors (CorotatedCholesky.hpp):
// K[3a+i][3b+j] = V0 beta (lambda g_a,i g_b,j + mu (delta_ij g_a.g_b + g_b,i g_a,j)).
// From v^T C v = V0 beta (lambda tr(dE/dt)^2 + 2 mu dE/dt:dE/dt) with
// dE/dt = sym(sum_(a,i) v_ai phi_i g_a^T): the general entry is
//     C_(ai)(bj) = V0 beta (lambda (phi_i.g_a)(phi_j.g_b)
//                  + mu ((phi_i.phi_j)(g_a.g_b) + (phi_i.g_b)(phi_j.g_a))),
// whose diagonal is viscousDiagonal's; F = I makes phi_i = e_i.  For F = R
// (the shape rotated rigidly) phi_i = R^T e_i and C = R K R^T node-blockwise.
inline void viscousReferenceMatrix(const Mat3& B, double V0, const ElementParams& p, double K[12][12]) {
    Vec3 g[4];
    shapeGradients(B, g);
    const double bl = V0 * p.beta * p.lambda, bm = V0 * p.beta * p.mu;
    for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
            const double gg = g[a].dot(g[b]);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    K[3 * a + i][3 * b + j] =
                        bl * g[a][i] * g[b][j] + bm * ((i == j ? gg : 0.0) + g[b][i] * g[a][j]);
        }
}

}  // namespace qdem
