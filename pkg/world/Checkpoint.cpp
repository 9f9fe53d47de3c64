// saveState / loadState (WorldState.hpp): restarts that continue a run
// exactly, for runs longer than a job's time limit.
#include <algorithm>
#include <type_traits>

#include "World.hpp"

namespace qdem {

// Every per-node, per-slot and per-piece array of the state, by name: the
// world's own, then each phase's (Phase::stateColumns).
StateColumns World::stateColumns() {
    StateColumns c;
    c.add("pos", pos);
    c.add("vel", vel);
    c.add("extForce", extForce);
    c.add("blocked", blocked);
    for (Phase* p : phases()) p->stateColumns(c);
    auto f = [&](const char* name, auto& col) { c.add(name, col); };
    f("asleep", asleep_);
    f("slowFor", slowFor_);
    f("pieceSpeed2", pieceSpeed2_);
    f("sleepMoved2", sleepMoved2_);
    f("pieceEnergy", pieceEnergy_);
    return c;
}

WorldState World::saveState() const {
    WorldState s;
    const int64_t counts[4] = {static_cast<int64_t>(nNodes()), static_cast<int64_t>(nTets()),
                               static_cast<int64_t>(pieces.size()), static_cast<int64_t>(surfNodes.size())};
    s.put("counts", counts, 4);
    const double clock[1] = {time};
    const int64_t steps[3] = {iter, sleepCount, wakeCount};
    s.put("time", clock, 1);
    s.put("iter", steps, 3);
    const double e[10] = {energy.kinetic,        energy.elastic,  energy.gravity,      energy.viscous,
                          energy.contactElastic, energy.contactDamping, energy.friction, energy.boundaryWork,
                          energy.localDamping,   energy.sleep};
    s.put("energy", e, 10);
    // (the columns are only read here)
    for (const auto& r : const_cast<World*>(this)->stateColumns().refs) s.putBytes(r.name, r.data, r.count, r.elemSize);
    std::vector<int64_t> start{0};  // frozen obstacle reactions, flattened
    std::vector<double> flat;
    for (const auto& fr : frozenReaction_) {
        flat.insert(flat.end(), fr.begin(), fr.end());
        start.push_back(static_cast<int64_t>(flat.size()));
    }
    s.put("frozenStart", start.data(), start.size());
    s.put("frozenReaction", flat.data(), flat.size());
    const std::vector<double> sig = obstacleSignature(obstacles);
    s.put("obstacles", sig.data(), sig.size());
    s.put("gravity", gravity.data(), 3);
    s.put("held", held_.data(), held_.size());
    return s;
}

void World::loadState(const WorldState& s) {
    const std::vector<int64_t> counts = s.getAll<int64_t>("counts");
    const int64_t mine[4] = {static_cast<int64_t>(nNodes()), static_cast<int64_t>(nTets()),
                             static_cast<int64_t>(pieces.size()), static_cast<int64_t>(surfNodes.size())};
    if (counts.size() != 4 || !std::equal(counts.begin(), counts.end(), mine))
        throw InputError("world state: saved from a world of " +
                         (counts.size() == 4 ? std::to_string(counts[0]) + " nodes, " + std::to_string(counts[1]) +
                                                   " tets, " + std::to_string(counts[2]) + " pieces"
                                             : std::string("unknown size")) +
                         "; this one has " + std::to_string(mine[0]) + " nodes, " + std::to_string(mine[1]) +
                         " tets, " + std::to_string(mine[2]) + " pieces (build the same scene before loading)");
    const std::vector<int64_t> fs = s.getAll<int64_t>("frozenStart");
    const std::vector<double> flat = s.getAll<double>("frozenReaction");
    if (fs.size() != pieces.size() + 1 || fs.back() != static_cast<int64_t>(flat.size()))
        throw InputError("world state: field 'frozenStart' does not match the pieces");
    // Every size checked before anything changes: a wrong file leaves the world as it was.
    s.check<double>("time", 1);
    s.check<int64_t>("iter", 3);
    s.check<double>("energy", 10);
    const StateColumns cols = stateColumns();
    for (const auto& r : cols.refs) s.checkBytes(r.name, r.count, r.elemSize);
    const bool hasHeld = s.fields.count("held") > 0;  // (files from before Piece.dynamic have none)
    if (hasHeld) s.check<uint8_t>("held", held_.size());
    for (const auto& r : cols.refs) s.getBytes(r.name, r.data, r.count, r.elemSize);
    if (hasHeld) s.get("held", held_.data(), held_.size());
    else std::fill(held_.begin(), held_.end(), 0);
    double clock[1];
    int64_t steps[3];
    double e[10];
    s.get("time", clock, 1);
    s.get("iter", steps, 3);
    s.get("energy", e, 10);
    time = clock[0];
    iter = steps[0];
    sleepCount = steps[1];
    wakeCount = steps[2];
    energy = Energy{e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8], e[9]};
    for (std::size_t p = 0; p < pieces.size(); ++p)
        frozenReaction_[p].assign(flat.begin() + fs[p], flat.begin() + fs[p + 1]);
    updatePieceBounds(true);    // sleeping pieces' boxes are not updated by the step
    contactsActive_ = false;
    for (Phase* p : phases()) p->stateLoaded();
    // Sleeping pieces rest in the obstacles and gravity the state was saved
    // with (frozen reactions are by obstacle index): if this world gets others
    // (or the file predates these fields) they are woken at the next step.
    obstaclesPending_ = s.fields.count("obstacles") > 0;
    gravityPending_ = s.fields.count("gravity") > 0 && s.fields.find("gravity")->second.size() == 3 * sizeof(double);
    loadedObstacles_ = obstaclesPending_ ? s.getAll<double>("obstacles") : std::vector<double>{};
    if (gravityPending_) s.get("gravity", loadedGravity_.data(), 3);
    if (!obstaclesPending_ || !gravityPending_) wakeAll();
    awakeSetChanged();
}

}  // namespace qdem
