// The element kernel, generic over the material law: gather node data,
// F = Ds * B, the law's first Piola stress (and strain energy), the
// law-independent Kelvin-Voigt viscous stress, scatter nodal forces.
// elementBlock evaluates one TetBlock (kLanes tetrahedra) at once: node data
// are gathered into lane arrays (NodeGather.hpp), the arithmetic runs as one
// straight-line loop over lanes (which the compiler turns into SIMD code), the
// caller scatters the forces back.  elementBatch does the same for tets read
// straight from the world arrays.  tetStress is the scalar (Eigen) reference;
// the unit tests compare the two.
#pragma once
#include <cstdint>

#include "NodeGather.hpp"
#include "TetBlock.hpp"
#include "Tetra.hpp"

namespace qdem {

struct alignas(64) BatchOut {
    double f[4][3][kLanes];  // nodal forces per lane
    double wElastic[kLanes]; // V0 * strain energy density
    double diss[kLanes];     // V0 * viscous dissipation rate
};

// Forces for the kLanes tets of block blk (padding lanes included: the caller
// drops them).  Law: one of laws/*.hpp (its lane() is inlined: no virtual call).
//
// elementLanes is the arithmetic alone, from the edge vectors of positions
// (dx) and velocities (dv, read only when Viscous) already in lanes;
// elementBlock gathers them and calls it (inlined: one function, as compiled
// before the split).  The split lets scripts/bench/element_parts.cpp time the
// gather, the arithmetic and the scatter apart.
template <class Law, bool Viscous, bool Energy>
__attribute__((always_inline)) inline void elementLanes(const Law& law, const TetBlock& blk,
                                                        const double (&dx)[3][3][kLanes],
                                                        const double (&dv)[3][3][kLanes], const ElementParams& p,
                                                        BatchOut& out) {
    alignas(64) double aux[kLanes];
    const auto& B = blk.B;
    const auto& V0 = blk.vol;
    const double bmu = p.beta * p.mu, blam = p.beta * p.lambda;
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
        // F = Ds * B  (Ds columns are the edge vectors)
        double F[3][3], Fd[3][3];
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i)
            #pragma GCC unroll 3
            for (int j = 0; j < 3; ++j) {
                F[i][j] = dx[0][i][l] * B[0 * 3 + j][l] + dx[1][i][l] * B[1 * 3 + j][l] + dx[2][i][l] * B[2 * 3 + j][l];
                if constexpr (Viscous)
                    Fd[i][j] =
                        dv[0][i][l] * B[0 * 3 + j][l] + dv[1][i][l] * B[1 * 3 + j][l] + dv[2][i][l] * B[2 * 3 + j][l];
            }
        // The forces are H = -V0 P B^T.  The factor s = -V0 is folded into
        // the stresses' constants (a few multiplies per lane) instead of
        // scaling the nine entries of H: the laws return s P.
        const double s = -V0[l];
        // Kelvin-Voigt: S_v = beta (2 mu dE/dt + lambda tr(dE/dt) I) on the
        // Green-Lagrange strain rate dE/dt = sym(g), g = F^T dF/dt, for every
        // law, written on g itself (2 dE/dt = g + g^T, tr dE/dt = tr g) so
        // that no factor 1/2 is applied and undone; passed on as s S_v.
        double Sv[3][3] = {};  // (read by the laws only when Viscous)
        double dRate = 0;
        if constexpr (Viscous) {
            double g[3][3];
            #pragma GCC unroll 3
            for (int a = 0; a < 3; ++a)
                #pragma GCC unroll 3
                for (int b = 0; b < 3; ++b) g[a][b] = F[0][a] * Fd[0][b] + F[1][a] * Fd[1][b] + F[2][a] * Fd[2][b];
            const double cm = s * bmu, cl = s * blam * (g[0][0] + g[1][1] + g[2][2]);
            double gs[3][3];  // g + g^T = 2 dE/dt (off the diagonal)
            #pragma GCC unroll 3
            for (int a = 0; a < 3; ++a) {
                Sv[a][a] = (cm + cm) * g[a][a] + cl;
                #pragma GCC unroll 3
                for (int b = a + 1; b < 3; ++b) {
                    gs[a][b] = g[a][b] + g[b][a];
                    Sv[a][b] = Sv[b][a] = cm * gs[a][b];
                }
            }
            // V0 S_v : dE/dt = -(s S_v) : dE/dt
            if constexpr (Energy)
                dRate = -(Sv[0][0] * g[0][0] + Sv[1][1] * g[1][1] + Sv[2][2] * g[2][2] + Sv[0][1] * gs[0][1] +
                          Sv[0][2] * gs[0][2] + Sv[1][2] * gs[1][2]);
        }
        double P[3][3];  // s P
        double wEl = 0, ax = 0;
        law.template lane<Viscous, Energy>(F, Sv, s, P, wEl, ax);
        // H = s P B^T : forces on nodes 1..3 as columns
        #pragma GCC unroll 3
        for (int i = 0; i < 3; ++i) {
            double sum = 0;
            #pragma GCC unroll 3
            for (int k = 0; k < 3; ++k) {
                const double h = P[i][0] * B[k * 3 + 0][l] + P[i][1] * B[k * 3 + 1][l] + P[i][2] * B[k * 3 + 2][l];
                out.f[k + 1][i][l] = h;
                sum += h;
            }
            out.f[0][i][l] = -sum;
        }
        out.wElastic[l] = V0[l] * wEl;
        out.diss[l] = dRate;
        if constexpr (Energy && Law::kEnergyFinish) aux[l] = ax;
    }
    if constexpr (Energy && Law::kEnergyFinish)
        for (int l = 0; l < kLanes; ++l) out.wElastic[l] += V0[l] * law.energyFinish(aux[l]);
}

// X, V: node arrays of last + 1 nodes (x y z each).
template <class Law, bool Viscous, bool Energy>
__attribute__((noinline)) void elementBlock(const Law& law, const TetBlock& blk, const double* X, const double* V,
                                            int32_t last, const ElementParams& p, BatchOut& out) {
    alignas(64) double dx[3][3][kLanes], dv[3][3][kLanes];
    gatherBlockEdges<Viscous>(X, V, last, blk.node, dx, dv);
    elementLanes<Law, Viscous, Energy>(law, blk, dx, dv, p, out);
}

// Computes forces for tets e0 .. e0+count-1 (1 <= count <= kLanes) of the
// world arrays.  Lanes beyond count are padded with the last tet and must be
// ignored by the caller.
template <class Law, bool Viscous, bool Energy>
inline void elementBatch(const Law& law, int32_t e0, int count, const int32_t* conn, const double* X, const double* V,
                         const double* Bs, const double* vol, const ElementParams& p, BatchOut& out) {
    TetBlock b;
    fillTetBlock(b, e0, count, conn, Bs, vol);
    elementBlock<Law, Viscous, Energy>(law, b, X, V, -1, p, out);  // -1: sizes unknown, masked loads
}

// Stress of one element (elastic + viscous) and the pieces of it that the
// energy bookkeeping needs: the scalar reference of elementBatch.
struct TetStress {
    Mat3 F;            // deformation gradient
    Mat3 P;            // total first Piola-Kirchhoff stress
    double wElastic;   // strain energy density
    double dissRate;   // viscous dissipation density rate  S_v : dE/dt
};

template <class Law, bool Viscous, bool Energy>
inline TetStress tetStress(const Law& law, const Mat3& F, const Mat3& Fdot, const ElementParams& p) {
    TetStress r;
    r.F = F;
    r.P = law.piola(F);
    r.wElastic = Energy ? law.energy(F) : 0.0;
    r.dissRate = 0;
    if constexpr (Viscous) {
        Mat3 Ed;
        const Mat3 Sv = viscousStress(F, Fdot, p, &Ed);
        r.P += F * Sv;
        if constexpr (Energy) r.dissRate = (Sv.array() * Ed.array()).sum();
    }
    return r;
}

}  // namespace qdem
