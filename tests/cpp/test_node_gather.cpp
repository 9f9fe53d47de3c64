// The element kernel's node gather and force scatter (NodeGather.hpp) against
// plain scalar loops: the same numbers to the bit, including a node at the
// very end of the array (read with a masked vector load: nothing past it),
// lanes that share nodes (the scatter's store-to-load chain), partial blocks
// (lanes past `count` add nothing), and corner 0's force formed from the
// other three as the kernel forms it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/Aligned.hpp"
#include "contact/TriLanesFill.hpp"
#include "element/NodeGather.hpp"

using namespace qdem;

namespace {

// Node ids with repeats and the last node of the array, in every corner.
void makeBlock(int32_t (&node)[4][kLanes], int32_t nNodes) {
    const int32_t pattern[4][kLanes] = {{0, 5, nNodes - 1, 7, 3, 3, 9, 2},
                                        {1, nNodes - 1, 4, 8, 5, 10, 3, 11},
                                        {2, 6, 5, nNodes - 1, 12, 4, 13, 3},
                                        {nNodes - 1, 7, 6, 9, 14, 15, 1, 0}};
    std::memcpy(node, pattern, sizeof(pattern));
}

// The scatter forms corner 0's force from the other three, as the kernel
// does (the element is in balance), and never reads f[0]: NaN there.
void unbalance(double (&f)[4][3][kLanes]) {
    for (int i = 0; i < 3; ++i)
        for (int l = 0; l < kLanes; ++l) f[0][i][l] = std::nan("");
}
double force(const double (&f)[4][3][kLanes], int k, int i, int l) {
    return k > 0 ? f[k][i][l] : 0.0 - ((f[1][i][l] + f[2][i][l]) + f[3][i][l]);
}

}  // namespace

TEST(NodeGather, EdgesEqualScalarLoopsUpToTheLastNode) {
    const int32_t N = 17;
    // Exactly 3N doubles: an unmasked 4-wide load of the last node would
    // read one past the end (AddressSanitizer builds flag it).
    std::vector<double> X(3 * N);
    for (int i = 0; i < 3 * N; ++i) X[i] = 0.37 * i - 0.011 * i * i + (i % 3) * 1e-9;
    int32_t node[4][kLanes];
    makeBlock(node, N);
    alignas(64) double d[3][3][kLanes];
    gatherEdges(X.data(), node, d);
    for (int l = 0; l < kLanes; ++l)
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i) {
                const double want = X[3 * node[k + 1][l] + i] - X[3 * node[0][l] + i];
                EXPECT_EQ(d[k][i][l], want) << "lane " << l << " edge " << k << " component " << i;
            }
}

TEST(NodeGather, ScatterAddsLaneByLaneLikeTheScalarCode) {
    const int32_t N = 17, lo = 0;
    int32_t node[4][kLanes];
    makeBlock(node, N);
    alignas(64) double f[4][3][kLanes];
    for (int k = 0; k < 4; ++k)
        for (int i = 0; i < 3; ++i)
            for (int l = 0; l < kLanes; ++l) f[k][i][l] = 1.0 / (1 + k + 7 * i + 13 * l) - 0.03 * l;
    unbalance(f);
    for (int count : {1, 3, 4, 5, 8}) {
        AlignedVector<double> buf(kForceStride * N, 0.25), want(kForceStride * N, 0.25);
        scatterForces(f, node, count, buf.data(), lo);
        for (int l = 0; l < count; ++l)  // the scalar order: lanes, then corners
            for (int k = 0; k < 4; ++k)
                for (int i = 0; i < 3; ++i) want[kForceStride * node[k][l] + i] += force(f, k, i, l);
        for (int32_t n = 0; n < N; ++n) {
            for (int i = 0; i < 3; ++i)
                EXPECT_EQ(buf[kForceStride * n + i], want[kForceStride * n + i])
                    << "count " << count << " node " << n << " component " << i;
            EXPECT_EQ(buf[kForceStride * n + 3], 0.25) << "the pad slot only ever receives zeros";
        }
    }
}

TEST(NodeGather, ScatterIntoABufferStartingAtNodeLo) {
    const int32_t N = 17, lo = 0;
    int32_t node[4][kLanes];
    makeBlock(node, N);
    for (auto& row : node)
        for (int32_t& n : row) n += 100;  // a thread whose nodes start at 100
    alignas(64) double f[4][3][kLanes];
    for (int k = 0; k < 4; ++k)
        for (int i = 0; i < 3; ++i)
            for (int l = 0; l < kLanes; ++l) f[k][i][l] = k + 0.5 * i + 0.25 * l;
    unbalance(f);
    AlignedVector<double> buf(kForceStride * N, 0.0), want(kForceStride * N, 0.0);
    scatterForces(f, node, kLanes, buf.data(), lo + 100);
    for (int l = 0; l < kLanes; ++l)
        for (int k = 0; k < 4; ++k)
            for (int i = 0; i < 3; ++i) want[kForceStride * (node[k][l] - 100) + i] += force(f, k, i, l);
    for (std::size_t j = 0; j < buf.size(); ++j) EXPECT_EQ(buf[j], want[j]) << j;
}

TEST(NodeGather, PlainLoadsAllowedOnlyWhereNoCornerIsTheLastNode) {
    const int32_t N = 40, last = N - 1;
    int32_t node[4][kLanes];
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < kLanes; ++l) node[k][l] = (7 * k + 3 * l) % last;  // never the last node
    EXPECT_TRUE(plainGatherSafe(node, last));
    EXPECT_FALSE(plainGatherSafe(node, -1)) << "an array of unknown size gets masked loads";
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < kLanes; ++l) {
            const int32_t keep = node[k][l];
            node[k][l] = last;
            EXPECT_FALSE(plainGatherSafe(node, last)) << "last node in corner " << k << " lane " << l;
            node[k][l] = keep;
        }
}

TEST(NodeGather, PlainGatherEqualsTheMaskedOneAndTheScalarLoop) {
    const int32_t N = 40, last = N - 1;
    std::vector<double> X(3 * N);
    for (int i = 0; i < 3 * N; ++i) X[i] = 0.37 * i - 0.011 * i * i + (i % 3) * 1e-9;
    int32_t node[4][kLanes];
    for (int k = 0; k < 4; ++k)
        for (int l = 0; l < kLanes; ++l) node[k][l] = (11 * k + 5 * l + (l == 3 ? 0 : 1)) % last;  // repeats too
    ASSERT_TRUE(plainGatherSafe(node, last));
    alignas(64) double plain[3][3][kLanes], masked[3][3][kLanes];
    gatherEdges<true>(X.data(), node, plain);
    gatherEdges(X.data(), node, masked);
    for (int l = 0; l < kLanes; ++l)
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < 3; ++i) {
                EXPECT_EQ(plain[k][i][l], masked[k][i][l]) << "lane " << l << " edge " << k << " component " << i;
                EXPECT_EQ(plain[k][i][l], X[3 * node[k + 1][l] + i] - X[3 * node[0][l] + i]);
            }
}

// The point-polygon loop's lane fill: corners and normals of listed
// triangles as columns, equal to the scalar copy, including the last node
// and the last triangle of their arrays (masked loads: nothing read past).
TEST(NodeGather, TriangleLanesEqualTheScalarCopy) {
    const int32_t N = 13, T = 9;
    std::vector<double> X(3 * N), normal(3 * T);
    for (int i = 0; i < 3 * N; ++i) X[i] = 0.21 * i - 0.003 * i * i;
    for (int i = 0; i < 3 * T; ++i) normal[i] = std::sin(0.7 * i);
    std::vector<int32_t> tri(3 * T);
    for (int t = 0; t < T; ++t)
        for (int j = 0; j < 3; ++j) tri[3 * t + j] = (5 * t + 4 * j + (t == T - 1 ? N - 1 : 0)) % N;
    tri[3 * (T - 1) + 2] = N - 1;
    const int32_t L[kTriLanes] = {T - 1, 0, 3, 3, 7, 2, T - 1, 5};
    TriLanes lanes{};
    fillTriLanes4(X.data(), tri.data(), normal.data(), L, 0, lanes);
    fillTriLanes4(X.data(), tri.data(), normal.data(), L + 4, 1, lanes);
    for (int l = 0; l < kTriLanes; ++l) {
        const int32_t* c = &tri[3 * L[l]];
        for (int d = 0; d < 3; ++d) {
            EXPECT_EQ(lanes.a[d][l], X[3 * c[0] + d]) << "lane " << l;
            EXPECT_EQ(lanes.b[d][l], X[3 * c[1] + d]) << "lane " << l;
            EXPECT_EQ(lanes.c[d][l], X[3 * c[2] + d]) << "lane " << l;
            EXPECT_EQ(lanes.n[d][l], normal[3 * L[l] + d]) << "lane " << l;
        }
    }
}
