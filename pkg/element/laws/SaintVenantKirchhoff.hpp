// Saint-Venant-Kirchhoff: S = lambda tr(E) I + 2 mu E on the Green-Lagrange
// strain E = (F^T F - I)/2, P = F S.  Objective and exact Hooke at small
// strain, but its compression response peaks at stretch 1/sqrt(3) (uniaxial
// strain) and falls to zero at the mirror state F = diag(-1, 1, 1): an
// element pushed past the peak snaps through and stays inverted
// (doc/formulation.md, "Material laws").  Kept by name:
// QdemMat(law='saintVenantKirchhoff').
#pragma once
#include <algorithm>
#include <cmath>

#include "../../material/Material.hpp"
#include "../Tetra.hpp"

namespace qdem {

struct SaintVenantKirchhoff {
    static constexpr MaterialLaw kTag = MaterialLaw::SaintVenantKirchhoff;
    static constexpr bool kRecoversFromInversion = false;
    static constexpr bool kEnergyFinish = false;  // no per-lane scalar energy term

    double lam, mu, mu2, halfLam, restOffset;
    SaintVenantKirchhoff(double lambda, double mu_)
        : lam(lambda), mu(mu_), mu2(2 * mu_), halfLam(0.5 * lambda), restOffset(-(1.5 * lambda + mu_)) {}

    // One SIMD lane: sP = F (s S_e + sS_v) with the viscous stress sS_v
    // (already scaled by s) added before the push-forward.  S_e is written
    // on C = F^T F, not on E = (C - I)/2:
    //     S_e = mu (C - I) + lambda/2 (tr C - 3) I,
    // so the diagonal is mu C_aa + q with q = lambda/2 tr C - (3 lambda/2 + mu)
    // (the subtraction of the rest state, a cancellation like C_aa - 1 in E,
    // with a rounding error of the same size: a few ulps of lambda + mu), and
    // the scale s rides on the three constants mu, lambda/2 and that offset.
    // w: strain energy density (unscaled); aux unused.
    template <bool Viscous, bool Energy>
    inline void lane(const double (&F)[3][3], const double (&sSv)[3][3], double s, double (&P)[3][3], double& w,
                     double& /*aux*/) const {
        double C[3][3];
        #pragma GCC unroll 3
        for (int a = 0; a < 3; ++a)
            #pragma GCC unroll 3
            for (int b = a; b < 3; ++b) {
                C[a][b] = F[0][a] * F[0][b] + F[1][a] * F[1][b] + F[2][a] * F[2][b];
                C[b][a] = C[a][b];
            }
        const double trC = C[0][0] + C[1][1] + C[2][2];
        const double sMu = s * mu, q = (s * halfLam) * trC + s * restOffset;
        double S[3][3];  // s (S_e + S_v)
        #pragma GCC unroll 3
        for (int a = 0; a < 3; ++a)
            #pragma GCC unroll 3
            for (int b = a; b < 3; ++b) {
                S[a][b] = sMu * C[a][b] + (a == b ? q : 0.0);
                if constexpr (Viscous) S[a][b] += sSv[a][b];
                S[b][a] = S[a][b];
            }
        if constexpr (Energy) {
            double E[3][3];
            #pragma GCC unroll 3
            for (int a = 0; a < 3; ++a)
                #pragma GCC unroll 3
                for (int b = 0; b < 3; ++b) E[a][b] = 0.5 * (C[a][b] - (a == b ? 1.0 : 0.0));
            const double trE = E[0][0] + E[1][1] + E[2][2];
            double ee = 0;
            #pragma GCC unroll 3
            for (int a = 0; a < 3; ++a)
                #pragma GCC unroll 3
                for (int b = 0; b < 3; ++b) ee += E[a][b] * E[a][b];
            w = 0.5 * lam * trE * trE + 0.5 * mu2 * ee;
        }
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) P[i][j] = F[i][0] * S[0][j] + F[i][1] * S[1][j] + F[i][2] * S[2][j];
    }
    double energyFinish(double /*aux*/) const { return 0.0; }

    // ---- reference (Eigen) forms: output, stable step, tests --------------
    // Lame constants of tangent(I) (Hooke's law at small strain).
    void lameAtRest(double& lambda, double& mu_) const { lambda = lam, mu_ = mu; }
    Mat3 secondPiola(const Mat3& F) const {
        const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
        Mat3 S = 2 * mu * E;
        S.diagonal().array() += lam * E.trace();
        return S;
    }
    Mat3 piola(const Mat3& F) const { return F * secondPiola(F); }
    double energy(const Mat3& F) const {
        const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
        const double trE = E.trace();
        return 0.5 * lam * trE * trE + mu * E.squaredNorm();
    }
    // dP_iJ/dF_kL = delta_ik S_JL + lambda F_iJ F_kL + mu (F_iM F_kM delta_JL + F_iL F_kJ)
    Mat9 tangent(const Mat3& F) const {
        const Mat3 S = secondPiola(F), FFt = F * F.transpose();
        Mat9 A;
        for (int i = 0; i < 3; ++i)
            for (int J = 0; J < 3; ++J)
                for (int k = 0; k < 3; ++k)
                    for (int L = 0; L < 3; ++L)
                        A(3 * i + J, 3 * k + L) = (i == k ? S(J, L) : 0.0) + lam * F(i, J) * F(k, L) +
                                                  mu * ((J == L ? FFt(i, k) : 0.0) + F(i, L) * F(k, J));
        return A;
    }
    // An upper bound of ||A(F) - A(I)||_2 (StableNeoHookean.hpp says what it
    // is for).  With D0[Y] = lambda tr(Y) I + 2 mu sym(Y), ||D0|| = max(|3
    // lambda + 2 mu|, 2 mu), the tangent is A(F)[X] = X S + F D0[F'X], so
    //   A(F)[X] - A(I)[X] = X S + (F - I) D0[F'X] + D0[(F - I)' X]
    // and ||A(F) - A(I)|| <= |S| + ||D0|| |F - I| (s1 + 1), s1 = ||F||_2.
    double tangentChangeBound(const Mat3& F, double s1) const {
        const double d0 = std::max(std::fabs(3 * lam + 2 * mu), 2 * mu);
        return secondPiola(F).norm() + d0 * (F - Mat3::Identity()).norm() * (s1 + 1.0);
    }
};

}  // namespace qdem
