// Moving node data between the node arrays (x y z per node) and the element
// kernel's lanes (one tet per lane), for a block of kLanes tets.
//
// Why by hand: node data are stored x y z per node, the kernel wants each
// component across lanes.  Element by element that is 3 scalar loads and a
// scalar store per component, corner and lane (24 + 24 per tet for positions
// and velocities), and the stores bound the element phase (measured: the
// gather was ~60 % of it).  Here each node is one vector load of x y z (the
// fourth slot masked off, so a node at the end of the array reads nothing
// past it), and four nodes are transposed in registers into x, y and z
// across four lanes.  The forces go back the same way, transposed into
// (fx fy fz 0) rows that are added to force buffers padded to 4 doubles per
// node: one aligned vector read-modify-write per corner, which the CPU
// forwards from store to load when two lanes share a node (a 3-double stride
// would overlap the neighbour node and defeat that forwarding: measured
// slower than scalar adds).  Additions happen in the same order as the scalar
// code (lane by lane, corners in order), so results are bit-identical to it.
#pragma once
#include <cstdint>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "TetBlock.hpp"

namespace qdem {

// Force buffers hold this many doubles per node (x y z and a zero pad).
constexpr int kForceStride = 4;

#if defined(__AVX__)
namespace simd {

// x y z of the node at p.  Plain: a 4-wide load that also reads the next
// node's x (dropped), for nodes that are not the last of their array.
template <bool Plain>
inline __m256d loadXyz(const double* p) {
#if defined(__AVX512VL__)
    return _mm256_maskz_loadu_pd(0x7, p);
#else
    if constexpr (Plain) return _mm256_loadu_pd(p);
    return _mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1));
#endif
}

// Rows (x y z .) of four nodes -> columns x, y, z across the four.
inline void rowsToColumns(__m256d r0, __m256d r1, __m256d r2, __m256d r3, __m256d& x, __m256d& y, __m256d& z) {
    const __m256d t0 = _mm256_unpacklo_pd(r0, r1);  // x0 x1 z0 z1
    const __m256d t1 = _mm256_unpackhi_pd(r0, r1);  // y0 y1 .  .
    const __m256d t2 = _mm256_unpacklo_pd(r2, r3);  // x2 x3 z2 z3
    const __m256d t3 = _mm256_unpackhi_pd(r2, r3);  // y2 y3 .  .
    x = _mm256_permute2f128_pd(t0, t2, 0x20);
    y = _mm256_permute2f128_pd(t1, t3, 0x20);
    z = _mm256_permute2f128_pd(t0, t2, 0x31);
}

// Columns x, y, z across four lanes -> rows (x y z 0) of the four.
inline void columnsToRows(__m256d x, __m256d y, __m256d z, __m256d (&r)[4]) {
    const __m256d zero = _mm256_setzero_pd();
    const __m256d t0 = _mm256_unpacklo_pd(x, y);     // x0 y0 x2 y2
    const __m256d t1 = _mm256_unpackhi_pd(x, y);     // x1 y1 x3 y3
    const __m256d t2 = _mm256_unpacklo_pd(z, zero);  // z0 0 z2 0
    const __m256d t3 = _mm256_unpackhi_pd(z, zero);  // z1 0 z3 0
    r[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
    r[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
    r[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
    r[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// Corner k of lanes 4h .. 4h+3 as x, y, z columns.
template <bool Plain>
inline void cornerColumns(const double* A, const int32_t (&node)[4][kLanes], int k, int h, __m256d& x, __m256d& y,
                          __m256d& z) {
    const int32_t* n = node[k] + 4 * h;
    rowsToColumns(loadXyz<Plain>(A + 3 * n[0]), loadXyz<Plain>(A + 3 * n[1]), loadXyz<Plain>(A + 3 * n[2]),
                  loadXyz<Plain>(A + 3 * n[3]), x, y, z);
}

#if defined(__AVX512F__)
// (lo, hi) as one 8-wide register.  (Not _mm512_insertf64x4: GCC 12's
// version reads an undefined register and warns under -Wall.)
inline __m512d join(__m256d lo, __m256d hi) {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    return _mm512_insertf64x4(_mm512_castpd256_pd512(lo), hi, 1);
#pragma GCC diagnostic pop
}
#endif

}  // namespace simd
#endif

// Whether the gather of a block may read each node with a plain 4-wide load
// (no corner is the array's last node, `last`).  Only AVX2 builds use it:
// there the masked load that keeps the last node from reading past the
// array is a slower instruction (the element pass took 0.88-0.96 of its
// time with plain loads, doc/dev/performance_notebook.md); AVX-512's masked load costs
// what a plain one does.  last < 0: the array's size is not known (no).
inline bool plainGatherSafe(const int32_t (&node)[4][kLanes], int32_t last) {
    if (last < 0) return false;
#if defined(__AVX2__) && !defined(__AVX512VL__)
    static_assert(kLanes == 8, "one 8 x int32 register per corner");
    const __m256i l = _mm256_set1_epi32(last);
    __m256i hit = _mm256_cmpeq_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(node[0])), l);
    for (int k = 1; k < 4; ++k)
        hit = _mm256_or_si256(hit, _mm256_cmpeq_epi32(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(node[k])), l));
    return _mm256_testz_si256(hit, hit);
#else
    bool hit = false;
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < kLanes; ++l) hit |= node[k][l] == last;
    return !hit;
#endif
}

// d[k][i][l] = A[node[k+1][l]][i] - A[node[0][l]][i]: the edge vectors (of
// positions or velocities) of every lane's tet, k = 0..2, component i.
// Plain: no node is the last of A (plainGatherSafe), so each may be read
// with a plain 4-wide load.
template <bool Plain = false>
inline void gatherEdges(const double* A, const int32_t (&node)[4][kLanes], double (&d)[3][3][kLanes]) {
#if defined(__AVX__)
    static_assert(kLanes == 8, "the transposes below take lanes in two groups of four");
#if defined(__AVX512F__)
    // Both halves joined into one 8-lane register before the store: the
    // kernel reads each row with one 8-wide load, which a store of two
    // 4-wide halves could not forward.
    __m256d c0[2][3], ck[2][3];
    for (int h = 0; h < 2; ++h) simd::cornerColumns<Plain>(A, node, 0, h, c0[h][0], c0[h][1], c0[h][2]);
    for (int k = 1; k < 4; ++k) {
        for (int h = 0; h < 2; ++h) simd::cornerColumns<Plain>(A, node, k, h, ck[h][0], ck[h][1], ck[h][2]);
        for (int i = 0; i < 3; ++i) {
            _mm512_store_pd(d[k - 1][i], _mm512_sub_pd(simd::join(ck[0][i], ck[1][i]), simd::join(c0[0][i], c0[1][i])));
        }
    }
#else
    for (int h = 0; h < 2; ++h) {
        __m256d x0, y0, z0;
        simd::cornerColumns<Plain>(A, node, 0, h, x0, y0, z0);
        for (int k = 1; k < 4; ++k) {
            __m256d x, y, z;
            simd::cornerColumns<Plain>(A, node, k, h, x, y, z);
            _mm256_store_pd(d[k - 1][0] + 4 * h, _mm256_sub_pd(x, x0));
            _mm256_store_pd(d[k - 1][1] + 4 * h, _mm256_sub_pd(y, y0));
            _mm256_store_pd(d[k - 1][2] + 4 * h, _mm256_sub_pd(z, z0));
        }
    }
#endif
#else
    for (int l = 0; l < kLanes; ++l) {
        const double* a0 = A + 3 * node[0][l];
        for (int k = 0; k < 3; ++k) {
            const double* ak = A + 3 * node[k + 1][l];
            for (int i = 0; i < 3; ++i) d[k][i][l] = ak[i] - a0[i];
        }
    }
#endif
}

// The edges of positions X and, when Viscous, velocities V of a block whose
// node arrays hold last + 1 nodes: plain loads where plainGatherSafe allows
// them (last < 0: sizes unknown, masked loads).
template <bool Viscous>
inline void gatherBlockEdges(const double* X, const double* V, int32_t last, const int32_t (&node)[4][kLanes],
                             double (&dx)[3][3][kLanes], double (&dv)[3][3][kLanes]) {
    if (plainGatherSafe(node, last)) {
        gatherEdges<true>(X, node, dx);
        if constexpr (Viscous) gatherEdges<true>(V, node, dv);
    } else {
        gatherEdges(X, node, dx);
        if constexpr (Viscous) gatherEdges(V, node, dv);
    }
}

// buf[kForceStride * (node[k][l] - lo) + i] += f[k][i][l] for the first count
// lanes, lane by lane, corners in order.  buf: a force buffer with
// kForceStride doubles per node from node lo on, aligned to 32 bytes.
// Corner 0's force is not read: it is formed here as the kernel forms it,
// -((f1 + f2) + f3) (the element is in balance), on the rows after the
// transpose of corners 1..3: three vector additions where a fourth transpose
// took 8 shuffles (element_parts, AVX2: arithmetic + scatter 0.96-0.98 of its
// time).  (Session 14 measured no gain on the AVX-512 host: kept as one code.)
inline void scatterForces(const double (&f)[4][3][kLanes], const int32_t (&node)[4][kLanes], int count, double* buf,
                          int32_t lo) {
#if defined(__AVX__)
    for (int h = 0; h < 2 && 4 * h < count; ++h) {
        __m256d r[4][4];  // [corner][lane of the four]
        for (int k = 1; k < 4; ++k)
            simd::columnsToRows(_mm256_load_pd(f[k][0] + 4 * h), _mm256_load_pd(f[k][1] + 4 * h),
                                _mm256_load_pd(f[k][2] + 4 * h), r[k]);
        // Corner 0 as the lanes form it, -((f1 + f2) + f3), but on the rows:
        // three additions instead of a transpose (8 shuffles).
        for (int j = 0; j < 4; ++j)
            r[0][j] = _mm256_sub_pd(_mm256_setzero_pd(), _mm256_add_pd(_mm256_add_pd(r[1][j], r[2][j]), r[3][j]));
        const int lanes = count - 4 * h < 4 ? count - 4 * h : 4;
        for (int j = 0; j < lanes; ++j)
            for (int k = 0; k < 4; ++k) {
                double* o = buf + kForceStride * (node[k][4 * h + j] - lo);
                _mm256_store_pd(o, _mm256_add_pd(_mm256_load_pd(o), r[k][j]));
            }
    }
#else
    for (int l = 0; l < count; ++l)
        for (int k = 0; k < 4; ++k) {
            double* o = buf + kForceStride * (node[k][l] - lo);
            for (int i = 0; i < 3; ++i)
                o[i] += k > 0 ? f[k][i][l] : 0.0 - ((f[1][i][l] + f[2][i][l]) + f[3][i][l]);
        }
#endif
}

}  // namespace qdem
