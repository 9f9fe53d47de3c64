// The broad phase of the piece-piece contacts (seed paper §3-4; LAMMPS's
// Neighbor): which pieces can touch (sweep and prune on their boxes), the
// law's constants of each neighbour pair, and the lists the switched-on
// contact kinds declare (ContactKind.hpp Registration bits): surface
// triangles (or the seed's tetrahedra) in cell lists with each surface
// node's Verlet list, feature edges in box grids with each edge's Verlet
// list; with the per-thread force buffers and the triangles' normals.  It
// fills a PieceContactState, which the kinds read.  Rules: doc/contacts.md,
// "Verlet lists".
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../contact/ContactLaw.hpp"
#include "PieceContactData.hpp"
#include "PieceContactState.hpp"

namespace qdem {

class Domain;

class PieceBroadPhase {
public:
    PieceBroadPhase(const PieceContactData& w, PieceContactState& st) : w_(w), st_(st) {}
    // Neighbour pieces (CSR nbrStart/nbrs, pieceActive) and which pieces are
    // frozen (asleep with all neighbours asleep: their contacts are skipped);
    // false when no two pieces can touch (nothing else is built then).
    bool neighbours(std::vector<uint8_t>& frozen);
    // The rest of this step's lists, for the Registration bits `lists`.
    void build(unsigned lists);
    // A piece fell asleep or woke: its normals are stale, and its motion
    // before (AwakeSet::moved2) counts until the lists are rebuilt.
    void sleepChanged(std::size_t piece) { normalsFresh_[piece] = listsSinceSleep_[piece] = 0; }
    void piecesAdded(std::size_t nPieces) {
        normalsFresh_.resize(nPieces, 0);
        listsSinceSleep_.resize(nPieces, 0);
    }
    // A loaded state: the lists are rebuilt from its positions.
    void stateLoaded() {
        std::fill(normalsFresh_.begin(), normalsFresh_.end(), 0);
        st_.listValid = false;
    }

private:
    // This step's decisions, shared by the parts of build().
    struct Plan {
        std::size_t np;
        bool triLists, edgeLists;
        bool tetItems, allTets, verlet;
        double rMax, skin, grow;
        const Domain* dom;
        const uint8_t* cur;  // under MPI: the current nodes
        int spread;
        bool rebuild, edgeRebuild, registerNow, windowStart, finishWindow;
        double movedNow;
        double itemR = 0, edgeR = 0;  // largest registered item's radius, edge's length
    };
    void pairLaws();
    Plan plan(unsigned lists);
    void registerElements(Plan& pl);
    void packAndGrid(const Plan& pl, unsigned lists);
    void buffersAndNormals(const Plan& pl);
    void nodeLists(const Plan& pl);
    void edgeLists(const Plan& pl);

    PieceContactData w_;
    PieceContactState& st_;
    long listDomainVersion_ = -1;        // Domain::currentVersion the Verlet lists were built for
    std::vector<uint8_t> normalsFresh_;  // per piece: asleep, triangle normals computed since it stopped
    // Per piece: the Verlet lists were rebuilt since it fell asleep or woke
    // (its AwakeSet::moved2 then counts no more).
    std::vector<uint8_t> listsSinceSleep_;
    std::vector<PairConst> matPairLaw_;  // per step: the law's constants per pair of materials (a, b)
    std::vector<uint8_t> matPairDone_;   // and which of them this step has computed
};

}  // namespace qdem
