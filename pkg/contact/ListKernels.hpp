// The two tests of the Verlet list build (PieceContactPhase), 8 lanes at a
// time with AVX-512 and branch-free scalar code elsewhere.  The lanes do the
// very operations of the scalar code, rounded alike, so both give the lists
// the former branchy loops gave, bit for bit (tests/cpp/test_list_kernels.cpp).
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace qdem {

// |d|^2 rounded exactly as the former list build's (A - P).squaredNorm()
// compiled (-O3, FMA: its disassembly): dx^2 and dy^2 each rounded, summed,
// then dz^2 fused in.  Written out so that the compiler cannot fuse
// differently here (fma(x, x, 0) is x^2 rounded, and is not contracted into
// the add).
inline double distance2AsEigen(double dx, double dy, double dz) {
#ifdef __FMA__
    return std::fma(dz, dz, std::fma(dx, dx, 0.0) + std::fma(dy, dy, 0.0));
#else
    return dx * dx + dy * dy + dz * dz;
#endif
}

// Bit t (t < m <= 64) set when the point A lies in box q0 + t grown by its
// reach: A - reach[q] <= hi[d][q] and lo[d][q] <= A + reach[q] on every axis.
inline uint64_t boxesNearScalar(const double* A, const double* reach, const double* const* lo,
                                const double* const* hi, int32_t q0, int m) {
    uint64_t near = 0;
    for (int t = 0; t < m; ++t) {
        const int32_t q = q0 + t;
        const double r = reach[q];
        const bool o = (A[0] - r <= hi[0][q]) & (lo[0][q] <= A[0] + r) & (A[1] - r <= hi[1][q]) &
                       (lo[1][q] <= A[1] + r) & (A[2] - r <= hi[2][q]) & (lo[2][q] <= A[2] + r);
        near |= static_cast<uint64_t>(o) << t;
    }
    return near;
}

inline uint64_t boxesNear(const double* A, const double* reach, const double* const* lo, const double* const* hi,
                          int32_t q0, int m) {
#if defined(__AVX512F__)
    uint64_t near = 0;
    for (int t = 0; t < m; t += 8) {
        const __mmask8 lanes = m - t >= 8 ? __mmask8(0xFF) : static_cast<__mmask8>((1u << (m - t)) - 1);
        const __m512d R = _mm512_maskz_loadu_pd(lanes, reach + q0 + t);
        __mmask8 o = lanes;
        for (int d = 0; d < 3; ++d) {
            const __m512d a = _mm512_set1_pd(A[d]);
            o = _mm512_mask_cmp_pd_mask(o, _mm512_sub_pd(a, R), _mm512_maskz_loadu_pd(lanes, hi[d] + q0 + t),
                                        _CMP_LE_OQ);
            o = _mm512_mask_cmp_pd_mask(o, _mm512_maskz_loadu_pd(lanes, lo[d] + q0 + t), _mm512_add_pd(a, R),
                                        _CMP_LE_OQ);
        }
        near |= static_cast<uint64_t>(o) << t;
    }
    return near;
#else
    return boxesNearScalar(A, reach, lo, hi, q0, m);
#endif
}

// Appends to buf, in slot order, item[k] for the slots k in [b, e) whose
// sphere (x, y, z)[k], radius r[k] + reach, holds A: |A - P|^2 <= (r +
// reach)^2 (not greater: a NaN passes, as before).  Returns the new count,
// which may exceed cap: the entries past cap are not kept (buf needs cap + 8
// slots), the count says the list overflowed.
inline int spheresWithinScalar(const double* A, double reach, const double* x, const double* y, const double* z,
                               const double* r, const int32_t* item, int32_t b, int32_t e, int32_t* buf, int count,
                               int cap) {
    for (int32_t k = b; k < e; ++k) {
        const double R = r[k] + reach;
        const double d2 = distance2AsEigen(A[0] - x[k], A[1] - y[k], A[2] - z[k]);
        buf[std::min(count, cap)] = item[k];  // written always, kept only if it passes: no branch
        count += !(d2 > R * R);
    }
    return count;
}

inline int spheresWithin(const double* A, double reach, const double* x, const double* y, const double* z,
                         const double* r, const int32_t* item, int32_t b, int32_t e, int32_t* buf, int count,
                         int cap) {
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__FMA__)
    // distance2AsEigen's operations lane by lane; the passing items packed in
    // order by a register compress.
    const __m512d ax = _mm512_set1_pd(A[0]), ay = _mm512_set1_pd(A[1]), az = _mm512_set1_pd(A[2]);
    const __m512d rc = _mm512_set1_pd(reach), zero = _mm512_setzero_pd();
    for (int32_t k = b; k < e; k += 8) {
        const __mmask8 lanes = e - k >= 8 ? __mmask8(0xFF) : static_cast<__mmask8>((1u << (e - k)) - 1);
        const __m512d dx = _mm512_sub_pd(ax, _mm512_maskz_loadu_pd(lanes, x + k));
        const __m512d dy = _mm512_sub_pd(ay, _mm512_maskz_loadu_pd(lanes, y + k));
        const __m512d dz = _mm512_sub_pd(az, _mm512_maskz_loadu_pd(lanes, z + k));
        const __m512d R = _mm512_add_pd(_mm512_maskz_loadu_pd(lanes, r + k), rc);
        const __m512d d2 =
            _mm512_fmadd_pd(dz, dz, _mm512_add_pd(_mm512_fmadd_pd(dx, dx, zero), _mm512_fmadd_pd(dy, dy, zero)));
        const __mmask8 pass = _mm512_mask_cmp_pd_mask(lanes, d2, _mm512_mul_pd(R, R), _CMP_NGT_UQ);
        if (count <= cap)
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(buf + count),
                                _mm256_maskz_compress_epi32(pass, _mm256_maskz_loadu_epi32(lanes, item + k)));
        count += std::popcount(static_cast<unsigned>(pass));
    }
    return count;
#else
    return spheresWithinScalar(A, reach, x, y, z, r, item, b, e, buf, count, cap);
#endif
}

}  // namespace qdem
