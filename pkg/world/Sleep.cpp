// Sleeping pieces (doc/sleeping.md): pieces at rest are left out of the step
// until something near them moves.  In a domino line of 40 pieces only the
// few around the front move at any time; the rest stand or lie still.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "World.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"

namespace qdem {

void World::awakeSetChanged() {
    ++awakeVersion_;
    const std::size_t np = pieces.size();
    awakeTets_.clear();
    awakeNodes_.clear();
    awakeSurf_.clear();
    nAsleep_ = 0;
    for (std::size_t p = 0; p < np; ++p) {
        if (asleep_[p]) {
            ++nAsleep_;
            continue;
        }
        awakeTets_.push_back({static_cast<int32_t>(p), pieces[p].tetBegin, pieces[p].tetEnd});
        for (int32_t n = pieces[p].nodeBegin; n < pieces[p].nodeEnd; ++n) awakeNodes_.push_back(n);
        for (int32_t s = pieces[p].surfBegin; s < pieces[p].surfEnd; ++s) awakeSurf_.push_back(s);
    }
}

void World::wakeOne(std::size_t p) {
    asleep_[p] = 0;
    pieceContactPhase_.sleepChanged(p, true);
    slowFor_[p] = 0;
    pieceSpeed2_[p] = 0;
    frozenReaction_[p].clear();
    ++wakeCount;
}

void World::wake(std::size_t p) {
    if (p >= asleep_.size() || !asleep_[p] || held_[p]) return;
    wakeOne(p);
    awakeSetChanged();
}

void World::wakeAll() {
    if (nAsleep_ == 0) return;
    bool changed = false;
    for (std::size_t p = 0; p < asleep_.size(); ++p)
        if (asleep_[p] && !held_[p]) {
            wakeOne(p);
            changed = true;
        }
    if (changed) awakeSetChanged();
}

void World::setDynamic(std::size_t p, bool dynamic) {
    if (p >= pieces.size()) throw InputError(cat("setDynamic: no piece ", p));
    if (dynamic) {
        held_[p] = 0;
        wake(p);
        return;
    }
    held_[p] = 1;
    if (!asleep_[p]) {
        putToSleep(p);
        awakeSetChanged();
    }
    updatePieceBounds(true);  // its box is no longer updated by the step (and may not exist yet)
}

void World::setGravity(const Eigen::Vector3d& g) {
    const bool same = g == gravity || (gravityPending_ && g == loadedGravity_);
    gravityPending_ = false;
    gravity = g;
    if (!same) wakeAll();  // a sleeping piece would not feel the change
}

void World::checkLoadedRest() {
    const bool same = (!gravityPending_ || gravity == loadedGravity_) &&
                      (!obstaclesPending_ || obstacleSignature(obstacles) == loadedObstacles_);
    gravityPending_ = obstaclesPending_ = false;
    if (!same) wakeAll();
}

void World::putToSleep(std::size_t p) {
    const PieceInfo& P = pieces[p];
    // Velocities to zero: the kinetic energy left is booked as removed.
    double ek = 0;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n)
        for (int d = 0; d < 3; ++d) {
            double& v = vel[3 * n + d];
            ek += 0.5 * mass[n] * v * v;
            v = 0;
        }
    if (settings.trackEnergy) energy.sleep += ek;
    // What it pushed on obstacles this step stays in their reactions.
    std::vector<double>& fr = frozenReaction_[p];
    fr.clear();
    const std::vector<int>& pieceObstacles_ = obstaclePhase_.pieceObstacles();
    const std::vector<int>& pieceObstacleBegin_ = obstaclePhase_.pieceObstacleBegin();
    const std::vector<double>& pairReaction_ = obstaclePhase_.pairReaction();
    if (pieceObstacleBegin_.size() == pieces.size() + 1 && pairReaction_.size() == 6 * pieceObstacles_.size())
        for (int j = pieceObstacleBegin_[p]; j < pieceObstacleBegin_[p + 1]; ++j) {
            fr.push_back(pieceObstacles_[j]);
            fr.insert(fr.end(), &pairReaction_[6 * j], &pairReaction_[6 * j + 6]);
        }
    // How far it moved since the Verlet lists were built: other nodes may
    // only move the rest of half the skin before the lists are rebuilt.
    double m2 = 0;
    const PieceContactState& pc = pieceContactPhase_.state();
    if (pc.listValid && pc.listPos.size() == 3 * surfNodes.size())
        for (int32_t s = P.surfBegin; s < P.surfEnd; ++s) {
            const int32_t n = surfNodes[s];
            double d2 = 0;
            for (int d = 0; d < 3; ++d) d2 += std::pow(pos[3 * n + d] - pc.listPos[3 * s + d], 2);
            m2 = std::max(m2, d2);
        }
    sleepMoved2_[p] = m2;
    asleep_[p] = 1;
    pieceContactPhase_.sleepChanged(p, false);
    ++sleepCount;
}

void World::updateSleep(double dt) {
    const std::size_t np = pieces.size();
    if (!(settings.sleepVelocity > 0)) {
        wakeAll();
        return;
    }
    const double v2 = settings.sleepVelocity * settings.sleepVelocity;
    // Largest node speed of each awake piece, from the integration.
    for (std::size_t p = 0; p < np; ++p) {
        if (asleep_[p]) continue;
        const double m = integrationPhase_.maxSpeed2(p);
        pieceSpeed2_[p] = m;
        slowFor_[p] = m < v2 ? slowFor_[p] + dt : 0.0;
    }
    const PieceContactState& pc = pieceContactPhase_.state();
    const bool nbrsValid = pc.nbrStart.size() == np + 1 && (settings.pointPolygonOn || settings.edgeEdgeOn) && np > 1;
    auto fastNeighbour = [&](std::size_t p) {
        if (!nbrsValid) return false;
        for (int32_t q = pc.nbrStart[p]; q < pc.nbrStart[p + 1]; ++q) {
            const int32_t b = pc.nbrs[q];
            if (!asleep_[b] && pieceSpeed2_[b] >= v2) return true;
        }
        return false;
    };
    const std::vector<int>& pieceObstacles_ = obstaclePhase_.pieceObstacles();
    const std::vector<int>& pieceObstacleBegin_ = obstaclePhase_.pieceObstacleBegin();
    auto movingObstacle = [&](std::size_t p) {
        if (pieceObstacleBegin_.size() != np + 1) return false;
        for (int j = pieceObstacleBegin_[p]; j < pieceObstacleBegin_[p + 1]; ++j) {
            const Obstacle& o = obstacles[pieceObstacles_[j]];
            if (o.vel.squaredNorm() > 0 || o.angVel.squaredNorm() > 0) return true;
        }
        return false;
    };
    auto nearSphere = [&](std::size_t p) { return p < spheres.pieceUsed.size() && spheres.pieceUsed[p]; };
    bool changed = false;
    for (std::size_t p = 0; p < np; ++p) {
        if (asleep_[p]) {
            if (!held_[p] && (fastNeighbour(p) || movingObstacle(p) || nearSphere(p))) {
                wakeOne(p);
                changed = true;
            }
        } else if (pieceSpeed2_[p] < v2 && slowFor_[p] >= settings.sleepTime && !fastNeighbour(p) && !movingObstacle(p) &&
                   !nearSphere(p)) {
            putToSleep(p);
            changed = true;
        }
    }
    if (changed) awakeSetChanged();
}

// Energy states per piece: a sleeping piece keeps the values it had, since
// nothing of it moves (its contacts are with sleeping pieces only while they
// are skipped).
void World::beginPieceEnergy() {
    const std::size_t nth = std::max(1, omp_get_max_threads());
    if (threadPieceEnergy_.size() < nth) threadPieceEnergy_.resize(nth);
    for (auto& t : threadPieceEnergy_) t.assign(3 * pieces.size(), 0.0);
}

void World::finishPieceEnergy() {
    double el = 0, contact = 0;
    for (std::size_t p = 0; p < pieces.size(); ++p) {
        for (int c = 0; c < 3; ++c) {
            const bool computed = c < 2 ? !asleep_[p] : !pieceContactPhase_.frozen(p);
            if (!computed) continue;
            double sum = 0;
            for (const auto& t : threadPieceEnergy_) sum += t[3 * p + c];
            pieceEnergy_[3 * p + c] = sum;
        }
        el += pieceEnergy_[3 * p];
        contact += pieceEnergy_[3 * p + 1] + pieceEnergy_[3 * p + 2];
    }
    energy.elastic = el;
    energy.contactElastic += contact;
}

}  // namespace qdem
