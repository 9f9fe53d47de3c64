// The Verlet list build's kernels (contact/ListKernels.hpp): the lane (AVX-512
// when built for it) versions against the scalar ones, item for item and in
// order, on random spheres and boxes and on points placed exactly on the
// boundary (|A - P| = r + reach and A - reach = hi in exact arithmetic),
// where a different rounding would flip the decision.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "contact/ListKernels.hpp"

using namespace qdem;

TEST(ListKernels, SpheresWithinMatchesScalarInOrder) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0), ur(0.0, 0.5);
    const int n = 37;  // not a multiple of 8: masked tails
    std::vector<double> x(n), y(n), z(n), r(n);
    std::vector<int32_t> item(n);
    int boundary = 0, passed = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        const double A[3] = {u(rng), u(rng), u(rng)};
        const double reach = 0.1 * ur(rng);
        for (int k = 0; k < n; ++k) {
            r[k] = ur(rng), item[k] = 1000 * trial + k;
            if (k % 3 == 0) {
                // On the sphere's boundary along (3, 4, 0)/5, (1, 2, 2)/3 or
                // an axis: |d| = r + reach up to the rounding of d, where
                // fusing dx^2 + dy^2 differently flips the test.
                const double R = r[k] + reach;
                static const double dir[3][3] = {{0.6, 0.8, 0.0}, {1.0 / 3, 2.0 / 3, 2.0 / 3}, {0.0, 0.0, 1.0}};
                const double* v = dir[k % 9 / 3];
                x[k] = A[0] + R * v[0], y[k] = A[1] - R * v[1], z[k] = A[2] + R * v[2];
                ++boundary;
            } else {
                x[k] = u(rng), y[k] = u(rng), z[k] = u(rng);
            }
        }
        const int b = trial % 5, e = n - trial % 3;
        int32_t lane[64 + 8], scalar[64 + 8];
        const int cap = 48;
        const int nl = spheresWithin(A, reach, x.data(), y.data(), z.data(), r.data(), item.data(), b, e, lane, 0, cap);
        const int ns =
            spheresWithinScalar(A, reach, x.data(), y.data(), z.data(), r.data(), item.data(), b, e, scalar, 0, cap);
        ASSERT_EQ(nl, ns) << "trial " << trial;
        for (int k = 0; k < std::min(ns, cap); ++k) ASSERT_EQ(lane[k], scalar[k]) << "trial " << trial << " slot " << k;
        // The scalar kernel against its definition, written out here.
        int expect = 0;
        for (int k = b; k < e; ++k) {
            const double R = r[k] + reach;
            expect += !(distance2AsEigen(A[0] - x[k], A[1] - y[k], A[2] - z[k]) > R * R);
        }
        ASSERT_EQ(ns, expect);
        passed += ns;
    }
    EXPECT_GT(boundary, 0);
    EXPECT_GT(passed, 0);
}

TEST(ListKernels, SpheresWithinCountsPastTheCap) {
    // 20 items all holding A, cap 8: the count says 20, the first 8 kept in order.
    const int n = 20;
    std::vector<double> x(n, 0.0), y(n, 0.0), z(n, 0.0), r(n, 1.0);
    std::vector<int32_t> item(n);
    for (int k = 0; k < n; ++k) item[k] = k;
    const double A[3] = {0.1, 0.0, 0.0};
    int32_t buf[8 + 8];
    const int c = spheresWithin(A, 0.0, x.data(), y.data(), z.data(), r.data(), item.data(), 0, n, buf, 0, 8);
    EXPECT_EQ(c, n);
    for (int k = 0; k < 8; ++k) EXPECT_EQ(buf[k], k);
}

TEST(ListKernels, BoxesNearMatchesScalar) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-2.0, 2.0), ur(0.0, 0.3);
    const int n = 70;  // two chunks: 64 + 6
    std::vector<double> reach(n), lo[3], hi[3];
    for (int d = 0; d < 3; ++d) lo[d].resize(n), hi[d].resize(n);
    const double* L[3] = {lo[0].data(), lo[1].data(), lo[2].data()};
    const double* H[3] = {hi[0].data(), hi[1].data(), hi[2].data()};
    int hits = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const double A[3] = {u(rng), u(rng), u(rng)};
        for (int q = 0; q < n; ++q) {
            reach[q] = ur(rng);
            for (int d = 0; d < 3; ++d) {
                const double a = u(rng), b = u(rng);
                lo[d][q] = std::min(a, b), hi[d][q] = std::max(a, b);
            }
            // Touching exactly: A - reach on hi (x) or lo on A + reach (y).
            if (q % 4 == 0) hi[0][q] = A[0] - reach[q];
            if (q % 4 == 1) lo[1][q] = A[1] + reach[q];
        }
        for (int q0 = 0; q0 < n; q0 += 64) {
            const int m = std::min(64, n - q0);
            const uint64_t lane = boxesNear(A, reach.data(), L, H, q0, m);
            ASSERT_EQ(lane, boxesNearScalar(A, reach.data(), L, H, q0, m)) << "trial " << trial;
            hits += std::popcount(lane);
        }
    }
    EXPECT_GT(hits, 0);
}
