// How QDEM's nodes and tetrahedra are split across MPI ranks (the seed's
// §4.3, doc/parallel.md): along the Hilbert curve of the global box, into
// contiguous key ranges of equal weight.  Pure data and geometry: no MPI here,
// so every rank computes the same split from the same (replicated) set-up,
// and the scaling model runs the very same code for 16,384 ranks on one core.
#pragma once
#include <cstdint>
#include <vector>

namespace qdem {

// What the partitioner reads: the nodes and tets of all pieces in the world's
// global numbering (World.hpp).  Pointers, not copies: the arrays are large.
struct PartitionInput {
    int32_t nNodes = 0, nTets = 0;
    const double* pos = nullptr;        // 3 per node (current positions)
    const int32_t* tetNodes = nullptr;  // 4 per tet
    int32_t nPieces = 0;
    const int32_t* pieceNodeBegin = nullptr;  // nPieces + 1: piece p owns nodes [begin[p], begin[p+1])
    // Extra work per node on top of its elements (contact work measured per
    // surface node, in units of one tet); nullptr: none.
    const double* nodeExtraWeight = nullptr;
};

struct PartitionOptions {
    int nRanks = 1;
    // A piece whose weight is at most this fraction of one rank's share is
    // keyed as a whole (all its nodes at its centroid's key) and a cut that
    // falls inside it is moved to its nearer end (else its farther one) when
    // the ranks on either side stay within `tolerance` above the share: small
    // pieces stay whole where balance allows, big ones are split along the
    // curve.  So no rank exceeds (1 + tolerance) x its share because of a
    // whole piece.
    double wholePieceFraction = 0.5;
    double tolerance = 0.05;
    // Ranks below this one own nothing: the split is made over the others
    // (shiftRanks).  Under yade.mpy its master, rank 0, holds the walls and
    // no spheres, so QDEM's nodes go to the workers only (doc/parallel.md).
    int firstRank = 0;
};

struct Partition {
    int nRanks = 1;
    std::vector<int32_t> nodeOwner;  // per node: its rank
    std::vector<int32_t> tetOwner;   // per tet: the rank computing it (the lowest owner of its nodes)
    std::vector<double> rankWeight;  // per rank: tets + extra weight it owns
    std::vector<uint64_t> keyStart;  // per rank + 1: the key range [keyStart[r], keyStart[r+1]) (diagnostics)
    int firstRank = 0;               // ranks below own nothing (PartitionOptions::firstRank)

    double imbalance() const;  // max / mean of rankWeight over the ranks from firstRank (1 = perfect)
};

// Renumbers a split made over nRanks ranks as ranks first .. first+nRanks-1,
// ranks 0 .. first-1 owning nothing (PartitionOptions::firstRank).
void shiftRanks(Partition& p, int first);

// The weighted Hilbert split.  Deterministic: the same input gives the same
// split on every rank (ties broken by node id).  O(N log N) (one sort).
// The key is taken in the cube around the nodes' box, so a long box does not
// stretch the curve; flat boxes and nodes all at one point are fine (equal
// keys: the order is then by node id).  Each tet's weight goes to its node
// that comes first on the curve (whose owner is the tet's lowest owner), so
// the weight between two cuts is exactly the tets the rank will own: the
// balance is exact to one node's weight, except where a small piece is kept
// whole (then within `tolerance`).  More ranks than nodes, or than the
// weight can feed, leave some ranks empty (no nodes, weight 0): legal.
Partition partitionHilbert(const PartitionInput& in, const PartitionOptions& opt);
// Slabs of equal weight along the longest axis of the box (for comparison):
// the same engine with the coordinate on that axis as the key.
Partition partitionSlabs(const PartitionInput& in, const PartitionOptions& opt);
// Pieces whose nodes have more than one owner.
int32_t countSplitPieces(const Partition& p, const PartitionInput& in);

// One rank's view of a partition: which of its nodes others read (sent
// forward each step) and which of theirs it reads (ghosts).  Lists are per
// neighbour rank, neighbours ascending, node ids ascending in each list; the
// relation is symmetric: send[r][s] == recv[s][r].  recv[i] and send[i]
// belong to neighbours[i]; one of them may be empty (element reads go one
// way: a tet is computed by the lowest owner of its nodes).
struct Halo {
    int rank = 0;
    std::vector<int32_t> ownedNodes;  // ascending
    std::vector<int32_t> ownedTets;   // ascending
    std::vector<int> neighbours;      // ascending
    std::vector<std::vector<int32_t>> recv;  // per neighbour: ghost nodes owned by it that this rank reads
    std::vector<std::vector<int32_t>> send;  // per neighbour: owned nodes it reads
    std::size_t nGhosts() const;
};

// The element halo of rank r: ghosts are the nodes of r's tets owned by other
// ranks (each tet is computed once, by its owner; partial forces on ghosts go
// back to their owners, their positions and velocities come forward).
// Element reads only: contact ghosts depend on every rank's surface, so
// they come with haloAll / haloOf (the send lists follow from all ranks'
// reads).  O(nTets + nNodes).
Halo elementHalo(const Partition& p, const PartitionInput& in, int rank);
// The halos of all ranks at once (what the model and the tests use), with a
// contact halo: every surface node of another rank and another piece within
// `contactReach` [m] of a surface node rank r owns is also a ghost of r (0:
// none; nodes of one piece never touch each other, PieceContactPhase).
// surfNodes: the surface node ids (nSurf of them).  The contact search is a
// cell grid of side contactReach: O(nSurf) for a bounded surface density.
std::vector<Halo> haloAll(const Partition& p, const PartitionInput& in, const int32_t* surfNodes, int32_t nSurf,
                          double contactReach);
// The same for some ranks only (ascending, distinct), each halo complete and
// exact (what the model uses at thousands of ranks): one pass over the tets
// and the surface, the sorting limited to reads involving those ranks.
std::vector<Halo> haloOf(const Partition& p, const PartitionInput& in, const int32_t* surfNodes, int32_t nSurf,
                         double contactReach, const std::vector<int>& ranks);

}  // namespace qdem
