// Mesh generation, checks, surface extraction, Hilbert order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/Errors.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Hilbert.hpp"
#include "mesh/Surface.hpp"

using namespace qdem;

TEST(Mesh, SeedCubeCounts) {
    const TetMesh m = boxMesh(8, 8, 8, 1, 1, 1, 12);
    EXPECT_EQ(m.nNodes(), 1241u);
    EXPECT_EQ(m.nTets(), 6144u);
    const Surface s = extractSurface(m);
    EXPECT_EQ(s.nodes.size(), 386u);
    EXPECT_EQ(s.nTriangles(), 768u);
}

TEST(Mesh, BoxVariantsFillTheVolume) {
    for (int k : {5, 6, 12}) {
        const TetMesh m = boxMesh(3, 4, 5, 0.3, 0.4, 0.5, k);
        checkMesh(m);
        double v = 0;
        for (std::size_t t = 0; t < m.nTets(); ++t) v += tetSixVolume(m, t) / 6;
        EXPECT_NEAR(v, 0.3 * 0.4 * 0.5, 1e-12) << k;
        const Surface s = extractSurface(m);  // conforming: manifold surface
        EXPECT_EQ(s.nodes.size(), 4u * 5 * 6 - 2u * 3 * 4) << k;
    }
}

TEST(Mesh, RejectsBadInput) {
    TetMesh m = boxMesh(1, 1, 1, 1, 1, 1, 6);
    TetMesh inv = m;
    std::swap(inv.tets[2], inv.tets[3]);
    EXPECT_THROW(checkMesh(inv), InputError);
    TetMesh nan = m;
    nan.nodes[4] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(checkMesh(nan), InputError);
    TetMesh flat = m;
    for (std::size_t i = 0; i < flat.nNodes(); ++i) flat.nodes[3 * i + 2] = 0;
    EXPECT_THROW(checkMesh(flat), InputError);
    TetMesh range = m;
    range.tets[0] = 99;
    EXPECT_THROW(checkMesh(range), InputError);
    try {
        checkMesh(inv);
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("inverted"), std::string::npos);
    }
}

TEST(Mesh, NonManifoldSurfaceIsRejected) {
    // Two tets sharing only an edge: the surface is pinched along it.
    TetMesh m;
    m.nodes = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, -1, 0.2, -1, 0.5, 0.6};
    m.tets = {0, 1, 2, 3, 0, 3, 4, 5};
    orientPositive(m);
    checkMesh(m);
    EXPECT_THROW(extractSurface(m), InputError);
}

TEST(Mesh, HilbertReorderIsAPermutation) {
    TetMesh m = boxMesh(4, 4, 4, 1, 1, 1, 12);
    const TetMesh before = m;
    const std::vector<int32_t> oldOf = hilbertReorder(m);
    ASSERT_EQ(oldOf.size(), m.nNodes());
    std::vector<int32_t> sorted = oldOf;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(sorted[i], static_cast<int32_t>(i));
    for (std::size_t i = 0; i < m.nNodes(); ++i)
        for (int d = 0; d < 3; ++d) EXPECT_EQ(m.nodes[3 * i + d], before.nodes[3 * oldOf[i] + d]);
    checkMesh(m);
}
