// Mesh generation, checks, surface extraction, Hilbert order.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "core/Errors.hpp"
#include "mesh/BoxMesh.hpp"
#include "mesh/Hilbert.hpp"
#include "mesh/Surface.hpp"
#include "mesh/TetMesh.hpp"

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

namespace {

std::vector<double> lumpedVolume(const TetMesh& m) {
    std::vector<double> v(m.nNodes(), 0.0);
    for (std::size_t t = 0; t < m.nTets(); ++t)
        for (int k = 0; k < 4; ++k) v[m.tets[4 * t + k]] += tetSixVolume(m, t) / 24;
    return v;
}

// Node at the given coordinates (a box mesh's nodes sit on a half-cell grid).
int32_t nodeAt(const TetMesh& m, const double x[3], double tol) {
    for (std::size_t i = 0; i < m.nNodes(); ++i)
        if (std::fabs(m.nodes[3 * i] - x[0]) < tol && std::fabs(m.nodes[3 * i + 1] - x[1]) < tol &&
            std::fabs(m.nodes[3 * i + 2] - x[2]) < tol)
            return static_cast<int32_t>(i);
    return -1;
}

// Offset of the bottom face's lumped-mass centre from the face centre, in
// cells (the box is centred on the origin).
double bottomMassOffset(const TetMesh& m, double lz, double h) {
    const std::vector<double> v = lumpedVolume(m);
    double s = 0, sx = 0, sy = 0;
    for (std::size_t i = 0; i < m.nNodes(); ++i)
        if (std::fabs(m.nodes[3 * i + 2] + 0.5 * lz) < 1e-12) {
            s += v[i];
            sx += v[i] * m.nodes[3 * i];
            sy += v[i] * m.nodes[3 * i + 1];
        }
    return std::hypot(sx / s, sy / s) / h;
}

}  // namespace

// Conforming: every face of a tetrahedron is shared by exactly two tets
// unless it lies on the box's surface; the surface is a closed manifold
// (extractSurface throws otherwise) and the volume is exact.
TEST(Mesh, BoxMeshesAreConforming) {
    for (int k : {5, 6, 12})
        for (auto c : {std::array<int, 3>{2, 2, 2}, {3, 3, 3}, {4, 5, 6}, {5, 2, 3}, {1, 1, 1}}) {
            const double L[3] = {0.3, 0.4, 0.5};
            const TetMesh m = boxMesh(c[0], c[1], c[2], L[0], L[1], L[2], k);
            checkMesh(m);
            std::map<std::array<int32_t, 3>, int> faces;
            for (std::size_t t = 0; t < m.nTets(); ++t)
                for (int skip = 0; skip < 4; ++skip) {
                    std::array<int32_t, 3> f;
                    int q = 0;
                    for (int j = 0; j < 4; ++j)
                        if (j != skip) f[q++] = m.tets[4 * t + j];
                    std::sort(f.begin(), f.end());
                    ++faces[f];
                }
            double v = 0;
            for (std::size_t t = 0; t < m.nTets(); ++t) v += tetSixVolume(m, t) / 6;
            EXPECT_NEAR(v, L[0] * L[1] * L[2], 1e-13);
            for (const auto& [f, count] : faces) {
                bool onBoundary = false;
                for (int d = 0; d < 3; ++d)
                    for (double side : {-0.5, 0.5}) {
                        bool all = true;
                        for (int32_t n : f) all = all && std::fabs(m.nodes[3 * n + d] - side * L[d]) < 1e-12;
                        onBoundary = onBoundary || all;
                    }
                ASSERT_EQ(count, onBoundary ? 1 : 2) << k << " tets/cell, " << c[0] << "x" << c[1] << "x" << c[2];
            }
            const Surface s = extractSurface(m);
            EXPECT_EQ(s.nTriangles(), static_cast<std::size_t>(4 * (c[0] * c[1] + c[1] * c[2] + c[0] * c[2])));
        }
}

// Mirror symmetry for even cell counts: the lumped mass at every node equals
// the one at its mirror image about each of the box's mid-planes (before: the
// 6-tet split put 3x the mass on one corner node of each face).
TEST(Mesh, EvenBoxMeshesAreMirrorSymmetric) {
    for (int k : {5, 6, 12})
        for (auto c : {std::array<int, 3>{2, 2, 2}, {4, 4, 4}, {2, 4, 6}}) {
            const TetMesh m = boxMesh(c[0], c[1], c[2], 1.0, 1.2, 1.4, k);
            const std::vector<double> v = lumpedVolume(m);
            const double mean = 1.0 * 1.2 * 1.4 / m.nNodes();
            for (std::size_t i = 0; i < m.nNodes(); ++i)
                for (int d = 0; d < 3; ++d) {
                    double x[3] = {m.nodes[3 * i], m.nodes[3 * i + 1], m.nodes[3 * i + 2]};
                    x[d] = -x[d];
                    const int32_t j = nodeAt(m, x, 1e-9);
                    ASSERT_GE(j, 0);
                    ASSERT_NEAR(v[i], v[j], 1e-12 * mean)
                        << k << " tets/cell, " << c[0] << "x" << c[1] << "x" << c[2] << ", node " << i << ", axis " << d;
                }
            EXPECT_LT(bottomMassOffset(m, 1.4, 1.0 / c[0]), 1e-12);
        }
}

// Odd counts: no split of the middle layer is symmetric; the offset of the
// bottom face's mass centre stays within what was measured for 3..9 cells
// (doc/dev/hard_cases_notebook.md, "Mesh symmetry"), n times below the old 6-tet split's.
TEST(Mesh, OddBoxMeshesStayNearlyBalanced) {
    for (int n : {3, 5, 7, 9})
        for (int k : {5, 6, 12}) {
            const TetMesh m = boxMesh(n, n, n, 1, 1, 1, k);
            const double off = bottomMassOffset(m, 1, 1.0 / n);
            // Measured (scripts/hard_cases/mesh_symmetry.py): sqrt(2)/6 h / n
            // for 6 (the old split's sqrt(2)/6 h, now from the middle layer
            // alone), a third of that for 12, 0 for 5 (half-turn symmetry).
            const double bound = (k == 6 ? std::sqrt(2.0) / 6 : (k == 12 ? std::sqrt(2.0) / 18 : 0.0)) / n + 1e-12;
            EXPECT_LE(off, bound) << n << " cells, " << k << " tets/cell";
        }
}

// A square pyramid (two tets) with a flat tet lying on its top face: the flat
// one has two faces on the surface and goes; the pyramid stays, checked.
TEST(Mesh, FlatTetInTheSurfaceIsDropped) {
    TetMesh m;
    m.nodes = {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0.5, 0.5, 0};  // a b c d (top), e (apex)
    m.tets = {4, 0, 1, 2, 4, 0, 2, 3, 0, 1, 2, 3};
    orientPositive(m);
    EXPECT_THROW(checkMesh(m), InputError);
    EXPECT_EQ(dropFlatSurfaceTets(m), 1u);
    ASSERT_EQ(m.nTets(), 2u);
    EXPECT_NO_THROW(checkMesh(m));
    EXPECT_EQ(dropFlatSurfaceTets(m), 0u);
}

// A flat tet between two pyramids, every face of it shared with one of them
// (none in the surface): left for checkMesh to name.
TEST(Mesh, FlatTetInsideIsKept) {
    TetMesh m;
    m.nodes = {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1, 0.5, 0.5, 0, 0.5, 0.5, 2};
    // lower pyramid on the split abc/acd, upper on abd/bcd, the flat tet abcd between
    m.tets = {4, 0, 1, 2, 4, 0, 2, 3, 5, 0, 1, 3, 5, 1, 2, 3, 0, 1, 2, 3};
    orientPositive(m);
    EXPECT_EQ(dropFlatSurfaceTets(m), 0u);
    EXPECT_EQ(m.nTets(), 5u);
    EXPECT_THROW(checkMesh(m), InputError);
}
