// The graded size field of meshClosedSurface's thin parts (pkg/mesh/SizeGrid).
#ifdef QDEM_HAVE_CGAL

#include <gtest/gtest.h>

#include <cmath>

#include "mesh/SizeGrid.hpp"

using namespace qdem;

namespace {

// One seed node of size s0 at the grid's node nearest the centre.
SizeGrid seeded(double s0, double gradation, std::array<std::size_t, 3>* at) {
    SizeGrid g({0, 0, 0}, {1, 1, 1}, 0.02, 0.5);
    const auto n = g.dims();
    *at = {n[0] / 2, n[1] / 2, n[2] / 2};
    g.lower((*at)[0], (*at)[1], (*at)[2], s0);
    g.grade(gradation);
    return g;
}

}  // namespace

TEST(SizeGrid, UnseededIsTheCapEverywhere) {
    SizeGrid g({0, 0, 0}, {1, 2, 3}, 0.1, 0.3);
    EXPECT_TRUE(g.empty());
    EXPECT_DOUBLE_EQ(g.at(0.5, 0.5, 0.5), 0.3);
    EXPECT_DOUBLE_EQ(g.at(-10, 50, 3), 0.3);
}

TEST(SizeGrid, GrowsByTheGradationAwayFromASeedUpToTheCap) {
    std::array<std::size_t, 3> c{};
    const SizeGrid g = seeded(0.01, 0.4, &c);
    const auto p = g.node(c[0], c[1], c[2]);
    EXPECT_NEAR(g.at(p[0], p[1], p[2]), 0.01, 1e-6);
    // Along an axis and a diagonal: s0 + gradation x distance (the chamfer
    // length is within 8 % of the Euclidean one), never below it.
    for (double d : {0.1, 0.3}) {
        const double along = g.at(p[0] + d, p[1], p[2]);
        EXPECT_NEAR(along, 0.01 + 0.4 * d, 1e-5);
        const double e = d / std::sqrt(3.0);
        const double diag = g.at(p[0] + e, p[1] + e, p[2] + e);
        EXPECT_GE(diag, 0.01 + 0.4 * d - 1e-5);
        EXPECT_LE(diag, 0.01 + 1.08 * 0.4 * d);
    }
    // Far enough (0.01 + 1.0 x 0.85 > 0.5): the cap.
    std::array<std::size_t, 3> c1{};
    const SizeGrid steep = seeded(0.01, 1.0, &c1);
    const auto q = steep.node(c1[0], c1[1], c1[2]);
    EXPECT_DOUBLE_EQ(steep.at(q[0] + 0.49, q[1] + 0.49, q[2] + 0.49), 0.5);
}

TEST(SizeGrid, NodeBudgetCoarsensTheSpacing) {
    SizeGrid g({0, 0, 0}, {1, 1, 1}, 0.001, 1.0, 100000);
    const auto n = g.dims();
    EXPECT_LE(n[0] * n[1] * n[2], 100000u);
    EXPECT_GT(g.spacing(), 0.001);
}

#endif
