// Piece-piece surface contacts (seed paper §3-4): its broad phase
// (PieceBroadPhase: which pieces can touch, cell lists, Verlet lists), then
// the contact kinds of the table (ContactKind.hpp), each a class owning its
// history: point-polygon (PointPolygonKind), edge-edge (EdgeEdgeKind); then
// their per-thread forces summed into the nodes.  Derivations and rules:
// doc/contacts.md.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include <memory>
#include <string>
#include <utility>

#include <omp.h>

#include <algorithm>

#include "../step/Phase.hpp"
#include "ContactKind.hpp"
#include "ContactLoad.hpp"
#include "PieceBroadPhase.hpp"
#include "PieceContactData.hpp"
#include "PieceContactState.hpp"

namespace qdem {

class PieceContactPhase final : public Phase {
public:
    // What it reads and writes of the world (its kinds see the same).
    using Data = PieceContactData;
    // Makes one kernel per row of the contact-kinds table (ContactKind.hpp).
    explicit PieceContactPhase(const Data& data);
    const char* name() const override { return "pieceContacts"; }
    void run(double dt) override;
    // Its time split into broad phase (lists), point-polygon (with the sum of
    // the thread buffers) and edge-edge; contacts of each kind; cases A/B:
    // interior faces tested for nothing, and of them those within reach.
    void report(PhaseReport& r) const override;
    // Largest overlap of a piece-piece contact in the last step [m].
    double maxOverlap() const { return maxOverlap_; }
    // Largest depth of a contact's node (or edge crossing) behind the other
    // piece's surface, over its reach r_a + r_b, in the last step (0: none
    // behind).  Above 1 the run stops (checkContactDepth).
    double maxDepthRatio() const { return maxDepthRatio_; }
    // The stable step of the last step's contacts as they act on each node
    // with its piece's elements (ContactLoad.hpp): piece-piece contacts, and
    // the walls, boxes, facets and YADE spheres on the same nodes
    // (ContactForces::load, which every contact phase adds to); infinite
    // when none.  A step whose contacts make it below dt stops the run
    // (StabilityError).
    const ContactStepLimit& stepLimit() const { return stepLimit_; }
    // Refuses the step when stepLimit() is below dt (StabilityError naming
    // the node, its piece, its load and the fix).
    void checkStepLimit(double dt) const;
    // Serially, after the contact phases (World::step): the smallest limit
    // over the awake surface nodes' loads, refused below dt.
    void contactStepLimit(double dt);
    // Under MPI a rank sums only the contacts it computed: its share of each
    // current surface node's load.  Its shares go with the forces to the
    // nodes' owners (Domain::returnGhostForces), which add them to their
    // rows; then ownedStepLimit() takes this rank's smallest limit over the
    // nodes it owns, and the end-of-step reduction carries every rank's
    // (packStepLimit, kLimitValues per rank, no message of its own), so
    // every rank holds, reports and stops on the same node.
    void ownedStepLimit();
    static constexpr int kLimitValues = 6;
    void packStepLimit(double* v, int rank) const;
    void unpackStepLimit(const double* v, int nRanks);
    // Pieces placed pressed into each other, accepted by the start check:
    // the energy their springs hold and the speed it throws them apart at,
    // handed over once (QdemEngine warns).
    std::vector<std::string> takeStartWarnings() { return std::exchange(startWarnings_, {}); }
    void stateColumns(StateColumns& c) override;
    void piecesAdded() override;
    void stateLoaded() override;
    void saveFields(WorldState& s) const override;
    void checkFields(const WorldState& s) const override;
    void loadFields(const WorldState& s) override;

    // Read by the sleeping logic: neighbour pieces (CSR nbrStart/nbrs) and
    // the node positions of the last list rebuild.
    const PieceContactState& state() const { return st_; }
    // Asleep with all its neighbours asleep: its contacts were skipped this
    // step (and it has not woken or fallen asleep again since).
    bool frozen(std::size_t piece) const {
        return frozen_[piece] != 0 && sleepSeen_[piece] == w_.sleeping.changes(piece);
    }

    // What the kinds use of the phase (KindStep::phase).
    // The deepest contact of a thread in this step (see maxDepthRatio), and
    // the deepest of those past the reach that the per-step check judges:
    // depth of the node (edge crossing) behind the other surface, reach,
    // relative normal velocity (< 0 closing), which node and pieces.
    struct DeepContact {
        double ratio = 0;  // largest depth / reach of every contact
        double depth = 0, reach = 1, vn = 0;
        int32_t node = -1, pa = -1, pb = -1;
        bool edge = false;
    };
    // Called by the kinds for a contact whose node lies `depth` behind the
    // other piece's surface: keeps the thread's maxima (two compares; the
    // pair look-up only for the rare contact deeper than its reach).
    void noteDepth(DeepContact& d, double depth, double reach, double vn, int32_t node, int32_t pa, int32_t pb,
                   bool edge) const {
        const double ratio = depth / reach;
        if (ratio > d.ratio) d.ratio = ratio;
        if (ratio <= 1 || ratio * d.reach <= d.depth || !judged(pa, pb)) return;
        d.depth = depth, d.reach = reach, d.vn = vn, d.node = node, d.pa = pa, d.pb = pb, d.edge = edge;
    }
    DeepContact& threadDeep(int thread) { return threadDeep_[thread]; }
    // Per piece: asleep with all its neighbours asleep this step (its
    // contacts are skipped, their history kept: the kind stamps it).
    const uint8_t* frozenFlags() const { return frozen_.data(); }
    // The start check (PieceStartOverlap.cpp) runs this step: a kind that
    // sees a node inside another piece notes the pair (noteStartSeen), one
    // whose springs start pressed notes their energy (notePress); pairs of
    // two checked pieces (startChecked) are not noted.
    bool startPending() const { return startPending_; }
    const uint8_t* startCheckedFlags() const { return startChecked_.data(); }
    void noteStartSeen(int32_t pa, int32_t pb) {
        auto& seen = threadStartSeen_[omp_get_thread_num()];
        const std::pair<int32_t, int32_t> ab{std::min(pa, pb), std::max(pa, pb)};
        if (seen.empty() || seen.back() != ab) seen.push_back(ab);
    }
    void notePress(int32_t pa, int32_t pb, double energy, double overlap) {
        auto& v = threadStartPress_[omp_get_thread_num()];
        const int32_t a = std::min(pa, pb), b = std::max(pa, pb);
        if (v.empty() || v.back().a != a || v.back().b != b) v.push_back({a, b, 0.0, 0.0});
        v.back().energy += energy;
        v.back().overlap = std::max(v.back().overlap, overlap);
    }
    // The kind of the table named `name` (nullptr: none), e.g. to read its history.
    const ContactKind* kind(const char* name) const;
    // Under MPI (Domain): the halo the switched-on kinds need [m] (0: none
    // on, or fewer than two pieces), and their contacts of the last step.
    double haloReach(double rMax, double hMax) const;
    long contacts() const;
    void addLoadWeights(double* perNode, double work) const override;

    const Data& data() const { return w_; }
    // Some kind of the table is switched on (pieces then have neighbour lists).
    bool anyKindOn() const;
    // Every check period (PieceStartOverlap.cpp): throws StabilityError naming
    // both pieces, the node, its depth and the fixes when a surface node lies
    // inside another piece deeper than their contact reach r_a + r_b (the
    // contact cannot see it: the pieces interpenetrate for good).  Reads
    // every node: gatherAll() first under MPI.  Pairs started
    // interpenetrated (accepted by the start check: the contact pushes them
    // apart) are let alone until a check finds them out of each other.
    void checkDeepOverlap(long iter, double time);

private:
    Data w_;
    struct Kind {
        const ContactKindRow* row;
        std::unique_ptr<ContactKind> kernel;
        double seconds = 0;
        long contacts = 0;
    };
    std::vector<Kind> kinds_;  // in table order
    bool kindOn(const Kind& k) const;
    // The Registration bits of the switched-on kinds: what the broad phase builds.
    unsigned listsWanted() const;

    PieceContactState st_;
    PieceBroadPhase broad_;  // fills st_ (after it: constructed with it)
    // After the kinds: the thread buffers into the nodes' forces and loads.
    void sumForces(const KindStep& ks);
    // Fills st_.surfSpin for this step (SurfaceSpin.hpp); its time and nodes.
    void surfaceSpins();
    double spinSeconds_ = 0;
    long spinNodes_ = 0;
    double broadSeconds_ = 0, sumSeconds_ = 0, maxOverlap_ = 0, maxDepthRatio_ = 0;
    std::vector<DeepContact> threadDeep_;  // per thread, sized once
    ContactStepLimit stepLimit_;
    // The stable step of a node with contact load k [N/m], c [N s/m] and its
    // piece's elements (infinite when the element modes are not measured).
    double nodeStepLimit(int32_t node, double k, double c) const;
    // Is a contact of pieces pa, pb past its reach judged by the per-step
    // check?  Not while the start check judges the pair (a new piece), nor
    // for a pair the start check accepted interpenetrated (startOverlap_):
    // the contact is pushing it apart.
    bool judged(int32_t pa, int32_t pb) const;
    // After the kinds: a contact whose node lies deeper behind the other
    // piece's surface than the reach r_a + r_b stops the run (StabilityError
    // naming the pieces, the depth, the closing speed, the radius and the
    // fixes), the step it happens (doc/hard_cases.md, "Impacts deeper than
    // the reach").
    void checkContactDepth(double dt) const;
    std::vector<std::string> startWarnings_;
    // Per thread, while startPending_: per pair with a new piece (lower id
    // first), the point-polygon springs' energy and largest overlap.
    struct StartPress {
        int32_t a, b;
        double energy, overlap;
    };
    std::vector<std::vector<StartPress>> threadStartPress_;
    std::vector<uint8_t> frozen_;        // per piece: asleep with all neighbours asleep (contacts skipped)
    // Per piece: the awake set's change count (AwakeSet::changes) last seen.
    std::vector<uint32_t> sleepSeen_;
    // Before anything reads them: a piece that fell asleep or woke since the
    // last run has its normals and frozen flag cleared, and its displacement
    // since the lists (AwakeSet::moved2) counts until they are rebuilt.
    void noteSleepChanges();

    // A piece that starts inside another piece deeper than the contact can
    // see is refused (PieceStartOverlap.cpp), once per piece: the first step
    // after it is added.  A loaded state is not a set-up: its pieces count
    // as checked.
    std::vector<uint8_t> startChecked_;  // per piece
    bool startPending_ = false;          // this step checks some piece
    // Per thread: the pairs of pieces (lower id first) in which point-polygon
    // found a node centre inside the other piece this step, while startPending_.
    std::vector<std::vector<std::pair<int32_t, int32_t>>> threadStartSeen_;
    // Before the kinds run: which pieces this step checks.
    void beginStartCheck();
    // After them: refuses (InputError) a pair with a new piece whose nodes lie
    // deep inside the other (winding number) where point-polygon saw none
    // inside: no contact pushes them apart.
    void finishStartCheck();
    // The mean length of a piece's surface edges, now (its cell size) [m].
    double meanSurfaceEdge(int32_t piece) const;
    // Accepted: pairs with a new piece whose springs start pressed by more
    // than a quarter of the reach get a warning naming the energy held and
    // the speed it throws them apart at (startWarnings_).
    void warnStartPress();
    // The surface node lying deepest inside another piece (winding number),
    // among at most 16 per neighbour pair, those deepest in the other's box
    // less the reach.  Start check (periodic = false): pairs with a piece not
    // yet checked and not in `pushed`, own nodes.  Periodic: every pair, only
    // nodes deeper than the pair's reach, the deepest beyond it.
    struct DeepNode {
        int32_t node = -1, pa = -1, pb = -1;
        double depth = 0, reach = 0;
        long count = 0;
    };
    // Periodic: pairs in `pushed` (started interpenetrated) are not reported;
    // those of them still deep are returned in *stillDeep (sorted).
    DeepNode deepestInside(bool periodic, const std::vector<std::pair<int32_t, int32_t>>& pushed,
                           std::vector<std::pair<int32_t, int32_t>>* stillDeep) const;
    // Pairs (lower id first, sorted) the start check accepted interpenetrated,
    // not yet found out of each other by the periodic check.
    std::vector<std::pair<int32_t, int32_t>> startOverlap_;
};

}  // namespace qdem
