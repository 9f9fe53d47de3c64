// Sleeping pieces (doc/sleeping.md): the last phase of a step decides which
// pieces fall asleep or wake, and owns the awake set every other phase reads
// (asleep flags, the awake pieces' tets, nodes and surface nodes).  A piece
// at rest is left out of the step until something near it moves; what it
// pushed on obstacles stays in their reactions.
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../contact/Obstacle.hpp"
#include "../contact/SphereSet.hpp"
#include "../core/Column.hpp"
#include "../parallel/DomainRef.hpp"
#include "../world/Energy.hpp"
#include "../world/Phase.hpp"
#include "../world/PieceBounds.hpp"
#include "../world/PieceInfo.hpp"
#include "../world/Settings.hpp"
#include "../world/ThreadLayout.hpp"

namespace qdem {

class ObstaclePhase;
class PieceContactPhase;
class IntegrationPhase;

class SleepPhase final : public Phase {
public:
    // What it reads and writes of the world: the node states it zeroes, and
    // what tells whether something moves near a piece.
    struct Data {
        const Column<double>& pos;
        Column<double>& vel;                    // zeroed when a piece falls asleep
        const Column<double>& mass;
        const Column<uint8_t>& blocked;         // prescribed DOFs: a piece driven through them stays awake
        const Column<int32_t>& surfNodes;
        const std::vector<PieceInfo>& pieces;
        const std::vector<Obstacle>& obstacles;
        const SphereSet& spheres;               // pieces a sphere is near
        const Settings& settings;
        const Eigen::Vector3d& gravity;
        DomainRef domain;                       // under MPI: owned nodes, decisions alike on every rank
        Energy& energy;                         // kinetic energy removed at sleep
        PieceBounds& bounds;                    // a held piece's box, no longer updated by the step
        const ObstaclePhase& obstacleContacts;  // what a piece pushed on obstacles, which it can reach
        PieceContactPhase& pieceContacts;       // neighbour pieces, Verlet lists; told of sleep changes
        const IntegrationPhase& integration;    // the pieces' largest node speeds
        const Column<double>& force;            // the step's total node forces: is a piece held up?
    };
    explicit SleepPhase(const Data& data) : w_(data) {}
    const char* name() const override { return "sleep"; }
    // Puts slow pieces to sleep and wakes those something moves near.
    void run(double dt) override;
    void stateColumns(StateColumns& c) override;
    void saveFields(WorldState& s) const override;
    void checkFields(const WorldState& s) const override;
    void loadFields(const WorldState& s) override;
    void piecesAdded() override;

    // ---- the awake set (read by every phase) -----------------------------------
    bool asleep(std::size_t piece) const { return piece < asleep_.size() && asleep_[piece]; }
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
    // Squared displacement of a piece's surface since the last Verlet list
    // rebuild, when it fell asleep (other nodes may only move the rest of half
    // the skin before the lists are rebuilt); listsRebuilt() clears it.
    double moved2(std::size_t piece) const { return sleepMoved2_[piece]; }
    void listsRebuilt() { std::fill(sleepMoved2_.begin(), sleepMoved2_.end(), 0.0); }
    // (obstacle index, F, T) x 7 per obstacle a sleeping piece pushed on when it fell asleep.
    const std::vector<double>& frozenReaction(std::size_t piece) const { return frozenReaction_[piece]; }

    // ---- changes from outside -----------------------------------------------------
    void wake(std::size_t piece);
    void wakeAll();
    bool dynamic(std::size_t piece) const { return piece >= held_.size() || !held_[piece]; }
    void setDynamic(std::size_t piece, bool dynamic);
    // Gravity changed from old to g: sleeping pieces would not feel it, so they
    // are woken - unless this is the gravity a loaded state was saved with.
    void gravitySet(const Eigen::Vector3d& old, const Eigen::Vector3d& g);
    // A new obstacle list (signatures: obstacleSignature): true when sleeping
    // pieces may keep resting (the same list, or the one a loaded state was
    // saved with); false: every piece was woken.
    bool obstaclesSet(const std::vector<double>& newSig, const std::vector<double>& oldSig);
    // Before the first step after a load: wakes everything when the world got
    // other obstacles or gravity than the state was saved with.
    void checkLoadedRest();
    // The awake lists from the flags (after pieces were added or flags loaded).
    void awakeSetChanged();

    long sleepCount() const { return sleepCount_; }  // pieces put to sleep so far (diagnostics)
    long wakeCount() const { return wakeCount_; }    // and woken
    void setCounts(long sleeps, long wakes) { sleepCount_ = sleeps, wakeCount_ = wakes; }

private:
    Data w_;
    void putToSleep(std::size_t p);
    void wakeOne(std::size_t p);

    std::vector<uint8_t> asleep_;
    std::vector<double> slowFor_;      // time all its nodes have been slower than sleepVelocity [s]
    std::vector<double> pieceSpeed2_;  // largest squared node speed in the last step
    std::vector<double> restSums_;     // per candidate piece: net force, its scale, blocked and driven flags
    std::vector<uint8_t> held_;        // not dynamic (asleep until made dynamic)
    std::vector<double> sleepMoved2_;
    std::vector<std::vector<double>> frozenReaction_;
    // What the sleeping pieces of a loaded state rest in: the obstacle list
    // (obstacleSignature) and gravity it was saved with.  A script restarting
    // in a new process loads the state before its engine hands over gravity
    // and the YADE bodies: when they are the saved ones nobody is woken; if
    // the first step comes with others, every piece is (checkLoadedRest).
    std::vector<double> loadedObstacles_;
    Eigen::Vector3d loadedGravity_ = Eigen::Vector3d::Zero();
    bool obstaclesPending_ = false;
    bool gravityPending_ = false;
    long nAsleep_ = 0;
    bool everything_ = true;
    long version_ = 0;
    std::vector<TetSegment> awakeTets_;
    std::vector<int32_t> awakeNodes_, awakeSurf_;
    std::vector<int32_t> obstacleSurf_;  // (obstacleSurf())
    long sleepCount_ = 0, wakeCount_ = 0;
};

}  // namespace qdem
