// World::periodicChecks: the checks QdemEngine runs every checkPeriod steps,
// scheduled and ordered here, in one call from Python.
#include "world/World.hpp"

namespace qdem {

PeriodicChecks World::periodicChecks(long checkPeriod, long gatherPeriod, double dt, bool checkDt) {
    PeriodicChecks r;
    const bool due = checkPeriod > 0 && iter % checkPeriod == 0;
    const bool gather = due || (gatherPeriod > 0 && iter % gatherPeriod == 0);
    if (gather && domain() && domain()->size() > 1) gatherAll();  // every rank sees every node: the checks agree
    if (!due) return r;
    r.inverted = checkInverted();  // first: an inverted element is named as inverted
    if (checkDt) checkCurrentDt(dt);  // then: a strained, stiffened element is named before it blows up
    checkFinite();
    if (pieces.size() > 1) checkDeepOverlap();  // a node sunk into another piece beyond the contact's reach
    if (spheres.size() > 0 && !pieces.empty()) checkSpheresInside();  // a YADE sphere sunk into (or placed in) a piece
    if (!obstacles.empty() && !pieces.empty()) r.edges = obstacleEdgeCrossing();
    r.ran = true;
    return r;
}

}  // namespace qdem
