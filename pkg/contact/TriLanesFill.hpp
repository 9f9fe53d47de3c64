// Filling the closest-point kernel's lanes (TriLanes, Geometry.hpp) from
// the listed triangles: the point-polygon loop's gather.
#pragma once
#include <cstdint>

#include "../element/NodeGather.hpp"
#include "Geometry.hpp"

namespace qdem {

// Lanes 4h .. 4h+3 of the closest-point kernel's input: the corners and the
// normal of the listed triangles L[0..3], each an x y z row read by one
// (masked) vector load and turned into columns by in-register transposes
// (NodeGather.hpp), instead of 48 scalar loads and 48 scalar stores.  Same
// values: the kernel's results are unchanged.
__attribute__((always_inline)) inline void fillTriLanes4(const double* X, const int32_t* tri, const double* normal,
                                                         const int32_t* L, int h, TriLanes& lanes) {
#if defined(__AVX__)
    const int32_t *t0 = tri + 3 * L[0], *t1 = tri + 3 * L[1], *t2 = tri + 3 * L[2], *t3 = tri + 3 * L[3];
    const auto rows = [&](const double* r0, const double* r1, const double* r2, const double* r3,
                          double (&col)[3][kTriLanes]) {
        __m256d x, y, z;
        simd::rowsToColumns(simd::loadXyz<false>(r0), simd::loadXyz<false>(r1), simd::loadXyz<false>(r2),
                            simd::loadXyz<false>(r3), x, y, z);
        _mm256_store_pd(col[0] + 4 * h, x);
        _mm256_store_pd(col[1] + 4 * h, y);
        _mm256_store_pd(col[2] + 4 * h, z);
    };
    rows(X + 3 * t0[0], X + 3 * t1[0], X + 3 * t2[0], X + 3 * t3[0], lanes.a);
    rows(X + 3 * t0[1], X + 3 * t1[1], X + 3 * t2[1], X + 3 * t3[1], lanes.b);
    rows(X + 3 * t0[2], X + 3 * t1[2], X + 3 * t2[2], X + 3 * t3[2], lanes.c);
    rows(normal + 3 * L[0], normal + 3 * L[1], normal + 3 * L[2], normal + 3 * L[3], lanes.n);
#else
    for (int l = 0; l < 4; ++l) {
        const int32_t* c = tri + 3 * L[l];
        for (int d = 0; d < 3; ++d) {
            lanes.a[d][4 * h + l] = X[3 * c[0] + d];
            lanes.b[d][4 * h + l] = X[3 * c[1] + d];
            lanes.c[d][4 * h + l] = X[3 * c[2] + d];
            lanes.n[d][4 * h + l] = normal[3 * L[l] + d];
        }
    }
#endif
}


}  // namespace qdem
