// Surface nodes against YADE walls, boxes and facets: the first phase of a
// step.  Owns the node-obstacle contact history and the per-(piece,
// obstacle) reactions that sleeping pieces keep pushing with.
#pragma once
#include <array>
#include <cstdint>
#include <set>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "../contact/ContactLaw.hpp"
#include "../contact/Obstacle.hpp"
#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../step/PieceBounds.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"
#include "../step/AwakeSet.hpp"

namespace qdem {


class ObstaclePhase final : public Phase {
public:
    // What it reads and writes of the world.
    struct Data {
        const Column<double>& pos;
        const Column<double>& vel;
        const Column<double>& refPos;    // rest shape: how deep behind a wall a node may go (restDiagonal_)
        const Column<double>& mass;
        const Column<int32_t>& nodePiece;
        const Column<int32_t>& surfNodes;
        const Column<double>& surfWeight;
        const std::vector<PieceInfo>& pieces;
        const std::vector<Material>& materials;
        const Settings& settings;
        const AwakeSet& sleeping;        // awake surface nodes, sleeping pieces' frozen reactions
        const PieceBounds& bounds;       // which obstacles a piece can reach
        std::vector<Obstacle>& obstacles;  // their reactions
        ContactForces& contacts;
        Energy& energy;                  // contact damping, friction, boundary work
        std::vector<std::vector<double>>& threadPieceEnergy;  // contact energy with obstacles per piece
        const long& iter;                // steps done (errors name the step being made)
    };
    explicit ObstaclePhase(const Data& data) : w_(data) {}
    const char* name() const override { return "obstacles"; }
    // Contact forces on the awake surface nodes (ContactForces), the
    // obstacles' reactions (sleeping pieces' frozen ones included), energies.
    void run(double dt) override;
    void report(PhaseReport& r) const override {
        Phase::report(r);
        r.counts.push_back({"wall", contacts_});  // surface node - obstacle contacts (awake pieces)
    }
    void stateColumns(StateColumns& c) override;
    void piecesAdded() override;
    // `work` per slot holding a wall contact, on its node.
    void addLoadWeights(double* perNode, double work) const override;
    // A loaded state continues a run: its contacts with obstacles are not a
    // set-up mistake (a new obstacle list still gets checked).
    void stateLoaded() override;
    // The obstacles' shapes go with the state: after a load, the obstacles
    // the saved run had are not new (O.loadTmp into a fresh world, O.load in
    // a new process), those added since are.
    void saveFields(WorldState& s) const override;
    void loadFields(const WorldState& s) override;
    // A new obstacle list: the pieces are checked once against the
    // obstacles it holds that were not checked before (a body, or a shape of
    // it, new since the last check), not against the ones they already
    // touch: adding a facet elsewhere in the middle of an impact is no
    // set-up mistake.
    void obstaclesChanged() { shapesPending_ = true; }
    // Pieces that started pressed into an obstacle by more than a quarter of their
    // node radius (not refused: their node centres are outside), one message
    // each, handed over once (the engine turns them into warnings).
    std::vector<std::string> takeStartWarnings() { return std::exchange(startWarnings_, {}); }

    // The obstacles each piece could reach in the last step (CSR: piece p's
    // are pieceObstacles()[pieceObstacleBegin()[p] .. [p + 1])), and what
    // the piece pushed on each of them (6 per entry: force, torque).
    const std::vector<int>& pieceObstacles() const { return pieceObstacles_; }
    const std::vector<int>& pieceObstacleBegin() const { return pieceObstacleBegin_; }
    const std::vector<double>& pairReaction() const { return pairReaction_; }

    // Contact history: kSlots (obstacle body id, side, tangential spring) per surface node.
    static constexpr int kSlots = 4;
    // Bodies one node may touch before the one-touch-per-surface rule (run()).
    static constexpr int kTouches = 8;

private:
    // Refuses (InputError) a piece whose nodes start inside a wall, box or
    // facet, once per piece and obstacle list.
    void checkStartOverlaps();
    // freshObstacle_ from checkedShapes_, when the list or the state changed
    // (then true).
    bool updateFresh();
    // checkedShapes_: the obstacles in force.
    void knowCurrentObstacles();
    // A node that went through an obstacle this step: passed a thin one's
    // surface (two-sided wall, facet) without touching it the step before,
    // or lies behind a one-sided wall by more than its piece's largest extent.
    struct Through {
        int32_t node = -1;
        int piece = -1, obstacle = -1;
        bool thin = false;
        double travel = 0, depth = 0, speed = 0, mass = 0, kn = 0;
    };
    [[noreturn]] void reportThrough(const Through& t, double dt) const;
    // Refuses (StabilityError) a dynamic obstacle whose contact springs this
    // step make its stable step shorter than dt (World::dynamicObstacleLimit
    // bounds them before the run).  Per (piece, obstacle) pair and thread,
    // kDyn numbers: sum of g k, sum of g c (g: the obstacle's mobility at
    // the contact point), largest k/m and c/m of a node, the contacts.
    static constexpr int kDyn = 5;
    void checkDynamicObstacles(double dt, std::size_t stride) const;
    std::vector<double> threadDynamic_;
    std::vector<Through> threadThrough_;  // per thread: its first
    // The deepest node contact of the step (overlap / node radius), per
    // thread: a piece sinking half its radius into a much softer YADE body
    // is named once per (body, piece) (warnSoftObstacle).
    struct Deepest {
        double ratio = 0;
        int obstacle = -1, piece = -1;
    };
    std::vector<Deepest> threadDeepest_;
    std::set<std::pair<int, int>> softWarned_;  // (YADE body id, piece) already named
    void warnSoftObstacle(const Deepest& d);
    // run()'s parts: the obstacles each piece can reach and their pair
    // constants; the node contacts, one NodePass per thread (ObstaclePhase.cpp),
    // returning the energies (damping, slip, boundary work); the checks,
    // reactions and energies after them.
    struct NodePass;
    void listReachable();
    std::array<double, 3> contactPass(double dt, int nth);
    void finishStep(double dt, int nth, const std::array<double, 3>& energySum);
    std::vector<double> pieceExtent_;     // per piece: its largest extent (this step)
    std::vector<double> restDiagonal_;    // per piece: its rest shape's bounding-box diagonal (piecesAdded)
    std::vector<uint8_t> surfaceNode_;    // per node: on the surface (checkInnerNodesThrough)
    void measureRestShapes();

    Data w_;

    Column<int32_t> slotBody_;  // YADE body id, -1 = empty
    Column<double> slotShear_;
    Column<int8_t> slotSide_;
    std::vector<uint8_t> startChecked_;     // per piece: start overlap checked for this obstacle list
    std::vector<uint8_t> freshObstacle_;    // per obstacle: not checked yet (checked against every piece)
    // The obstacles checked against the pieces (or those the loaded run had),
    // by identity: body, kind, shape.  By identity, not by index, so that two
    // list changes before a step, a refused check, or a load whose list is
    // set before or after it lose no unchecked obstacle and make no known
    // one new.
    std::unordered_set<std::string> checkedShapes_;
    bool shapesPending_ = true;   // the list or the state changed: freshObstacle_ to update
    bool adoptCurrent_ = false;   // a state saved without its obstacles' shapes: the next list is known
    std::vector<std::string> startWarnings_;
    std::vector<double> threadReaction_;    // per thread x (piece, obstacle) pair x 6
    std::vector<int> pieceObstacles_, pieceObstacleBegin_;
    std::vector<PairConst> pairConst_;      // per (piece, obstacle) pair: the contact model's constants
    std::vector<double> pairReaction_;      // per (piece, obstacle) pair, 6 each
    long contacts_ = 0;
};

}  // namespace qdem
