// The point-polygon prefilter (mayBeCandidate, contact/TriangleRecord.hpp)
// never drops a triangle that the exact candidate test (pointTriangle) keeps:
// filtering a node's list by it must leave the candidates unchanged.  Points
// are drawn near random triangles, on and beside grid triangles (the 27-cube
// scene's ties: nodes exactly over vertices and edges), in front, behind,
// straight behind deep down, and at heights within rounding of the reach.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "contact/PointTriangle.hpp"
#include "contact/TriangleRecord.hpp"

using namespace qdem;
using namespace qdem::contact_detail;
using Eigen::Vector3d;

namespace {

struct Counts {
    long candidates = 0, dropped = 0;
};

void check(const Vector3d& P, const Vector3d& a, const Vector3d& b, const Vector3d& c, double reach, double reachMax,
           bool regions, Counts& k) {
    Vector3d n = (b - a).cross(c - a).normalized();
    if (!n.allFinite()) return;
    TriRecord r;
    fillTriRecord(a, b, c, n, r);
    TriPoint cp;
    double dist;
    bool behind;
    const bool exact = pointTriangle(P, a, b, c, n, reach, regions, cp, dist, behind);
    const bool pass = mayBeCandidate(P.data(), r, reachMax);
    k.candidates += exact;
    k.dropped += !pass;
    ASSERT_TRUE(pass || !exact) << "dropped a candidate: P " << P.transpose() << " a " << a.transpose() << " b "
                                << b.transpose() << " c " << c.transpose() << " reach " << reach;
}

}  // namespace

TEST(TriangleRecord, PrefilterKeepsEveryCandidate) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0), s(0.0, 1.0);
    Counts k;
    for (int it = 0; it < 400000; ++it) {
        const double reach = 0.02 + 0.1 * s(rng);
        const double reachMax = reach * (1 + (it % 3 == 0 ? 0.5 * s(rng) : 0.0));
        const bool regions = it % 7 != 0;
        Vector3d a, b, c;
        if (it % 2 == 0) {  // a grid triangle of 0.5 m cells, fan of 4 per cell
            const Vector3d o(0.5 * (it % 5), 0.5 * (it % 3), 0.0);
            a = o, b = o + Vector3d(0.5, 0, 0), c = o + Vector3d(0.25, 0.25, 0);
        } else {
            a = Vector3d(u(rng), u(rng), u(rng)), b = a + 0.3 * Vector3d(u(rng), u(rng), u(rng));
            c = a + 0.3 * Vector3d(u(rng), u(rng), u(rng));
        }
        const Vector3d n = (b - a).cross(c - a).normalized();
        // Over a vertex, an edge's middle, the face, or anywhere near; at a
        // height drawn in [-3, 1.5] reach, or at the reach to rounding.
        const double w0 = s(rng), w1 = s(rng) * (1 - w0);
        Vector3d base;
        switch (it % 4) {
            case 0: base = (it % 8 == 0) ? a : b; break;
            case 1: base = 0.5 * (a + c); break;
            case 2: base = w0 * a + w1 * b + (1 - w0 - w1) * c; break;
            default: base = a + 0.6 * Vector3d(u(rng), u(rng), u(rng));
        }
        double h = reach * (4.5 * s(rng) - 3.0);
        if (it % 11 == 0) h = reach * (1 - 1e-15 * u(rng));
        if (it % 13 == 0) h = -20 * reach * s(rng);  // deep behind
        Vector3d side = Vector3d::Zero();
        if (it % 17 == 0) side = Vector3d(u(rng), u(rng), u(rng)).cross(n) * reach * s(rng);
        check(base + h * n + side, a, b, c, reach, reachMax, regions, k);
    }
    // The test means something: many candidates, and many triangles dropped.
    EXPECT_GT(k.candidates, 50000);
    EXPECT_GT(k.dropped, 50000);
}

TEST(TriangleRecord, RecordHoldsTheCornersBitForBit) {
    const Vector3d a(0.1, 0.2, 0.3), b(1.0 / 3, 0.7, -0.2), c(-0.4, 2.0 / 7, 0.9);
    const Vector3d n = (b - a).cross(c - a).normalized();
    TriRecord r;
    fillTriRecord(a, b, c, n, r);
    for (int d = 0; d < 3; ++d) {
        EXPECT_EQ(r.a[d], a[d]);
        EXPECT_EQ(r.b[d], b[d]);
        EXPECT_EQ(r.c[d], c[d]);
        EXPECT_EQ(r.n[d], n[d]);
    }
    const Vector3d m = (a + b + c) / 3;
    EXPECT_NEAR(r.radius, std::max({(a - m).norm(), (b - m).norm(), (c - m).norm()}), 1e-15);
}
