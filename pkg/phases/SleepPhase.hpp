// Sleeping pieces (doc/sleeping.md): the last phase of a step decides which
// pieces fall asleep or wake, and writes the awake set every other phase
// reads (AwakeSet.hpp: asleep flags, the awake pieces' tets, nodes and
// surface nodes).  A piece at rest is left out of the step until something
// near it moves; what it pushed on obstacles stays in their reactions.  It
// also decides which pieces are rigid (settings.rigidify: RigidSwitch.cpp).
#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../contact/Obstacle.hpp"
#include "../contact/SphereSet.hpp"
#include "../core/Column.hpp"
#include "../parallel/DomainRef.hpp"
#include "../step/AwakeSet.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../step/PieceBounds.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"
#include "../parallel/ThreadLayout.hpp"

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
        AwakeSet& awake;                        // what it decides: written here only
        const ObstaclePhase& obstacleContacts;  // what a piece pushed on obstacles, which it can reach
        const PieceContactPhase& pieceContacts; // neighbour pieces, the Verlet lists' positions
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

    // ---- changes from outside -----------------------------------------------------
    // Wakes a sleeping piece, or makes a rigid one deformable (its state is
    // about to be written from outside).  wakeAll wakes sleeping pieces only.
    void wake(std::size_t piece);
    void wakeAll();
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
    long rigidSwitches() const { return rigidSwitches_; }  // switches rigid <-> deformable so far
    long wakeCount() const { return wakeCount_; }    // and woken
    void setCounts(long sleeps, long wakes) { sleepCount_ = sleeps, wakeCount_ = wakes; }

private:
    Data w_;
    void putToSleep(std::size_t p);
    void wakeOne(std::size_t p);
    // Adaptive rigidity (RigidSwitch.cpp): pieces made rigid or deformable
    // by the integration's indicators; true if any changed.
    bool switchRigid();

    std::vector<double> slowFor_;      // time all its nodes have been slower than sleepVelocity [s]
    std::vector<double> pieceSpeed2_;  // largest squared node speed in the last step
    std::vector<double> restSums_;     // per candidate piece: net force, its scale, blocked and driven flags
    // What the sleeping pieces of a loaded state rest in: the obstacle list
    // (obstacleSignature) and gravity it was saved with.  A script restarting
    // in a new process loads the state before its engine hands over gravity
    // and the YADE bodies: when they are the saved ones nobody is woken; if
    // the first step comes with others, every piece is (checkLoadedRest).
    std::vector<double> loadedObstacles_;
    Eigen::Vector3d loadedGravity_ = Eigen::Vector3d::Zero();
    bool obstaclesPending_ = false;
    bool gravityPending_ = false;
    long sleepCount_ = 0, wakeCount_ = 0;
    long rigidSwitches_ = 0;
};

}  // namespace qdem
