// The lane (SIMD) closest point on triangles against the scalar one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "contact/Geometry.hpp"

using namespace qdem;
using Eigen::Vector3d;

namespace {

// Random triangles and points, and points placed exactly over the vertices
// and edges of a regular grid of triangles (the ties of the 27-cube scene).
void checkAgainstScalar(std::mt19937& rng, double gridShare, int& boundary) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_int_distribution<int> g(-2, 2);
    TriLanes in;
    Vector3d a[kTriLanes], b[kTriLanes], c[kTriLanes], n[kTriLanes];
    const bool grid = std::uniform_real_distribution<double>(0, 1)(rng) < gridShare;
    for (int l = 0; l < kTriLanes; ++l) {
        if (grid) {
            const Vector3d o(0.5 * g(rng), 0.5 * g(rng), 0.0);
            a[l] = o, b[l] = o + Vector3d(0.5, 0, 0), c[l] = o + Vector3d(0.5 * (l % 2), 0.5, 0);
        } else {
            a[l] = Vector3d(u(rng), u(rng), u(rng)), b[l] = Vector3d(u(rng), u(rng), u(rng));
            c[l] = Vector3d(u(rng), u(rng), u(rng));
        }
        n[l] = (b[l] - a[l]).cross(c[l] - a[l]).normalized();
        if (!n[l].allFinite()) n[l] = Vector3d::UnitZ();
        for (int d = 0; d < 3; ++d)
            in.a[d][l] = a[l][d], in.b[d][l] = b[l][d], in.c[d][l] = c[l][d], in.n[d][l] = n[l][d];
    }
    const Vector3d p = grid ? Vector3d(0.5 * g(rng), 0.25 * g(rng), 0.078) : Vector3d(u(rng), u(rng), u(rng));
    TriLanesOut out;
    closestOnTriangles(p.data(), in, out);
    for (int l = 0; l < kTriLanes; ++l) {
        const TriPoint r = closestOnTriangle(p, a[l], b[l], c[l]);
        const Vector3d q(out.point[0][l], out.point[1][l], out.point[2][l]);
        const double tol = 1e-12;
        // The same point, weights, height and distance to rounding (the
        // compiler may fuse multiply-adds differently in lane code) ...
        EXPECT_LT((q - r.point).norm(), tol);
        for (int d = 0; d < 3; ++d) EXPECT_NEAR(r.w[d], out.w[d][l], tol);
        EXPECT_NEAR((p - a[l]).dot(n[l]), out.h[l], tol);
        EXPECT_NEAR((p - r.point).norm(), std::sqrt(out.dist2[l]), tol);
        // ... and the same region, except on a region boundary (a point on an
        // edge's end is that edge's and that corner's), where the weights
        // agree to rounding anyway.
        if (static_cast<int>(r.feature) != out.feature[l]) {
            ++boundary;
            double wMin = 1;
            for (int d = 0; d < 3; ++d) wMin = std::min(wMin, std::max(r.w[d], out.w[d][l]));
            EXPECT_LT(wMin, tol) << "lane " << l << " p " << p.transpose();
        }
    }
}

}  // namespace

TEST(Geometry, LaneClosestPointEqualsTheScalarOne) {
    std::mt19937 rng(12345);
    int boundary = 0;
    for (int i = 0; i < 20000; ++i) checkAgainstScalar(rng, 0.3, boundary);
    EXPECT_LT(boundary, 20000 * kTriLanes / 50);  // region differs only on boundaries: rare
}
