// One step of the QDEM world: the phases in order (World.hpp lists them).
#include <omp.h>

#include <cmath>

#include "../core/Errors.hpp"
#include "../core/Threads.hpp"
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

void World::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError("QDEM: time step must be a positive finite number");
    const ThreadScope threads;  // QDEM's thread count for this step, YADE's restored after
    // Set-up of the step: a loaded state's sleeping pieces checked against
    // this world's obstacles and gravity, contact forces and energy states
    // summed afresh, the pieces' boxes from the current positions.
    sleepPhase_.checkLoadedRest();
    contactsActive_ = false;
    if (settings.trackEnergy) {
        energy.contactElastic = 0;  // a state: summed afresh by the contact phases
        beginPieceEnergy();
    }
    updatePieceBounds();
    // Forces: contacts (into contactForce_), then elements (thread buffers).
    runTimed(obstaclePhase_, dt);
    runTimed(pieceContactPhase_, dt);
    runTimed(spherePhase_, dt);
    runTimed(elementPhase_, dt);
    // Motion, the energy states of the step, the clock.
    runTimed(integrationPhase_, dt);
    if (settings.trackEnergy) finishPieceEnergy();
    time += dt;
    ++iter;
    // Which pieces sleep in the next step.
    runTimed(sleepPhase_, dt);
}

}  // namespace qdem
