// The MPI split (pkg/parallel/Partition.hpp): ownership, balance, whole
// pieces, determinism and halos, on scenes built as the world builds them.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <numeric>

#include "mesh/BoxMesh.hpp"
#include "mesh/Hilbert.hpp"
#include "parallel/Partition.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

// A world and the partitioner's view of it.
struct Scene {
    std::unique_ptr<World> w = std::make_unique<World>();
    std::vector<int32_t> pieceBegin;
    int mat = w->addMaterial(Material());

    void add(int n, double size, double x, double y, double z) {
        TetMesh m = boxMesh(n, n, n, size, size, size, 6);
        for (std::size_t i = 0; i < m.nNodes(); ++i) {
            m.nodes[3 * i] += x;
            m.nodes[3 * i + 1] += y;
            m.nodes[3 * i + 2] += z;
        }
        w->addPiece(m, mat);
    }
    PartitionInput input() {
        pieceBegin.clear();
        for (const PieceInfo& p : w->pieces) pieceBegin.push_back(p.nodeBegin);
        pieceBegin.push_back(w->pieces.empty() ? 0 : w->pieces.back().nodeEnd);
        PartitionInput in;
        in.nNodes = static_cast<int32_t>(w->pos.size() / 3);
        in.nTets = static_cast<int32_t>(w->tetNodes.size() / 4);
        in.pos = w->pos.data();
        in.tetNodes = w->tetNodes.data();
        in.nPieces = static_cast<int32_t>(w->pieces.size());
        in.pieceNodeBegin = pieceBegin.data();
        return in;
    }
    std::vector<Halo> halos(const Partition& p, const PartitionInput& in, double reach) {
        return haloAll(p, in, w->surfNodes.data(), static_cast<int32_t>(w->surfNodes.size()), reach);
    }
};

// n^3 equal cubes of m^3 cells, side 1, gap 0.1.
std::unique_ptr<Scene> cubes(int n, int m) {
    auto s = std::make_unique<Scene>();
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) s->add(m, 1.0, 1.1 * i, 1.1 * j, 1.1 * k);
    return s;
}

PartitionOptions ranks(int n) {
    PartitionOptions o;
    o.nRanks = n;
    return o;
}

// Every node and tet has one owner in range, a tet's owner is the lowest of
// its nodes', the weights are the owned tets.
void checkOwnership(const Partition& p, const PartitionInput& in, int P) {
    ASSERT_EQ(p.nRanks, P);
    ASSERT_EQ(p.nodeOwner.size(), std::size_t(in.nNodes));
    ASSERT_EQ(p.tetOwner.size(), std::size_t(in.nTets));
    ASSERT_EQ(p.rankWeight.size(), std::size_t(P));
    ASSERT_EQ(p.keyStart.size(), std::size_t(P + 1));
    for (int32_t o : p.nodeOwner) ASSERT_TRUE(o >= 0 && o < P);
    std::vector<double> tets(P, 0.0);
    for (int32_t t = 0; t < in.nTets; ++t) {
        int32_t lowest = P;
        for (int k = 0; k < 4; ++k) lowest = std::min(lowest, p.nodeOwner[in.tetNodes[4 * t + k]]);
        ASSERT_EQ(p.tetOwner[t], lowest);
        tets[lowest] += 1;
    }
    for (int r = 0; r < P; ++r) EXPECT_EQ(p.rankWeight[r], tets[r]) << r;
    for (int r = 0; r < P; ++r) EXPECT_LE(p.keyStart[r], p.keyStart[r + 1]) << r;
}

// Halos: each node and tet listed once over all ranks, lists ascending,
// send[r][s] == recv[s][r], a ghost never owned by its reader, every node of
// an owned tet owned or a ghost.
void checkHalos(const Partition& p, const PartitionInput& in, const std::vector<Halo>& hs) {
    const int P = p.nRanks;
    ASSERT_EQ(hs.size(), std::size_t(P));
    std::vector<int> nodeSeen(in.nNodes, 0), tetSeen(in.nTets, 0);
    std::size_t nodeSum = 0, tetSum = 0;
    for (int r = 0; r < P; ++r) {
        const Halo& h = hs[r];
        ASSERT_EQ(h.rank, r);
        EXPECT_TRUE(std::is_sorted(h.ownedNodes.begin(), h.ownedNodes.end()));
        EXPECT_TRUE(std::is_sorted(h.ownedTets.begin(), h.ownedTets.end()));
        for (int32_t n : h.ownedNodes) {
            ++nodeSeen[n];
            ASSERT_EQ(p.nodeOwner[n], r);
        }
        for (int32_t t : h.ownedTets) {
            ++tetSeen[t];
            ASSERT_EQ(p.tetOwner[t], r);
        }
        nodeSum += h.ownedNodes.size();
        tetSum += h.ownedTets.size();
        ASSERT_EQ(h.recv.size(), h.neighbours.size());
        ASSERT_EQ(h.send.size(), h.neighbours.size());
        EXPECT_TRUE(std::adjacent_find(h.neighbours.begin(), h.neighbours.end(), std::greater_equal<int>()) ==
                    h.neighbours.end());
        std::vector<char> ghost(in.nNodes, 0);
        std::size_t nGhosts = 0;
        for (std::size_t i = 0; i < h.neighbours.size(); ++i) {
            const int s = h.neighbours[i];
            EXPECT_NE(s, r);
            EXPECT_FALSE(h.recv[i].empty() && h.send[i].empty());
            EXPECT_TRUE(std::adjacent_find(h.recv[i].begin(), h.recv[i].end(), std::greater_equal<int32_t>()) ==
                        h.recv[i].end());
            for (int32_t n : h.recv[i]) {
                EXPECT_EQ(p.nodeOwner[n], s);
                ghost[n] = 1;
            }
            for (int32_t n : h.send[i]) EXPECT_EQ(p.nodeOwner[n], r);
            nGhosts += h.recv[i].size();
            // symmetry
            const Halo& o = hs[s];
            const auto it = std::find(o.neighbours.begin(), o.neighbours.end(), r);
            ASSERT_TRUE(it != o.neighbours.end()) << r << " " << s;
            const std::size_t j = it - o.neighbours.begin();
            EXPECT_EQ(h.send[i], o.recv[j]) << r << " -> " << s;
            EXPECT_EQ(h.recv[i], o.send[j]) << s << " -> " << r;
        }
        EXPECT_EQ(h.nGhosts(), nGhosts);
        for (int32_t t : h.ownedTets)
            for (int k = 0; k < 4; ++k) {
                const int32_t n = in.tetNodes[4 * t + k];
                EXPECT_TRUE(p.nodeOwner[n] == r || ghost[n]) << "tet " << t << " node " << n << " rank " << r;
            }
    }
    EXPECT_EQ(nodeSum, std::size_t(in.nNodes));
    EXPECT_EQ(tetSum, std::size_t(in.nTets));
    for (int c : nodeSeen) ASSERT_EQ(c, 1);
    for (int c : tetSeen) ASSERT_EQ(c, 1);
}

// Hilbert keys as the partitioner takes them (the cube around the box, whole
// pieces at their centroid).
std::vector<uint64_t> curveKeys(const PartitionInput& in, const std::vector<char>& whole) {
    double lo[3], hi[3], side = 0, blo[3], bhi[3];
    for (int d = 0; d < 3; ++d) blo[d] = 1e300, bhi[d] = -1e300;
    for (int32_t n = 0; n < in.nNodes; ++n)
        for (int d = 0; d < 3; ++d) blo[d] = std::min(blo[d], in.pos[3 * n + d]), bhi[d] = std::max(bhi[d], in.pos[3 * n + d]);
    for (int d = 0; d < 3; ++d) side = std::max(side, bhi[d] - blo[d]);
    for (int d = 0; d < 3; ++d) lo[d] = 0.5 * (blo[d] + bhi[d]) - 0.5 * side, hi[d] = 0.5 * (blo[d] + bhi[d]) + 0.5 * side;
    std::vector<uint64_t> key(in.nNodes);
    for (int32_t n = 0; n < in.nNodes; ++n) key[n] = hilbertKey(in.pos + 3 * n, lo, hi);
    for (int32_t q = 0; q < in.nPieces; ++q) {
        if (!whole[q]) continue;
        double c[3] = {0, 0, 0};
        const int32_t b = in.pieceNodeBegin[q], e = in.pieceNodeBegin[q + 1];
        for (int32_t n = b; n < e; ++n)
            for (int d = 0; d < 3; ++d) c[d] += in.pos[3 * n + d];
        for (int d = 0; d < 3; ++d) c[d] /= (e - b);
        for (int32_t n = b; n < e; ++n) key[n] = hilbertKey(c, lo, hi);
    }
    return key;
}

void checkContiguous(const Partition& p, const PartitionInput& in, const std::vector<uint64_t>& key) {
    std::vector<int32_t> order(in.nNodes);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
    for (std::size_t j = 1; j < order.size(); ++j)
        ASSERT_LE(p.nodeOwner[order[j - 1]], p.nodeOwner[order[j]]) << j;
    for (int32_t n = 0; n < in.nNodes; ++n) {
        const int r = p.nodeOwner[n];
        EXPECT_LE(p.keyStart[r], key[n]);
        EXPECT_LE(key[n], p.keyStart[r + 1]);
    }
}

}  // namespace

TEST(Partition, BlockIsBalancedAndContiguousOnSeveralRanks) {
    Scene s;
    s.add(20, 1.0, 0, 0, 0);
    const PartitionInput in = s.input();
    for (int P : {2, 3, 4, 7}) {
        const Partition p = partitionHilbert(in, ranks(P));
        checkOwnership(p, in, P);
        EXPECT_LE(p.imbalance(), 1.05) << P;
        EXPECT_EQ(countSplitPieces(p, in), 1) << P;
        checkContiguous(p, in, curveKeys(in, {0}));
        checkHalos(p, in, s.halos(p, in, 0.0));
    }
}

TEST(Partition, OneRankOwnsEverythingWithoutHalo) {
    auto s = cubes(2, 3);
    const PartitionInput in = s->input();
    const Partition p = partitionHilbert(in, ranks(1));
    checkOwnership(p, in, 1);
    EXPECT_EQ(p.imbalance(), 1.0);
    const std::vector<Halo> hs = s->halos(p, in, 0.5);
    checkHalos(p, in, hs);
    EXPECT_EQ(hs[0].nGhosts(), 0u);
    EXPECT_TRUE(hs[0].neighbours.empty());
}

// 27 equal cubes: a cube is 1/27 of the work, under half of a share up to
// P = 13, so each is keyed whole; a cut lands inside one and moves to its
// nearer end when both sides stay within 5 %: with shares of 13.5, 9 and
// 6.75 cubes, moving a cut by up to half a cube (3.7 % of 13.5; 7.4 % of
// 6.75, where the farther end is taken instead: 7, 7, 6, 7 cubes) keeps them
// all whole at 3.7 % imbalance.
TEST(Partition, SmallCubesStayWhole) {
    auto s = cubes(3, 4);
    const PartitionInput in = s->input();
    for (int P : {2, 3, 4}) {
        const Partition p = partitionHilbert(in, ranks(P));
        checkOwnership(p, in, P);
        EXPECT_EQ(countSplitPieces(p, in), 0) << P;
        EXPECT_LE(p.imbalance(), 1.05) << P;
        if (P == 3) {
            EXPECT_EQ(p.imbalance(), 1.0);
        }
        checkContiguous(p, in, curveKeys(in, std::vector<char>(27, 1)));
        checkHalos(p, in, s->halos(p, in, 0.05));
    }
    // At 5 ranks the share is 5.4 cubes: 5 or 6 on a rank is 7.4 % off, so
    // the balance wins and cubes are split.
    const Partition p5 = partitionHilbert(in, ranks(5));
    EXPECT_GT(countSplitPieces(p5, in), 0);
    EXPECT_LE(p5.imbalance(), 1.05);
}

TEST(Partition, BigBlockIsSplitSmallCubesStayWhole) {
    Scene s;
    s.add(12, 2.0, 0, 0, 0);  // 10,368 tets
    for (int i = 0; i < 8; ++i) s.add(3, 0.4, -0.8 + 1.6 * (i & 1), -0.8 + 1.6 * ((i >> 1) & 1), 1.5);  // 162 each
    const PartitionInput in = s.input();
    for (int P : {2, 3, 4}) {
        const Partition p = partitionHilbert(in, ranks(P));
        checkOwnership(p, in, P);
        EXPECT_LE(p.imbalance(), 1.05) << P;
        EXPECT_EQ(countSplitPieces(p, in), 1) << P;  // the block, only
        const int32_t o = p.nodeOwner[in.pieceNodeBegin[0]];
        EXPECT_TRUE(std::any_of(p.nodeOwner.begin(), p.nodeOwner.begin() + in.pieceNodeBegin[1],
                                [&](int32_t x) { return x != o; }));
        std::vector<char> whole(9, 1);
        whole[0] = 0;
        checkContiguous(p, in, curveKeys(in, whole));
        checkHalos(p, in, s.halos(p, in, 0.1));
    }
}

TEST(Partition, SameInputSameSplit) {
    auto s = cubes(2, 5);
    s->add(10, 2.0, 3, 0, 0);
    const PartitionInput in = s->input();
    for (int P : {3, 5}) {
        const Partition a = partitionHilbert(in, ranks(P)), b = partitionHilbert(in, ranks(P));
        EXPECT_EQ(a.nodeOwner, b.nodeOwner);
        EXPECT_EQ(a.tetOwner, b.tetOwner);
        EXPECT_EQ(a.rankWeight, b.rankWeight);
        EXPECT_EQ(a.keyStart, b.keyStart);
        const std::vector<Halo> ha = s->halos(a, in, 0.2), hb = s->halos(b, in, 0.2);
        for (int r = 0; r < P; ++r) {
            EXPECT_EQ(ha[r].neighbours, hb[r].neighbours);
            EXPECT_EQ(ha[r].recv, hb[r].recv);
            EXPECT_EQ(ha[r].send, hb[r].send);
        }
    }
}

TEST(Partition, MoreRanksThanNodesLeavesSomeEmpty) {
    Scene s;
    s.add(1, 1.0, 0, 0, 0);  // 8 nodes, 6 tets
    const PartitionInput in = s.input();
    const Partition p = partitionHilbert(in, ranks(20));
    checkOwnership(p, in, 20);
    checkHalos(p, in, s.halos(p, in, 0.0));
    EXPECT_EQ(std::accumulate(p.rankWeight.begin(), p.rankWeight.end(), 0.0), 6.0);
    EXPECT_GT(std::count(p.rankWeight.begin(), p.rankWeight.end(), 0.0), 10);
}

TEST(Partition, FlatAndPointLikeBoxes) {
    // A block squashed flat (z = 0): keys use the other two axes.
    Scene s;
    s.add(12, 1.0, 0, 0, 0);
    PartitionInput in = s.input();
    std::vector<double> flat(in.pos, in.pos + 3 * in.nNodes);
    for (int32_t n = 0; n < in.nNodes; ++n) flat[3 * n + 2] = 0;
    in.pos = flat.data();
    for (int P : {3, 4}) {
        const Partition p = partitionHilbert(in, ranks(P));
        checkOwnership(p, in, P);
        EXPECT_LE(p.imbalance(), 1.05);
        checkHalos(p, in, s.halos(p, in, 0.0));
        const Partition q = partitionSlabs(in, ranks(P));
        checkOwnership(q, in, P);
        EXPECT_LE(q.imbalance(), 1.05);
    }
    // All nodes at one point: one key, the order is by node id.
    std::vector<double> point(3 * in.nNodes, 0.25);
    in.pos = point.data();
    const Partition p = partitionHilbert(in, ranks(4));
    checkOwnership(p, in, 4);
    EXPECT_LE(p.imbalance(), 1.05);
    EXPECT_TRUE(std::is_sorted(p.nodeOwner.begin(), p.nodeOwner.end()));
    checkHalos(p, in, haloAll(p, in, s.w->surfNodes.data(), int32_t(s.w->surfNodes.size()), 0.1));
}

TEST(Partition, SlabsBalanceAlongTheLongestAxis) {
    Scene s;
    s.add(10, 1.0, 0, 0, 0);
    s.add(10, 1.0, 1.2, 0, 0);
    s.add(10, 1.0, 2.4, 0, 0);
    const PartitionInput in = s.input();
    const Partition p = partitionSlabs(in, ranks(6));
    checkOwnership(p, in, 6);
    EXPECT_LE(p.imbalance(), 1.05);
    checkHalos(p, in, s.halos(p, in, 0.1));
    // Rank domains follow x: owners never decrease along it.
    std::vector<int32_t> order(in.nNodes);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return in.pos[3 * a] < in.pos[3 * b]; });
    for (std::size_t j = 1; j < order.size(); ++j)
        if (in.pos[3 * order[j - 1]] < in.pos[3 * order[j]]) {
            ASSERT_LE(p.nodeOwner[order[j - 1]], p.nodeOwner[order[j]]);
        }
}

TEST(Partition, ExtraWeightCountsInTheBalance) {
    Scene s;
    s.add(10, 1.0, 0, 0, 0);
    PartitionInput in = s.input();
    // Contact work on the surface nodes worth 2 tets each.
    std::vector<double> extra(in.nNodes, 0.0);
    for (std::size_t i = 0; i < s.w->surfNodes.size(); ++i) extra[s.w->surfNodes[i]] = 2.0;
    in.nodeExtraWeight = extra.data();
    const Partition p = partitionHilbert(in, ranks(4));
    const double total = in.nTets + 2.0 * s.w->surfNodes.size();
    EXPECT_DOUBLE_EQ(std::accumulate(p.rankWeight.begin(), p.rankWeight.end(), 0.0), total);
    EXPECT_LE(p.imbalance(), 1.05);
}

// Two cubes side by side, touching: with a reach, each rank reads the other
// cube's facing surface nodes (and only nodes that close); with none, the
// ranks share nothing.
TEST(Partition, ContactHaloReadsTheFacingSurface) {
    Scene s;
    s.add(4, 1.0, -0.5, 0, 0);
    s.add(4, 1.0, 0.5, 0, 0);
    const PartitionInput in = s.input();
    // A cube is a whole share: keyed whole only with the fraction raised.
    PartitionOptions opt = ranks(2);
    opt.wholePieceFraction = 1.0;
    const Partition p = partitionHilbert(in, opt);
    EXPECT_EQ(countSplitPieces(p, in), 0);
    EXPECT_EQ(p.imbalance(), 1.0);
    const int32_t split = in.pieceNodeBegin[1];
    const int a = p.nodeOwner[0], b = p.nodeOwner[split];
    ASSERT_NE(a, b);

    const std::vector<Halo> none = s.halos(p, in, 0.0);
    checkHalos(p, in, none);
    EXPECT_EQ(none[0].nGhosts() + none[1].nGhosts(), 0u);

    const double reach = 0.1;  // under the node spacing 0.25: the facing layer only
    const std::vector<Halo> hs = s.halos(p, in, reach);
    checkHalos(p, in, hs);
    auto facing = [&](int32_t begin, int32_t end) {
        std::vector<int32_t> f;
        for (int32_t n = begin; n < end; ++n)
            if (std::abs(in.pos[3 * n]) < 1e-12) f.push_back(n);
        return f;
    };
    const std::vector<int32_t> faceA = facing(0, split), faceB = facing(split, in.nNodes);
    EXPECT_EQ(faceA.size(), 25u);
    ASSERT_EQ(hs[a].neighbours, std::vector<int>{b});
    EXPECT_EQ(hs[a].recv[0], faceB);
    EXPECT_EQ(hs[a].send[0], faceA);
    EXPECT_EQ(hs[b].recv[0], faceA);
}

// The model computes halos for a sample of ranks: each must equal the one
// computed with all ranks (the send lists need every rank's reads).
TEST(Partition, HalosOfSomeRanksEqualTheirsAmongAll) {
    auto s = cubes(3, 3);
    s->add(9, 3.0, 1.1, 1.1, -2.2);
    const PartitionInput in = s->input();
    const Partition p = partitionHilbert(in, ranks(9));
    const std::vector<Halo> all = s->halos(p, in, 0.15);
    checkHalos(p, in, all);
    const std::vector<int> some = {1, 4, 8};
    const std::vector<Halo> part =
        haloOf(p, in, s->w->surfNodes.data(), static_cast<int32_t>(s->w->surfNodes.size()), 0.15, some);
    ASSERT_EQ(part.size(), some.size());
    for (std::size_t i = 0; i < some.size(); ++i) {
        const Halo &a = part[i], &b = all[some[i]];
        EXPECT_EQ(a.rank, b.rank);
        EXPECT_EQ(a.ownedNodes, b.ownedNodes);
        EXPECT_EQ(a.ownedTets, b.ownedTets);
        EXPECT_EQ(a.neighbours, b.neighbours);
        EXPECT_EQ(a.recv, b.recv);
        EXPECT_EQ(a.send, b.send);
    }
    // elementHalo: the same without the contact reads.
    const std::vector<Halo> noContact = s->halos(p, in, 0.0);
    for (int r : some) {
        const Halo e = elementHalo(p, in, r);
        EXPECT_EQ(e.neighbours, noContact[r].neighbours);
        EXPECT_EQ(e.recv, noContact[r].recv);
        EXPECT_EQ(e.send, noContact[r].send);
    }
    size_t contactGhosts = 0, elementGhosts = 0;
    for (int r = 0; r < 9; ++r) contactGhosts += all[r].nGhosts(), elementGhosts += noContact[r].nGhosts();
    EXPECT_GT(contactGhosts, elementGhosts);
}

// yade.mpy's master owns no node (PartitionOptions::firstRank): the split over
// P ranks from rank 1 is the split over P - 1 ranks, renumbered; rank 0 has
// no weight, no tet, no ghost, and the imbalance counts only the others.
TEST(Partition, RanksBelowFirstRankOwnNothing) {
    auto s = cubes(3, 3);
    const PartitionInput in = s->input();
    for (int P : {2, 3, 4}) {
        const Partition ref = partitionHilbert(in, ranks(P - 1));
        Partition p = partitionHilbert(in, ranks(P - 1));
        shiftRanks(p, 1);
        checkOwnership(p, in, P);
        for (std::size_t n = 0; n < p.nodeOwner.size(); ++n) ASSERT_EQ(p.nodeOwner[n], ref.nodeOwner[n] + 1);
        for (std::size_t t = 0; t < p.tetOwner.size(); ++t) ASSERT_EQ(p.tetOwner[t], ref.tetOwner[t] + 1);
        EXPECT_EQ(p.rankWeight[0], 0.0);
        EXPECT_EQ(p.imbalance(), ref.imbalance()) << P;
        const std::vector<Halo> hs = s->halos(p, in, 0.5);
        checkHalos(p, in, hs);
        EXPECT_TRUE(hs[0].ownedNodes.empty() && hs[0].ownedTets.empty() && hs[0].nGhosts() == 0u);
    }
}
