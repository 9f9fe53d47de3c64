// saveState / loadState (WorldState.hpp): restarts that continue a run
// exactly, for runs longer than a job's time limit.
#include <algorithm>
#include <type_traits>

#include "../core/Format.hpp"
#include "../parallel/Domain.hpp"
#include "Phases.hpp"
#include "World.hpp"

namespace qdem {

// Every per-node, per-slot and per-piece array of the state, by name: the
// world's own, then each phase's (Phase::stateColumns).
StateColumns World::stateColumns() {
    StateColumns c;
    c.add("pos", pos, Rows::Node);
    c.add("vel", vel, Rows::Node);
    c.add("extForce", extForce, Rows::Node);
    c.add("blocked", blocked, Rows::Node);
    c.add("pieceEnergy", pieceEnergy_);
    for (Phase* p : phases()) p->stateColumns(c);
    return c;
}

WorldState World::saveState() const {
    requireGathered("saveState");
    if (domain_ && domain_->built() && rowsGatheredIter_ != iter)
        throw InputError("saveState under MPI needs every rank's contact histories: call gatherState() on every "
                         "rank first (qdem.saveState and O.save do)");
    WorldState s;
    const int64_t counts[4] = {static_cast<int64_t>(nNodes()), static_cast<int64_t>(nTets()),
                               static_cast<int64_t>(pieces.size()), static_cast<int64_t>(surfNodes.size())};
    s.put("counts", counts, 4);
    const double clock[1] = {time};
    const int64_t steps[3] = {iter, phases_->sleep.sleepCount(), phases_->sleep.wakeCount()};
    s.put("time", clock, 1);
    s.put("iter", steps, 3);
    const Energy& et = energyTotal();  // under MPI: the sums over the ranks
    const double e[11] = {et.kinetic,        et.elastic,        et.gravity,  et.viscous,      et.contactElastic,
                          et.contactDamping, et.friction,       et.boundaryWork, et.localDamping, et.sleep,
                          et.rigid};
    s.put("energy", e, 11);
    // The mass added to each element (selective mass scaling): not state but
    // part of the scene, kept to refuse a load into a scene built without it
    // (its node masses, so its trajectories, would differ).
    s.put("tetAddedMass", tetAddedMass.data(), nTets());
    // Each element's material, for the same reason (a bonded piece's regions).
    s.put("tetMaterial", tetMaterial.data(), nTets());
    // (the columns are only read here)
    for (const auto& r : const_cast<World*>(this)->stateColumns().refs)
        if (r.restart) s.putBytes(r.name, r.data, r.count, r.elemSize);
    for (const Phase* p : phases()) p->saveFields(s);
    return s;
}

void World::loadState(const WorldState& s) {
    boxesIter_ = -1;  // (pieceBoxes: positions change)
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
    // Every size checked before anything changes: a wrong file leaves the world as it was.
    s.check<double>("time", 1);
    s.check<int64_t>("iter", 3);
    // (files from before adaptive rigidity have 10 terms: no energy.rigid)
    const std::size_t nEnergy = s.getAll<double>("energy").size() == 10 ? 10 : 11;
    s.check<double>("energy", nEnergy);
    {
        // A state saved before mass scaling existed had none.
        std::vector<double> saved(nTets(), 0.0);
        if (s.fields.count("tetAddedMass")) saved = s.getAll<double>("tetAddedMass");
        if (saved.size() != nTets() || !std::equal(saved.begin(), saved.end(), tetAddedMass.data())) {
            double a = 0, b = 0;
            for (const double v : saved) a += v;
            for (std::size_t e = 0; e < nTets(); ++e) b += tetAddedMass[e];
            throw InputError(cat("world state: saved from pieces with ", a, " kg added by mass scaling, this world's "
                                 "pieces have ", b, " kg (or on other elements): add the pieces with the same "
                                 "targetDt (qdem.addPiece(..., targetDt=...)) as the run that saved it"));
        }
    }
    if (s.fields.count("tetMaterial")) {  // (states saved before bonded pieces: one material per piece)
        const std::vector<int32_t> saved = s.getAll<int32_t>("tetMaterial");
        for (std::size_t e = 0; e < nTets(); ++e)
            if (saved.size() != nTets() || saved[e] != tetMaterial[e])
                throw InputError(cat("world state: element ", e, " (piece ", tetPiece[e], ") was saved with material ",
                                     saved.size() == nTets() ? saved[e] : -1, ", this world gives it material ",
                                     tetMaterial[e], ": add the pieces with the same materials (and regionMaterials) "
                                     "as the run that saved it"));
    }
    const StateColumns cols = stateColumns();
    for (const auto& r : cols.refs)
        if (r.restart) s.checkBytes(r.name, r.count, r.elemSize);
    for (const Phase* p : phases()) p->checkFields(s);
    for (const auto& r : cols.refs)
        if (r.restart) s.getBytes(r.name, r.data, r.count, r.elemSize);
    double clock[1];
    int64_t steps[3];
    double e[11] = {};
    s.get("time", clock, 1);
    s.get("iter", steps, 3);
    s.get("energy", e, nEnergy);
    time = clock[0];
    iter = steps[0];
    phases_->sleep.setCounts(steps[1], steps[2]);
    energy = Energy{e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8], e[9], e[10]};
    for (Phase* p : phases()) p->loadFields(s);
    if (domain_) {
        // Every rank loaded the whole state: split again from it at the next
        // step, and the saved energy sums count once (on rank 0).
        domain_->invalidate();
        energyTotal_ = energy;
        if (domain_->rank() != 0) energy = Energy{};
    }
    bounds_.update(true);  // sleeping pieces' boxes are not updated by the step
    contactForces_.reset();
    for (Phase* p : phases()) p->stateLoaded();
}

}  // namespace qdem
