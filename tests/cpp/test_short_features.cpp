// Short sharp creases smoothed before meshing (ShortFeatures.hpp); built
// with the CGAL mesher, which calls it.
#ifdef QDEM_HAVE_CGAL

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "mesh/ShortFeatures.hpp"

using namespace qdem;

namespace {

using Vec = std::array<double, 3>;
using Tri = std::array<std::size_t, 3>;

// A unit cube whose top face carries a small pointed bump: an inner square
// of half-side e around the face's centre and the centre raised by 3 e.
// The bump's edges are sharp (its sides stand 72 degrees off the face) and
// total about 20 e; the cube's 12 edges (sharp, 90 degrees) total 12.
struct Bumped {
    std::vector<Vec> points;
    std::vector<Tri> tris;
};

Bumped bumpedCube(double e) {
    Bumped b;
    b.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1},
                {0.5 - e, 0.5 - e, 1}, {0.5 + e, 0.5 - e, 1}, {0.5 + e, 0.5 + e, 1}, {0.5 - e, 0.5 + e, 1},
                {0.5, 0.5, 1 + 3 * e}};
    b.tris = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {3, 7, 6}, {3, 6, 2},
              {0, 4, 7}, {0, 7, 3}, {1, 2, 6}, {1, 6, 5}};
    // Top face: the ring between the outer square (4..7) and the inner one
    // (8..11), then the bump's fan around 12; all counter-clockwise from above.
    for (std::size_t i = 0; i < 4; ++i) {
        const std::size_t o0 = 4 + i, o1 = 4 + (i + 1) % 4, n0 = 8 + i, n1 = 8 + (i + 1) % 4;
        b.tris.push_back({o0, o1, n1});
        b.tris.push_back({o0, n1, n0});
        b.tris.push_back({n0, n1, 12});
    }
    return b;
}

}  // namespace

TEST(ShortFeatures, APointedBumpShorterThanTheSurfaceSizeIsSmoothedAndTheCubeKept) {
    Bumped b = bumpedCube(0.01);
    const std::vector<Vec> before = b.points;
    const ShortFeatureReport r = smoothShortFeatures(b.points, b.tris, 60.0, 0.5);
    EXPECT_EQ(r.smoothed, 1u);  // the bump's edges, one set of ~0.2
    EXPECT_EQ(r.kept, 1u);      // the cube's twelve edges, one set of 12
    for (std::size_t v = 0; v < 8; ++v) EXPECT_EQ(b.points[v], before[v]) << "cube corner " << v << " moved";
    EXPECT_LT(b.points[12][2] - 1.0, 0.5 * 0.03);  // the tip came down at least halfway
    EXPECT_GT(r.longestMoved, 0.0);
    EXPECT_LT(r.longestMoved, 0.03);  // no vertex moved further than the bump's own size
    // Nothing short is left: a second pass finds only the cube's edges.
    const ShortFeatureReport again = smoothShortFeatures(b.points, b.tris, 60.0, 0.5);
    EXPECT_EQ(again.smoothed, 0u);
    EXPECT_EQ(again.kept, 1u);
}

TEST(ShortFeatures, FeaturesAtLeastTheSurfaceSizeLongStay) {
    Bumped b = bumpedCube(0.01);
    const std::vector<Vec> before = b.points;
    const ShortFeatureReport r = smoothShortFeatures(b.points, b.tris, 60.0, 0.05);  // the bump (~0.2) is longer
    EXPECT_EQ(r.smoothed, 0u);
    EXPECT_EQ(r.kept, 2u);
    EXPECT_EQ(r.longestMoved, 0.0);
    EXPECT_EQ(b.points, before);
}

#endif  // QDEM_HAVE_CGAL
