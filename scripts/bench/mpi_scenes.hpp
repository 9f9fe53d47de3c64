// The synthetic scenes of the MPI partition benchmarks (doc/parallel_scaling.md) and
// the halo figures they report, shared by mpi_partition_model (our Hilbert
// split against slabs) and mpi_zoltan_compare (against Zoltan), so both
// measure the same scenes the same way.
//
// Scenes:
//   pieces  shogi-size boxes (12x10x4 cells, 715 nodes, 2,880 tets;
//           32 x 28 x 9.7 mm) on a grid 0.5 mm apart, like a heap
//   body    one block meshed as a whole
//   mixed   a block with half the nodes, the pieces on top of it
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh/BoxMesh.hpp"
#include "parallel/Partition.hpp"

namespace mpibench {

using qdem::boxMesh;
using qdem::Halo;
using qdem::PartitionInput;
using qdem::TetMesh;

struct RawScene {
    std::vector<double> pos;
    std::vector<int32_t> tets, pieceBegin{0}, surf;

    PartitionInput input() const {
        PartitionInput in;
        in.nNodes = static_cast<int32_t>(pos.size() / 3);
        in.nTets = static_cast<int32_t>(tets.size() / 4);
        in.pos = pos.data();
        in.tetNodes = tets.data();
        in.nPieces = static_cast<int32_t>(pieceBegin.size()) - 1;
        in.pieceNodeBegin = pieceBegin.data();
        return in;
    }
    int32_t nNodes() const { return static_cast<int32_t>(pos.size() / 3); }

    // Appends mesh m shifted by (x, y, z) as one piece; its surface nodes
    // are those on the faces of its box (the mesh is a box).
    void add(const TetMesh& m, const std::vector<int32_t>& surfOfM, double x, double y, double z) {
        const int32_t base = nNodes();
        for (std::size_t i = 0; i < m.nNodes(); ++i) {
            pos.push_back(m.nodes[3 * i] + x);
            pos.push_back(m.nodes[3 * i + 1] + y);
            pos.push_back(m.nodes[3 * i + 2] + z);
        }
        for (int32_t t : m.tets) tets.push_back(t + base);
        for (int32_t n : surfOfM) surf.push_back(n + base);
        pieceBegin.push_back(nNodes());
    }
};

inline std::vector<int32_t> boxSurface(const TetMesh& m) {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (std::size_t i = 0; i < m.nNodes(); ++i)
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], m.nodes[3 * i + d]), hi[d] = std::max(hi[d], m.nodes[3 * i + d]);
    std::vector<int32_t> s;
    for (std::size_t i = 0; i < m.nNodes(); ++i) {
        bool on = false;
        for (int d = 0; d < 3; ++d) {
            const double eps = 1e-9 * (hi[d] - lo[d]);
            on = on || m.nodes[3 * i + d] < lo[d] + eps || m.nodes[3 * i + d] > hi[d] - eps;
        }
        if (on) s.push_back(static_cast<int32_t>(i));
    }
    return s;
}

constexpr double kPieceX = 0.032, kPieceY = 0.028, kPieceZ = 0.0097, kGap = 0.0005;

// How n shogi-size pieces are heaped: a grid of cells the piece's size plus
// the gap, ~3 times more layers than the pieces' aspect alone would give, so
// the heap is about as tall as it is wide.
struct Heap {
    int64_t nx, ny, nz, perLayer;
    explicit Heap(int64_t n) {
        nz = std::max<int64_t>(1, std::llround(std::cbrt(double(n) * 9.0)));
        perLayer = (n + nz - 1) / nz;
        nx = std::max<int64_t>(1, std::llround(std::ceil(std::sqrt(double(perLayer)))));
        ny = (perLayer + nx - 1) / nx;
    }
    // Footprint: from -half a piece to the far edge.
    double width() const { return nx * (kPieceX + kGap) - kGap; }
    double depth() const { return ny * (kPieceY + kGap) - kGap; }
};

// n pieces heaped with their bottom at height z0.
inline void addPieces(RawScene& s, int64_t n, double z0) {
    const TetMesh m = boxMesh(12, 10, 4, kPieceX, kPieceY, kPieceZ, 6);
    const std::vector<int32_t> surf = boxSurface(m);
    const Heap h(n);
    for (int64_t i = 0; i < n; ++i) {
        const int64_t k = i / h.perLayer, r = i % h.perLayer;
        s.add(m, surf, (r % h.nx) * (kPieceX + kGap), (r / h.nx) * (kPieceY + kGap),
              z0 + 0.5 * kPieceZ + k * (kPieceZ + kGap));
    }
}

// One block of about `nodes` nodes in cubic cells of the pieces' cell size,
// its top at z = 0: a cube, or (width > 0) a slab of that footprint under
// the heap of pieces.
inline void addBlock(RawScene& s, int64_t nodes, double width, double depth) {
    const double h = kPieceX / 12;
    int ax, ay, az;
    if (width > 0) {
        ax = std::max(1, int(std::llround(width / h)));
        ay = std::max(1, int(std::llround(depth / h)));
        az = std::max(1, int(nodes / (int64_t(ax + 1) * (ay + 1))) - 1);
    } else {
        ax = ay = az = std::max(1, int(std::llround(std::cbrt(double(nodes)))) - 1);
    }
    const TetMesh m = boxMesh(ax, ay, az, ax * h, ay * h, az * h, 6);
    s.add(m, boxSurface(m), 0.5 * (ax * h - kPieceX), 0.5 * (ay * h - kPieceY), -0.5 * az * h);
}

constexpr int64_t kPieceNodes = 13 * 11 * 5;

inline RawScene makeScene(const std::string& kind, int P, int64_t nodesPerRank) {
    RawScene s;
    const int64_t nodes = int64_t(P) * nodesPerRank;
    if (kind == "pieces") addPieces(s, std::max<int64_t>(1, nodes / kPieceNodes), 0.0);
    if (kind == "body") addBlock(s, nodes, 0, 0);
    if (kind == "mixed") {
        const int64_t nPieces = std::max<int64_t>(1, nodes / 2 / kPieceNodes);
        const Heap heap(nPieces);
        addBlock(s, nodes / 2, heap.width(), heap.depth());
        addPieces(s, nPieces, kGap);
    }
    return s;
}

// Per-rank communication figures of some halos: halo size over owned nodes
// (mean over the non-empty ranks, max), neighbours, and bytes each rank sends
// and receives per step (forward: position and velocity, 6 doubles per
// ghost; reverse: the ghost's partial force, 3 doubles).
struct HaloFigures {
    double haloMean = 0, haloMax = 0, nbrMean = 0;
    int nbrMax = 0;
    double sendMean = 0, sendMax = 0, recvMax = 0;  // bytes per step per rank
};

inline HaloFigures haloFigures(const std::vector<Halo>& hs) {
    HaloFigures f;
    int counted = 0;
    for (const Halo& h : hs) {
        std::size_t nSend = 0;
        for (const auto& l : h.send) nSend += l.size();
        const double ghosts = double(h.nGhosts());
        const double sent = 48.0 * nSend + 24.0 * ghosts, received = 48.0 * ghosts + 24.0 * nSend;
        f.sendMean += sent;
        f.sendMax = std::max(f.sendMax, sent);
        f.recvMax = std::max(f.recvMax, received);
        f.nbrMean += double(h.neighbours.size());
        f.nbrMax = std::max(f.nbrMax, int(h.neighbours.size()));
        if (h.ownedNodes.empty()) continue;  // an empty rank has no ratio
        const double ratio = ghosts / double(h.ownedNodes.size());
        f.haloMean += ratio;
        f.haloMax = std::max(f.haloMax, ratio);
        ++counted;
    }
    f.sendMean /= std::max<std::size_t>(1, hs.size());
    f.nbrMean /= std::max<std::size_t>(1, hs.size());
    f.haloMean /= std::max(1, counted);
    return f;
}

}  // namespace mpibench
