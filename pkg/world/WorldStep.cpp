// One step of the QDEM world: the phases in order (World.hpp lists them).
#include <omp.h>

#include <cmath>

#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../core/Threads.hpp"
#include "../parallel/Domain.hpp"
#include "Phases.hpp"
#include "World.hpp"

namespace qdem {

namespace {

// Runs one phase and keeps its wall time (Phase::report).
inline void runTimed(Phase& p, double dt) {
    const double t0 = omp_get_wtime();
    p.run(dt);
    p.seconds = omp_get_wtime() - t0;
}

}  // namespace

// Piece.blocked is a writable uint8 view: 8, or -1 (255), would pass and
// mean nothing (the step reads bits 1, 2, 4 only), so a script that meant
// another encoding ran unconstrained.  One pass over a byte per node.
void World::checkBlockedBits() const {
    const uint8_t* b = blocked.data();
    const std::size_t n = blocked.size();
    uint8_t any = 0;
    for (std::size_t i = 0; i < n; ++i) any |= b[i];
    if (!(any & ~7u)) return;
    for (std::size_t i = 0; i < n; ++i)
        if (b[i] & ~7u) {
            const int32_t p = nodePiece[i];
            throw InputError(cat("QDEM: node ", static_cast<int64_t>(i) - pieces[p].nodeBegin, " of piece ", p,
                                 " has blocked = ", static_cast<int>(b[i]),
                                 ": blocked is a bit mask of the prescribed DOFs, 1 = x, 2 = y, 4 = z (0 to 7; "
                                 "e.g. 7 = all three, as YADE's blockedDOFs 'xyz'). Set piece.blocked[i] to a "
                                 "value in 0..7"));
        }
}

void World::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError("QDEM: time step must be a positive finite number");
    checkBlockedBits();
    const ThreadScope threads;  // QDEM's thread count for this step, YADE's restored after
    // (the same settings on every rank: they all refuse before any exchange)
    if (domain_ && settings.rigidify)
        throw InputError("QDEM: adaptive rigidity (QdemEngine.rigidify=True) is not available under MPI yet (a "
                         "rigid piece split across ranks would need its force and torque summed over them): set "
                         "rigidify=False, or run on one process");
    if (domain_) {
        domain_->agreeOnCall(Domain::Call::Step);
        prepareDomain(dt);
    }
    // Under MPI a phase's error is kept and the step goes on through every
    // later phase and exchange on that rank too: the phases after it hold
    // collectives (the implicit solve's sums, the sleep phase's reductions)
    // that the other ranks enter, and a rank that skipped them left those
    // waiting until their timeout.  Every rank thus reaches the end-of-step
    // reduction, whose error flag (a slot of it: no extra message) makes all
    // throw the earliest phase's error (Domain::agree).  Errors of later
    // phases on a failed rank (garbage in, garbage out) are dropped.
    std::string error;
    char order = '0';
    const auto run = [&](Phase& p) {
        ++order;
        if (!domain_) return runTimed(p, dt);
        try {
            runTimed(p, dt);
        } catch (const InputError& e) {
            if (error.empty()) error = std::string("I") + order + e.what();  // kind, phase order, message
        } catch (const std::exception& e) {
            if (error.empty()) error = std::string("S") + order + e.what();
        }
    };
    // Set-up of the step: a loaded state's sleeping pieces checked against
    // this world's obstacles and gravity, contact forces and energy states
    // summed afresh, the pieces' boxes from the current positions.
    WorldPhases& ph = *phases_;
    ph.sleep.checkLoadedRest();
    contactForces_.reset();
    if (settings.trackEnergy) {
        energy.contactElastic = 0;  // a state: summed afresh by the contact phases
        beginPieceEnergy();
    }
    bounds_.update();
    if (domain_) ph.sphere.listActive();  // the same pairs on every rank: they size the reduction
    // Forces: contacts (into contactForces_), then elements (thread buffers).
    run(ph.obstacle);
    refreshElementModes();  // (what the piece contacts' run-time step adds to)
    run(ph.pieceContact);
    run(ph.sphere);
    // Every contact's springs on each node (ContactForces::load): the
    // run-time stable step of the contacts as they are, serially here.
    if (!domain_) ph.pieceContact.contactStepLimit(dt);
    run(ph.element);
    // Under MPI: partial forces on ghosts to their owners.
    // The contacts' loads with them whenever contacts may be (decided alike
    // on every rank: the messages' sizes depend on it): the owners then hold
    // each node's whole load and take their nodes' run-time stable step.
    if (domain_) {
        const bool loads = (pieces.size() >= 2 && ph.pieceContact.anyKindOn()) || !obstacles.empty() ||
                           spheres.size() > 0;
        domain_->returnGhostForces(ph.element.layout(), contactForces_.force.data(), contactForces_.active,
                                   loads ? contactForces_.beginLoad() : nullptr);
        ph.pieceContact.ownedStepLimit();
    }
    // Motion, the energy states of the step, the clock.
    run(ph.integration);
    if (settings.trackEnergy && error.empty()) finishPieceEnergy();
    // Under MPI: the moved nodes to the ranks that read them.
    if (domain_) {
        domain_->sendStates();
        if (domain_->contactHalo()) domain_->sendContactHalo();
    }
    time += dt;
    ++iter;
    // Which pieces sleep in the next step.
    run(ph.sleep);
    if (domain_) {
        domain_->finishStep(error);
        // Every rank holds the smallest limit over the ranks (finishStep):
        // all stop alike, naming the same node, after the step it was found in.
        if (ph.pieceContact.stepLimit().limit < dt) ph.pieceContact.checkStepLimit(dt);
        // Every rank saw the same loads: they all split again, or none does.
        if (settings.rebalanceThreshold > 0 && domain_->loadImbalance > settings.rebalanceThreshold) rebalance();
    }
}

}  // namespace qdem
