// Stable Neo-Hookean (Smith, de Goes, Kim, "Stable Neo-Hookean Flesh
// Simulation", ACM TOG 37(2), 2018, eq. 14 with the rest-stability term):
//
//   Psi = mu'/2 (I_C - 3) + lambda'/2 (J - alpha)^2 - mu'/2 log(I_C + 1)
//   P   = mu' (1 - 1/(I_C + 1)) F + lambda' (J - alpha) cof(F)
//
// with I_C = |F|^2, J = det F, cof(F) = dJ/dF.  alpha = 1 + 3 mu'/(4 lambda')
// makes F = I stress-free; mu' = 4/3 mu, lambda' = lambda + 5/6 mu make the
// small-strain tangent exactly Hooke's (lambda, mu) (derivation:
// doc/formulation.md, "Material laws").  Psi is finite and P restoring for
// every F, J <= 0 included: an inverted element is pushed back.  The default
// law: QdemMat(law='stableNeoHookean').
#pragma once
#include <cmath>

#include "../../material/Material.hpp"
#include "../Tetra.hpp"

namespace qdem {

struct StableNeoHookean {
    static constexpr MaterialLaw kTag = MaterialLaw::StableNeoHookean;
    static constexpr bool kRecoversFromInversion = true;
    // The log term of the energy is added after the SIMD loop (GCC does not
    // vectorise log1p without -ffast-math).
    static constexpr bool kEnergyFinish = true;

    double muS, lamS, alpha;  // mu', lambda', alpha
    // lambda' = lambda + 5/6 mu > 0 for every Poisson ratio in (-1, 0.5)
    // (lambda/mu = 2 nu/(1 - 2 nu) > -2/3), so alpha stays finite; nu -> 0.5
    // gives alpha -> 1.
    StableNeoHookean(double lambda, double mu)
        : muS(4.0 / 3.0 * mu), lamS(lambda + 5.0 / 6.0 * mu), alpha(1.0 + 0.75 * muS / lamS) {}

    // One SIMD lane: sP = s P_e(F) + F (sS_v), the scale s on the two
    // coefficients of P_e and already in sS_v.  w: the
    // energy density W(F) - W(I) without its log term (unscaled), aux: what
    // the log term needs (energyFinish).
    template <bool Viscous, bool Energy>
    inline void lane(const double (&F)[3][3], const double (&sSv)[3][3], double s, double (&P)[3][3], double& w,
                     double& aux) const {
        double G[3][3];  // cofactor of F = dJ/dF
        G[0][0] = F[1][1] * F[2][2] - F[1][2] * F[2][1];
        G[0][1] = F[1][2] * F[2][0] - F[1][0] * F[2][2];
        G[0][2] = F[1][0] * F[2][1] - F[1][1] * F[2][0];
        G[1][0] = F[0][2] * F[2][1] - F[0][1] * F[2][2];
        G[1][1] = F[0][0] * F[2][2] - F[0][2] * F[2][0];
        G[1][2] = F[0][1] * F[2][0] - F[0][0] * F[2][1];
        G[2][0] = F[0][1] * F[1][2] - F[0][2] * F[1][1];
        G[2][1] = F[0][2] * F[1][0] - F[0][0] * F[1][2];
        G[2][2] = F[0][0] * F[1][1] - F[0][1] * F[1][0];
        const double J = F[0][0] * G[0][0] + F[0][1] * G[0][1] + F[0][2] * G[0][2];
        double Ic = 0;
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) Ic += F[i][j] * F[i][j];
        const double a = s * (muS * (1.0 - 1.0 / (Ic + 1.0)));
        const double t = s * (lamS * (J - alpha));
        // (Viscous: F sS_v first, a and t last: they wait for the division
        // and the determinant, the push-forward does not.  Merging a into
        // sS_v, F (s a I + sS_v), saves 6 operations but put all 27 of the
        // push-forward behind the division: measured slower.)
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) {
                if constexpr (Viscous)
                    P[i][j] = F[i][0] * sSv[0][j] + F[i][1] * sSv[1][j] + F[i][2] * sSv[2][j] + a * F[i][j] +
                              t * G[i][j];
                else
                    P[i][j] = a * F[i][j] + t * G[i][j];
            }
        if constexpr (Energy) {
            double h[3][3];  // F - I: exact near rest (Sterbenz)
            #pragma GCC unroll 3
            for (int i = 0; i < 3; ++i)
                #pragma GCC unroll 3
                for (int j = 0; j < 3; ++j) h[i][j] = F[i][j] - (i == j ? 1.0 : 0.0);
            w = energyNoLog(h, aux);
        }
    }
    // W(F) - W(I) without its log term, from H = F - I, written so that no
    // first-order terms cancel (the energy of a strain eps is accurate to
    // rounding relative to mu eps^2, not to mu times rounding):
    //   I_C - 3 = 2 tr H + |H|^2,  J - 1 = tr H + I_2(H) + det H,
    //   W = 3mu'/8 |H|^2 - 3mu'/4 (I_2(H) + det H) + lambda'/2 (J - 1)^2
    //       - mu'/2 (log1p(y) - y),   y = (I_C - 3)/4,
    // using 3mu'/4 = lambda'(alpha - 1) to cancel the linear terms exactly.
    // aux = y for energyFinish.
    inline double energyNoLog(const double (&h)[3][3], double& aux) const {
        const double trH = h[0][0] + h[1][1] + h[2][2];
        double hh = 0, hht = 0;
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) {
                hh += h[i][j] * h[i][j];
                hht += h[i][j] * h[j][i];
            }
        const double I2 = 0.5 * (trH * trH - hht);
        const double detH = h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1]) -
                            h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0]) +
                            h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
        const double Jm1 = trH + I2 + detH;
        aux = 0.25 * (2.0 * trH + hh);
        return 0.375 * muS * hh - 0.75 * muS * (I2 + detH) + 0.5 * lamS * Jm1 * Jm1;
    }
    double energyFinish(double y) const { return -0.5 * muS * (std::log1p(y) - y); }

    // ---- reference (Eigen) forms: output, stable step, tests --------------
    // Lame constants of tangent(I) (Hooke's law at small strain).
    void lameAtRest(double& lambda, double& mu_) const { mu_ = 0.75 * muS, lambda = lamS - 0.625 * muS; }
    static Mat3 cofactor(const Mat3& F) {
        Mat3 G;
        G.col(0) = F.col(1).cross(F.col(2));
        G.col(1) = F.col(2).cross(F.col(0));
        G.col(2) = F.col(0).cross(F.col(1));
        return G;
    }
    Mat3 piola(const Mat3& F) const {
        const double Ic = F.squaredNorm();
        return muS * (1.0 - 1.0 / (Ic + 1.0)) * F + lamS * (F.determinant() - alpha) * cofactor(F);
    }
    double energy(const Mat3& F) const {
        double h[3][3], y;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) h[i][j] = F(i, j) - (i == j ? 1.0 : 0.0);
        const double w = energyNoLog(h, y);
        return w + energyFinish(y);
    }
    // dP/dF = mu'(1 - 1/(I_C+1)) I + 2 mu'/(I_C+1)^2 F (x) F
    //       + lambda' cof(F) (x) cof(F) + lambda' (J - alpha) d cof(F)/dF,
    // with d cof(F)_iJ / dF_kL = e_ikm e_JLn F_mn (the Hessian of J; the
    // paper's eq. 29 writes it with cross-product matrices of F's columns).
    Mat9 tangent(const Mat3& F) const {
        const double Ic = F.squaredNorm(), J = F.determinant();
        const Mat3 G = cofactor(F);
        const double a = muS * (1.0 - 1.0 / (Ic + 1.0)), b = 2.0 * muS / ((Ic + 1.0) * (Ic + 1.0));
        const double t = lamS * (J - alpha);
        auto eps = [](int i, int j, int k) { return 0.5 * (i - j) * (j - k) * (k - i); };
        Mat9 A;
        for (int i = 0; i < 3; ++i)
            for (int I = 0; I < 3; ++I)
                for (int k = 0; k < 3; ++k)
                    for (int L = 0; L < 3; ++L) {
                        double h = 0;
                        for (int m = 0; m < 3; ++m)
                            for (int n = 0; n < 3; ++n) h += eps(i, k, m) * eps(I, L, n) * F(m, n);
                        A(3 * i + I, 3 * k + L) = (i == k && I == L ? a : 0.0) + b * F(i, I) * F(k, L) +
                                                  lamS * G(i, I) * G(k, L) + t * h;
                    }
        return A;
    }
    // An upper bound of ||A(F) - A(I)||_2, the spectral norm of the change of
    // the tangent dP/dF (9x9) from the reference shape: with it the element's
    // highest frequency on its current shape is bounded by Weyl's inequality,
    // omega^2(F) <= omega^2(I) + 4/rho ||A(F) - A(I)|| sigma_max(G)^2
    // (StableDt.cpp).  Term by term, with H = F - I, f = vec F, c = vec cof F
    // and the Hessian of J (linear in F, ||Hess J(X)|| <= s1(X) + s2(X) <=
    // sqrt2 |X|: doc/formulation.md, "Stable time step on a strained shape"):
    //   (a - a0) I + b (f f' - i i') + (b - b0) i i' + lambda' (c c' - i i')
    //   + t HessJ(H) + (t - t0) HessJ(I),   ||x x' - y y'|| <= |x - y| |x + y|.
    // (s1 = ||F||_2, unused here.)  Exact at F = I (zero); a filter only: the element's exact stiffness
    // decides when the bound does not clear the step.
    double tangentChangeBound(const Mat3& F, double /*s1*/) const {
        const double Ic = F.squaredNorm(), J = F.determinant();
        const Mat3 I = Mat3::Identity(), G = cofactor(F);
        const double a = muS * (1.0 - 1.0 / (Ic + 1.0)), a0 = 0.75 * muS;
        const double b = 2.0 * muS / ((Ic + 1.0) * (Ic + 1.0)), b0 = 0.125 * muS;
        const double t = lamS * (J - alpha), t0 = lamS * (1.0 - alpha);
        const double h = (F - I).norm();
        return std::fabs(a - a0) + b * h * (F + I).norm() + 3.0 * std::fabs(b - b0) +
               lamS * (G - I).norm() * (G + I).norm() + std::sqrt(2.0) * std::fabs(t) * h + 2.0 * std::fabs(t - t0);
    }
};

}  // namespace qdem
