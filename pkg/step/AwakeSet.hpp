// The awake set (doc/sleeping.md): which pieces sleep, and the awake
// pieces' tets, nodes and surface nodes that the phases loop over.  Data,
// written by one phase only (SleepPhase, the friend below; it also decides
// which pieces are rigid) and read by every
// other through a const reference: the obstacle, piece-contact, element and
// integration phases, the viscous solve, the contact forces and the piece
// boxes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../parallel/ThreadLayout.hpp"

namespace qdem {

class SleepPhase;

class AwakeSet {
public:
    bool asleep(std::size_t piece) const { return piece < asleep_.size() && asleep_[piece]; }
    // Not dynamic (YADE's Body.dynamic = False): asleep until made dynamic.
    bool dynamic(std::size_t piece) const { return piece >= held_.size() || !held_[piece]; }
    long nAsleep() const { return nAsleep_; }
    long version() const { return version_; }  // bumped whenever the awake set changes
    // Every tet, node and surface node is in the awake set (nothing asleep,
    // no MPI domain): phases then loop over all of them without the lists.
    bool everything() const { return everything_; }
    const std::vector<TetSegment>& awakeTets() const { return awakeTets_; }  // per awake piece, its tets
    const std::vector<int32_t>& awakeNodes() const { return awakeNodes_; }   // ids of their nodes
    const std::vector<int32_t>& awakeSurf() const { return awakeSurf_; }     // indices into surfNodes
    // The surface nodes whose obstacle contacts are computed: the awake
    // pieces' (awakeSurf) and then the held pieces', which touch obstacles
    // as a fixed body (ObstaclePhase.cpp).  Indices into surfNodes; under
    // MPI the owned ones.
    const std::vector<int32_t>& obstacleSurf() const { return obstacleSurf_; }
    // Squared displacement of a piece's surface since the Verlet lists in
    // force when it fell asleep were built (other nodes may only move the
    // rest of half the skin before the lists are rebuilt).  The lists'
    // owner takes it as 0 once it has rebuilt them since the piece's last
    // change (changes()).
    double moved2(std::size_t piece) const { return moved2_[piece]; }
    // How many times the piece fell asleep or woke: a reader that keeps
    // per-piece state about sleep (the piece-contact phase's frozen pieces
    // and triangle normals) compares it with the count it last saw.
    uint32_t changes(std::size_t piece) const { return changes_[piece]; }
    // (obstacle index, F, T) x 7 per obstacle a sleeping piece pushed on when it fell asleep.
    const std::vector<double>& frozenReaction(std::size_t piece) const { return frozenReaction_[piece]; }
    // Adaptive rigidity (settings.rigidify): a rigid piece is awake for the
    // contacts (its surface nodes are in awakeSurf and obstacleSurf) but has
    // no tets in awakeTets and no nodes in awakeNodes: the integration moves
    // it as a rigid body (RigidBodies.hpp).  Never asleep and rigid at once.
    bool rigid(std::size_t piece) const { return piece < rigid_.size() && rigid_[piece]; }
    // Awake and deformable: its elements and viscous forces are computed.
    bool deformable(std::size_t piece) const { return !asleep(piece) && !rigid(piece); }
    long nRigid() const { return nRigid_; }
    const std::vector<int32_t>& rigidPieces() const { return rigidPieces_; }  // ids of the rigid pieces

private:
    friend class SleepPhase;  // the one writer
    std::vector<uint8_t> asleep_;
    std::vector<uint8_t> held_;
    std::vector<double> moved2_;
    std::vector<uint32_t> changes_;
    std::vector<std::vector<double>> frozenReaction_;
    std::vector<uint8_t> rigid_;
    std::vector<int32_t> rigidPieces_;
    long nRigid_ = 0;
    long nAsleep_ = 0;
    bool everything_ = true;
    long version_ = 0;
    std::vector<TetSegment> awakeTets_;
    std::vector<int32_t> awakeNodes_, awakeSurf_;
    std::vector<int32_t> obstacleSurf_;
};

}  // namespace qdem
