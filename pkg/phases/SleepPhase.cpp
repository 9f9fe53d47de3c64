// Sleeping pieces (doc/sleeping.md): pieces at rest are left out of the step
// until something near them moves.  In a domino line of 40 pieces only the
// few around the front move at any time; the rest stand or lie still.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "../step/WorldState.hpp"
#include "IntegrationPhase.hpp"
#include "ObstaclePhase.hpp"
#include "PieceContactPhase.hpp"
#include "SleepPhase.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../parallel/Domain.hpp"

namespace qdem {

void SleepPhase::awakeSetChanged() {
    ++w_.awake.version_;
    const std::size_t np = w_.pieces.size();
    w_.awake.awakeTets_.clear();
    w_.awake.awakeNodes_.clear();
    w_.awake.awakeSurf_.clear();
    std::vector<int32_t> held;  // (built only when the awake set changes)
    w_.awake.nAsleep_ = 0;
    w_.awake.nRigid_ = 0;
    w_.awake.rigidPieces_.clear();
    const Domain* d = w_.domain.built();
    for (std::size_t p = 0; p < np; ++p) {
        if (w_.awake.asleep_[p]) w_.awake.rigid_[p] = 0;
        if (w_.awake.rigid_[p]) {
            // Rigid (RigidBodies.hpp): its surface nodes carry contacts, its
            // tets and nodes are not the element and node passes' (serial only).
            ++w_.awake.nRigid_;
            w_.awake.rigidPieces_.push_back(static_cast<int32_t>(p));
            for (int32_t s = w_.pieces[p].surfBegin; s < w_.pieces[p].surfEnd; ++s) w_.awake.awakeSurf_.push_back(s);
            continue;
        }
        if (w_.awake.asleep_[p]) {
            ++w_.awake.nAsleep_;
            if (p < w_.awake.held_.size() && w_.awake.held_[p])
                for (int32_t s = w_.pieces[p].surfBegin; s < w_.pieces[p].surfEnd; ++s)
                    if (!d || d->owns(w_.surfNodes[s])) held.push_back(s);
            continue;
        }
        if (!d) {
            w_.awake.awakeTets_.push_back({static_cast<int32_t>(p), w_.pieces[p].tetBegin, w_.pieces[p].tetEnd});
            for (int32_t n = w_.pieces[p].nodeBegin; n < w_.pieces[p].nodeEnd; ++n) w_.awake.awakeNodes_.push_back(n);
            for (int32_t s = w_.pieces[p].surfBegin; s < w_.pieces[p].surfEnd; ++s) w_.awake.awakeSurf_.push_back(s);
            continue;
        }
        // Under MPI (Domain.hpp) a rank steps only what it owns: the tets it
        // computes, the nodes it integrates, the surface nodes whose obstacle
        // contacts it keeps.
        d->ownedTetRuns(static_cast<int32_t>(p), w_.awake.awakeTets_);
        for (int32_t n = w_.pieces[p].nodeBegin; n < w_.pieces[p].nodeEnd; ++n)
            if (d->owns(n)) w_.awake.awakeNodes_.push_back(n);
        for (int32_t s = w_.pieces[p].surfBegin; s < w_.pieces[p].surfEnd; ++s)
            if (d->owns(w_.surfNodes[s])) w_.awake.awakeSurf_.push_back(s);
    }
    w_.awake.obstacleSurf_.assign(w_.awake.awakeSurf_.begin(), w_.awake.awakeSurf_.end());
    w_.awake.obstacleSurf_.insert(w_.awake.obstacleSurf_.end(), held.begin(), held.end());
    w_.awake.everything_ = w_.awake.nAsleep_ == 0 && w_.awake.nRigid_ == 0 && !d;
}

void SleepPhase::wakeOne(std::size_t p) {
    w_.awake.asleep_[p] = 0;
    ++w_.awake.changes_[p];
    slowFor_[p] = 0;
    pieceSpeed2_[p] = 0;
    w_.awake.frozenReaction_[p].clear();
    ++wakeCount_;
}

void SleepPhase::wake(std::size_t p) {
    if (p < w_.awake.rigid_.size() && w_.awake.rigid_[p]) {  // deformable: its state may be written from outside
        w_.awake.rigid_[p] = 0;
        ++rigidSwitches_;
        awakeSetChanged();
        return;
    }
    if (p >= w_.awake.asleep_.size() || !w_.awake.asleep_[p] || w_.awake.held_[p]) return;
    wakeOne(p);
    awakeSetChanged();
}

void SleepPhase::wakeAll() {
    if (w_.awake.nAsleep_ == 0) return;
    bool changed = false;
    for (std::size_t p = 0; p < w_.awake.asleep_.size(); ++p)
        if (w_.awake.asleep_[p] && !w_.awake.held_[p]) {
            wakeOne(p);
            changed = true;
        }
    if (changed) awakeSetChanged();
}

void SleepPhase::setDynamic(std::size_t p, bool dynamic) {
    if (dynamic) {
        w_.awake.held_[p] = 0;
        wake(p);
        return;
    }
    w_.awake.held_[p] = 1;
    if (!w_.awake.asleep_[p]) {
        putToSleep(p);
        awakeSetChanged();
    }
    w_.bounds.update(true);  // its box is no longer updated by the step (and may not exist yet)
}

void SleepPhase::putToSleep(std::size_t p) {
    const PieceInfo& P = w_.pieces[p];
    // Velocities to zero: the kinetic energy left is booked as removed.
    // (Under MPI each rank books its own nodes' share: Domain::finishStep sums.)
    const Domain* dom = w_.domain.built();
    double ek = 0;
    for (int32_t n = P.nodeBegin; n < P.nodeEnd; ++n)
        for (int d = 0; d < 3; ++d) {
            double& v = w_.vel[3 * n + d];
            if (!dom || dom->owns(n)) ek += 0.5 * w_.mass[n] * v * v;
            v = 0;
        }
    if (w_.settings.trackEnergy) w_.energy.sleep += ek;
    // What it pushed on obstacles this step stays in their reactions.
    std::vector<double>& fr = w_.awake.frozenReaction_[p];
    fr.clear();
    const std::vector<int>& pieceObstacles_ = w_.obstacleContacts.pieceObstacles();
    const std::vector<int>& pieceObstacleBegin_ = w_.obstacleContacts.pieceObstacleBegin();
    const std::vector<double>& pairReaction_ = w_.obstacleContacts.pairReaction();
    if (pieceObstacleBegin_.size() == w_.pieces.size() + 1 && pairReaction_.size() == 6 * pieceObstacles_.size())
        for (int j = pieceObstacleBegin_[p]; j < pieceObstacleBegin_[p + 1]; ++j) {
            fr.push_back(pieceObstacles_[j]);
            fr.insert(fr.end(), &pairReaction_[6 * j], &pairReaction_[6 * j + 6]);
        }
    // How far it moved since the Verlet lists were built: other nodes may
    // only move the rest of half the skin before the lists are rebuilt.
    double m2 = 0;
    const PieceContactState& pc = w_.pieceContacts.state();
    if (pc.listValid && pc.listPos.size() == 3 * w_.surfNodes.size())
        for (int32_t s = P.surfBegin; s < P.surfEnd; ++s) {
            const int32_t n = w_.surfNodes[s];
            if (dom && !dom->current(n)) continue;  // this rank's lists hold current nodes only
            double d2 = 0;
            for (int d = 0; d < 3; ++d) d2 += std::pow(w_.pos[3 * n + d] - pc.listPos[3 * s + d], 2);
            m2 = std::max(m2, d2);
        }
    w_.awake.moved2_[p] = m2;
    w_.awake.asleep_[p] = 1;
    if (w_.awake.rigid_[p]) {  // asleep, then deformable when woken
        w_.awake.rigid_[p] = 0;
        ++rigidSwitches_;
    }
    ++w_.awake.changes_[p];
    ++sleepCount_;
}

void SleepPhase::run(double dt) {
    const std::size_t np = w_.pieces.size();
    const bool rigidChanged = switchRigid();
    if (!(w_.settings.sleepVelocity > 0)) {
        if (rigidChanged) awakeSetChanged();
        wakeAll();
        return;
    }
    const double v2 = w_.settings.sleepVelocity * w_.settings.sleepVelocity;
    // Largest node speed of each awake piece, from the integration (under
    // MPI the largest over the ranks: every rank then decides alike, as the
    // pieces' boxes, neighbours and obstacles are the global ones too).
    // (A speed that is not finite counts as infinite: the maximum of a NaN
    // depends on the order the ranks meet in, and ranks must decide alike
    // even in the step an error stops.)
    for (std::size_t p = 0; p < np; ++p) {
        const double s2 = w_.awake.asleep_[p] ? pieceSpeed2_[p] : w_.integration.maxSpeed2(p);
        pieceSpeed2_[p] = std::isnan(s2) ? std::numeric_limits<double>::infinity() : s2;
    }
    if (Domain* dom = w_.domain.built()) dom->comm().allreduceMax(pieceSpeed2_.data(), static_cast<int>(np));
    for (std::size_t p = 0; p < np; ++p) {
        if (w_.awake.asleep_[p]) continue;
        const double m = pieceSpeed2_[p];
        slowFor_[p] = m < v2 ? slowFor_[p] + dt : 0.0;
    }
    const PieceContactState& pc = w_.pieceContacts.state();
    const bool nbrsValid = pc.nbrStart.size() == np + 1 && w_.pieceContacts.anyKindOn() && np > 1;
    auto fastNeighbour = [&](std::size_t p) {
        if (!nbrsValid) return false;
        for (int32_t q = pc.nbrStart[p]; q < pc.nbrStart[p + 1]; ++q) {
            const int32_t b = pc.nbrs[q];
            if (!w_.awake.asleep_[b] && pieceSpeed2_[b] >= v2) return true;
        }
        return false;
    };
    const std::vector<int>& pieceObstacles_ = w_.obstacleContacts.pieceObstacles();
    const std::vector<int>& pieceObstacleBegin_ = w_.obstacleContacts.pieceObstacleBegin();
    auto movingObstacle = [&](std::size_t p) {
        if (pieceObstacleBegin_.size() != np + 1) return false;
        for (int j = pieceObstacleBegin_[p]; j < pieceObstacleBegin_[p + 1]; ++j) {
            const Obstacle& o = w_.obstacles[pieceObstacles_[j]];
            if (o.vel.squaredNorm() > 0 || o.angVel.squaredNorm() > 0) return true;
        }
        return false;
    };
    auto nearSphere = [&](std::size_t p) { return p < w_.spheres.pieceUsed.size() && w_.spheres.pieceUsed[p]; };
    auto candidate = [&](std::size_t p) {
        return !w_.awake.asleep_[p] && pieceSpeed2_[p] < v2 && slowFor_[p] >= w_.settings.sleepTime &&
               !fastNeighbour(p) && !movingObstacle(p) && !nearSphere(p);
    };
    // Slow is not at rest: a piece let go in the air, or at the top of a throw,
    // is slow for sleepVelocity / g seconds, and one driven slowly through its
    // blocked DOFs is slow for good.  A candidate sleeps only when it is held:
    // the net force on it (gravity, contacts, external; its internal forces
    // cancel) is below half its weight, or a blocked DOF holds it; and none of
    // its blocked DOFs is driven (a non-zero velocity there).  Under MPI each
    // rank sums its owned nodes and the sums go through the fixed-shape tree,
    // so every rank decides alike (the candidates are the same everywhere).
    bool anyCandidate = false;
    for (std::size_t p = 0; p < np && !anyCandidate; ++p) anyCandidate = candidate(p);
    if (anyCandidate) {
        restSums_.assign(6 * np, 0.0);  // per piece: net force (3), sum of |F| (1); then blocked, driven flags
        Domain* dom = w_.domain.built();
        for (std::size_t p = 0; p < np; ++p) {
            if (!candidate(p)) continue;
            const PieceInfo& info = w_.pieces[p];
            double* sum = &restSums_[4 * p];
            double* flag = &restSums_[4 * np + 2 * p];
            for (int32_t n = info.nodeBegin; n < info.nodeEnd; ++n) {
                if (dom && !dom->owns(n)) continue;
                const double* f = &w_.force[3 * n];
                sum[0] += f[0], sum[1] += f[1], sum[2] += f[2];
                sum[3] += std::abs(f[0]) + std::abs(f[1]) + std::abs(f[2]);
                const uint8_t bits = w_.blocked[n];
                if (!bits) continue;
                flag[0] = 1.0;
                for (int d = 0; d < 3; ++d)
                    if ((bits >> d) & 1 && w_.vel[3 * n + d] != 0) flag[1] = 1.0;
            }
        }
        if (dom) dom->comm().treeReduce(restSums_.data(), static_cast<int>(4 * np), static_cast<int>(2 * np));
    }
    const double g = w_.gravity.norm();
    auto held = [&](std::size_t p) {
        const double* sum = &restSums_[4 * p];
        const double* flag = &restSums_[4 * np + 2 * p];
        const double net = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        // (1e-9 of the force magnitudes: the rounding of the internal forces' cancellation)
        return flag[1] == 0 && (flag[0] > 0 || net <= 0.5 * w_.pieces[p].mass * g + 1e-9 * sum[3]);
    };
    bool changed = rigidChanged;
    for (std::size_t p = 0; p < np; ++p) {
        if (w_.awake.asleep_[p]) {
            if (!w_.awake.held_[p] && (fastNeighbour(p) || movingObstacle(p) || nearSphere(p))) {
                wakeOne(p);
                changed = true;
            }
        } else if (anyCandidate && candidate(p) && held(p)) {
            putToSleep(p);
            changed = true;
        }
    }
    if (changed) awakeSetChanged();
}

void SleepPhase::gravitySet(const Eigen::Vector3d& old, const Eigen::Vector3d& g) {
    const bool same = g == old || (gravityPending_ && g == loadedGravity_);
    gravityPending_ = false;
    if (!same) wakeAll();  // a sleeping piece would not feel the change
}

bool SleepPhase::obstaclesSet(const std::vector<double>& newSig, const std::vector<double>& oldSig) {
    const bool same = obstaclesPending_ ? newSig == loadedObstacles_ : newSig == oldSig;
    obstaclesPending_ = false;
    if (!same) wakeAll();  // frozen reactions are kept by obstacle index
    return same;
}

void SleepPhase::checkLoadedRest() {
    if (!obstaclesPending_ && !gravityPending_) return;
    const bool same = (!gravityPending_ || w_.gravity == loadedGravity_) &&
                      (!obstaclesPending_ || obstacleSignature(w_.obstacles) == loadedObstacles_);
    gravityPending_ = obstaclesPending_ = false;
    if (!same) wakeAll();
}

void SleepPhase::piecesAdded() {
    const std::size_t np = w_.pieces.size();
    w_.awake.asleep_.resize(np, 0);
    slowFor_.resize(np, 0);
    pieceSpeed2_.resize(np, 0);
    w_.awake.moved2_.resize(np, 0);
    w_.awake.changes_.resize(np, 0);
    w_.awake.held_.resize(np, 0);
    w_.awake.frozenReaction_.resize(np);
    w_.awake.rigid_.resize(np, 0);
    awakeSetChanged();  // tet count changed: the thread layout is rebuilt at the next step
}

void SleepPhase::stateColumns(StateColumns& c) {
    c.add("asleep", w_.awake.asleep_);
    c.add("slowFor", slowFor_);
    c.add("pieceSpeed2", pieceSpeed2_);
    c.add("sleepMoved2", w_.awake.moved2_);
}

void SleepPhase::saveFields(WorldState& s) const {
    std::vector<int64_t> start{0};  // frozen obstacle reactions, flattened
    std::vector<double> flat;
    for (const auto& fr : w_.awake.frozenReaction_) {
        flat.insert(flat.end(), fr.begin(), fr.end());
        start.push_back(static_cast<int64_t>(flat.size()));
    }
    s.put("frozenStart", start.data(), start.size());
    s.put("frozenReaction", flat.data(), flat.size());
    const std::vector<double> sig = obstacleSignature(w_.obstacles);
    s.put("obstacles", sig.data(), sig.size());
    s.put("gravity", w_.gravity.data(), 3);
    s.put("held", w_.awake.held_.data(), w_.awake.held_.size());
    s.put("rigid", w_.awake.rigid_.data(), w_.awake.rigid_.size());
    const int64_t switches = rigidSwitches_;
    s.put("rigidSwitches", &switches, 1);
}

void SleepPhase::checkFields(const WorldState& s) const {
    const std::vector<int64_t> fs = s.getAll<int64_t>("frozenStart");
    const std::vector<double> flat = s.getAll<double>("frozenReaction");
    if (fs.size() != w_.pieces.size() + 1 || fs.back() != static_cast<int64_t>(flat.size()))
        throw InputError("world state: field 'frozenStart' does not match the pieces");
    if (s.fields.count("held") > 0) s.check<uint8_t>("held", w_.awake.held_.size());
    if (s.fields.count("rigid") > 0) {
        s.check<uint8_t>("rigid", w_.awake.rigid_.size());
        s.check<int64_t>("rigidSwitches", 1);
        if (s.fields.count("rigidBody") == 0)
            throw InputError("world state: field 'rigid' without 'rigidBody' (the rigid pieces' states)");
    }
}

void SleepPhase::loadFields(const WorldState& s) {
    const std::vector<int64_t> fs = s.getAll<int64_t>("frozenStart");
    const std::vector<double> flat = s.getAll<double>("frozenReaction");
    for (std::size_t p = 0; p < w_.pieces.size(); ++p)
        w_.awake.frozenReaction_[p].assign(flat.begin() + fs[p], flat.begin() + fs[p + 1]);
    // (files from before Piece.dynamic have no "held")
    if (s.fields.count("held") > 0) s.get("held", w_.awake.held_.data(), w_.awake.held_.size());
    else std::fill(w_.awake.held_.begin(), w_.awake.held_.end(), 0);
    // (files from before adaptive rigidity: no piece rigid)
    if (s.fields.count("rigid") > 0) {
        s.get("rigid", w_.awake.rigid_.data(), w_.awake.rigid_.size());
        int64_t switches = 0;
        s.get("rigidSwitches", &switches, 1);
        rigidSwitches_ = switches;
    } else {
        std::fill(w_.awake.rigid_.begin(), w_.awake.rigid_.end(), 0);
    }
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
