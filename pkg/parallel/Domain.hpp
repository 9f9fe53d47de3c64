// This rank's share of the world under MPI (doc/parallel.md): which nodes
// and tets it owns (Partition.hpp: a weighted Hilbert split that every rank
// computes alike from the replicated set-up), its halo, and the three
// exchanges of a step:
//   after the force phases  - partial forces on ghost nodes go to their
//                             owners (summed there in rank order);
//   after integration       - owned positions and velocities go forward to
//                             the ranks that read them as ghosts;
//   at the end of the step  - one gather of the step's globals: obstacle
//                             reactions, energies, and the error status, so
//                             an error on one rank stops every rank with its
//                             message instead of leaving them waiting.
// Storage stays at the world's full size on every rank (the script builds
// the whole scene everywhere); only owned and ghost entries are current, the
// rest are stale until gatherAll().
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ThreadLayout.hpp"
#include "Communicator.hpp"
#include "Partition.hpp"

namespace qdem {

class World;

// The split over nRanks ranks, those below opt.firstRank owning nothing.
Partition splitWorld(const PartitionInput& in, PartitionOptions opt, int nRanks);

class Domain {
public:
    Domain(World& w, std::shared_ptr<Communicator> comm);
    int rank() const { return comm_->rank(); }
    int size() const { return comm_->size(); }
    Communicator& comm() { return *comm_; }

    // The partitioner's input for the world as it stands: current positions,
    // and the contact work of the last step (pieceBegin and extra hold storage).
    static PartitionInput partitionInput(World& w, std::vector<int32_t>& pieceBegin, std::vector<double>& extra);
    // Splits the world as it stands (all pieces added) and builds the halo.
    void build(const PartitionOptions& opt);
    bool built() const { return built_; }
    bool everBuilt() const { return everBuilt_; }
    void invalidate() { built_ = false; }

    const Partition& partition() const { return part_; }
    const Halo& halo() const { return halo_; }
    bool owns(int32_t node) const { return part_.nodeOwner[node] == rank(); }
    // Per piece, its owned tets as runs [t0, t1) (what the element phase computes).
    void ownedTetRuns(int32_t piece, std::vector<TetSegment>& out) const;
    bool ownsTet(int32_t tet) const { return part_.tetOwner[tet] == rank(); }

    // ---- the step's exchanges ----------------------------------------------
    // Partial forces on ghosts (element buffers of `layout`, plus contact
    // forces when `contacts`) to their owners; ghostForce() then holds, for
    // owned nodes, the sum of what the other ranks computed (0 elsewhere).
    // With `contactLoad` (2 per surface node: the piece contacts' stiffness
    // and dashpot on it, PieceContactPhase::mpiNodeLoad) the ghosts' loads go
    // in the same messages and are added to the owners' rows.
    void returnGhostForces(const ThreadLayout& layout, const double* contactForce, bool contacts,
                           double* contactLoad = nullptr);
    const double* ghostForce() const { return ghostForce_.data(); }
    // Owned positions and velocities forward to the ghosts that read them.
    void sendStates();
    // ---- the implicit viscous solve's exchanges (ViscousSolve.cpp) -----------
    // A nodal field (3 per node) forward from the owned nodes to the element
    // ghosts that read it: the search direction C is applied to.
    void forwardField(double* field);
    // The partial sums `layout`'s thread buffers hold for element ghosts go
    // to their owners, which add them to `field` on their nodes in neighbour
    // (= rank) order, after their own tets' sum: C p on the owned nodes.
    void returnPartials(const ThreadLayout& layout, double* field);
    // v[0..n) summed over the ranks in rank order (every rank's partial sums
    // gathered, then added 0..P-1 on every rank): the same bits everywhere,
    // whatever a reduction tree would do, so every rank takes the same
    // decisions (the conjugate gradients' iteration count).  Collective.
    void sumInRankOrder(double* v, int n);
    // The contact halo (when pieces may touch): every rank's box of owned
    // surface nodes is gathered; to each rank whose box, grown by the contact
    // halo width, reaches this rank's, go the owned surface nodes within that
    // width of its box, ids with states.  Width: twice the largest particle
    // radius (node-face and edge-edge reach) plus two of the longest surface
    // edges now (a triangle or edge within reach, and its neighbour faces, is
    // then whole on the reading rank).  Renewed every step: no skin to trust.
    void sendContactHalo();
    bool contactHalo() const { return contactHalo_; }
    // YADE spheres coupled (World::spheres): the contact halo on, at least
    // as wide as their largest radius asks (sendContactHalo).  Collective;
    // every rank decides alike, the spheres being the same everywhere.
    void ensureSphereHalo();
    // Every rank's copy of YADE must hold the same obstacles and coupled
    // spheres in the same states (they size the step's reductions, and each
    // rank applies the same forces to its copy), and step with the same dt,
    // gravity, settings and materials (each rank integrates its own nodes
    // by them): checked at the start of every step by one reduction of a
    // hash each, refused on every rank naming what differs and the fix
    // (never a mismatched message).  Collective.
    void checkYadeAlike(double dt) const;

    // The collective operations a script reaches, for agreeOnCall.
    enum class Call : int { ScriptEnd = 0, Step = 1, GatherAll = 2, GatherState = 3, Rebalance = 4 };
    // Every rank must enter the same collective operation (a script that
    // steps or saves on some ranks only, inside `if rank == 0:`, or runs more
    // steps on one rank, left the others waiting for good): one reduction of
    // the call's id before it, refused on every rank naming the calls
    // otherwise.  Collective.
    void agreeOnCall(Call c) const;

    // Nodes whose state is current on this rank: owned, element ghosts and
    // contact ghosts.  version() changes whenever the set does (the contact
    // lists are then rebuilt: PieceContactPhase).
    bool current(int32_t node) const { return current_[node] != 0; }
    const std::vector<uint8_t>& currentMask() const { return current_; }
    long currentVersion() const { return currentVersion_; }
    // Surface nodes (indices into World::surfNodes) that are current.
    const std::vector<int32_t>& currentSurf() const { return currentSurf_; }
    // The rank that owns a node.
    int owner(int32_t node) const { return part_.nodeOwner[node]; }
    // The step's globals: obstacle reactions summed over ranks (each owner
    // added its nodes' pushes), energy totals, and the error agreement.
    void finishStep(const std::string& error);
    // This rank's load: owned tets + contactWork x contacts of the last step.
    double load() const;
    // max / mean of the ranks' loads at the end of the last step.
    double loadImbalance = 1;
    // Splits again from the current positions, the contact work of each
    // surface node weighing in; every state row (positions, velocities,
    // contact histories: Phase::stateColumns) goes from the rank that held
    // it to every rank first.  Collective.
    void rebalance(const PartitionOptions& opt);
    // Every state row (Phase::stateColumns: positions, velocities, contact
    // histories) from the rank that holds it true to every rank.  Collective.
    void gatherRows();
    long rebalances = 0;
    // Every rank learns every node's position and velocity (output, Python
    // reads, restarts): one gather of the owned nodes.
    void gatherAll();

    // The failing ranks' earliest message on every rank ("" when none
    // failed): of the lowest phase order, then of the lowest rank.  Messages
    // start with their kind, 'I' (InputError) or 'S' (any other), then the
    // order of the step phase that raised them ('0': outside the phases).
    std::string agree(const std::string& error);

    // Counted costs of the last step's halo (for doc/parallel.md).
    long stepBytes = 0, stepMessages = 0;
    double seconds = 0;  // wall time in exchanges last step [s]

private:
    void exchange(std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv);

    void markCurrent();
    void checkSameEverywhere(const PartitionInput& in) const;

    World& w_;
    std::shared_ptr<Communicator> comm_;
    bool contactHalo_ = false;
    double haloSphereRadius_ = 0;  // the sphere radius the contact halo was last made wide enough for
    double sphereRadius() const;   // the largest coupled sphere's radius (0: none)
    std::vector<uint8_t> current_, elementGhost_;
    std::vector<int32_t> currentSurf_;
    // Owned nodes the contact halo may send (global ids, ascending): the
    // surface nodes, and with the seed's broad phases the registered tets'.
    std::vector<int32_t> ownedSurf_;
    std::vector<int32_t> haloTets_;  // owned tets of the kind registered (seed's broad phases)
    long currentVersion_ = 0;
    // Contact halo: neighbours and, per neighbour, the ghosts received from it
    // and the owned nodes sent to it in the last sendContactHalo.
    std::vector<int> cNbr_, cNbrPrev_;
    std::vector<std::vector<int32_t>> cRecv_, cSend_;
    std::vector<std::vector<double>> cSendBuf_, cRecvBuf_;
    bool built_ = false, everBuilt_ = false;
    Partition part_;
    Halo halo_;
    std::vector<double> ghostForce_;
    std::vector<int32_t> ghostTouched_;  // nodes ghostForce_ holds values for
    std::vector<std::vector<double>> sendBuf_, recvBuf_;
    std::vector<double> gathered_;  // sumInRankOrder's P x n values
};

}  // namespace qdem
