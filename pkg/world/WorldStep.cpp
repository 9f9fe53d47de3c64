// The step pipeline: obstacle contacts, element forces, leapfrog update.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "../contact/ContactLaw.hpp"
#include "../core/Errors.hpp"
#include "../core/Threads.hpp"
#include "World.hpp"

namespace qdem {

void World::step(double dt) {
    if (!(dt > 0) || !std::isfinite(dt)) throw StabilityError("QDEM: time step must be a positive finite number");
    const ThreadScope threads;  // QDEM's thread count for this step, YADE's restored after
    double t0 = omp_get_wtime();
    sleepPhase_.checkLoadedRest();
    contactsActive_ = false;
    if (settings.trackEnergy) {
        energy.contactElastic = 0;  // a state: summed afresh by the contact phases
        beginPieceEnergy();
    }
    updatePieceBounds();
    obstaclePhase_.run(dt);
    const double tObs = omp_get_wtime();
    pieceContactPhase_.run(dt);
    spherePhase_.run(dt);
    double t1 = omp_get_wtime();
    elementPhase_.run(dt);
    double t2 = omp_get_wtime();
    integrationPhase_.run(dt);
    if (settings.trackEnergy) finishPieceEnergy();
    double t3 = omp_get_wtime();
    timings.obstacles = tObs - t0;
    timings.elements = t2 - t1;
    timings.integrate = t3 - t2;
    time += dt;
    ++iter;
    sleepPhase_.run(dt);
}

}  // namespace qdem
