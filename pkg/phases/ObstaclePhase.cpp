// Contacts of surface nodes with YADE walls, boxes and facets (rigid
// obstacles): which obstacles each piece can reach, the spring-dashpot and
// friction of each node contact with its history, and the reactions on the
// obstacles.  A piece that starts inside an obstacle is refused
// (ObstacleStartOverlap.cpp).
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../contact/ContactLoop.hpp"
#include "../contact/ContactModel.hpp"
#include "../core/Errors.hpp"
#include "../core/ThreadPartials.hpp"
#include "../core/Format.hpp"
#include "../step/AwakeSet.hpp"
#include "ContactKind.hpp"
#include "ContactLoad.hpp"
#include "ObstacleCrushCheck.hpp"
#include "ObstaclePhase.hpp"

namespace qdem {

namespace {

// A node of piece ip deeper behind one-sided wall io than the piece's own
// size: the piece was crushed through itself against the wall.  Named with
// the figures that say why (impact speed, wave speed, a surface node's
// stopping distance on its contact spring) and what would hold it.
[[noreturn]] void reportCrushedThrough(const ObstaclePhase::Data& w, std::size_t ip, int io, const PairConst& pc,
                                       double extent) {
    const PieceInfo& p = w.pieces[ip];
    const Obstacle& o = w.obstacles[io];
    const Material& m = w.materials[p.material];
    int32_t node = p.nodeBegin;
    double depth = -INFINITY, mass = 0, momentum = 0;
    for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) {
        const double d = depthBehind(o, Eigen::Map<const Eigen::Vector3d>(&w.pos[3 * static_cast<std::size_t>(n)]));
        if (d > depth) depth = d, node = n;
        mass += w.mass[n];
        momentum += w.mass[n] * w.vel[3 * static_cast<std::size_t>(n) + o.axis];
    }
    const double speed = std::max(0.0, -o.sense * momentum / mass);  // the piece's centre, towards the wall
    const double wave = std::sqrt(m.young / m.density);
    const double stop = speed * std::sqrt(p.minSurfaceMassPerWeight / pairLaw(pc, 1.0).kn);
    throw StabilityError(cat(
        "QDEM: during step ", w.iter + 1, " node ", node - p.nodeBegin, " of piece ", ip, " is ", depth,
        " m behind the one-sided wall (YADE body ", o.bodyId, "), more than the piece's own size (", extent,
        " m): the piece was crushed through itself against the wall, its inner nodes driven past the surface ",
        "nodes the wall holds. The impact is too fast for its elements and contacts: its centre moves at ", speed,
        " m/s towards the wall, ", speed / wave, " times the material's wave speed sqrt(E/rho) = ", wave,
        " m/s, and a surface node needs v sqrt(m/kn) = ", stop, " m to stop on its contact spring, against a ",
        "contact radius of ", m.radius, " m. Make the material stiffer (QdemMat young), the contact stiffer or ",
        "thicker (QdemMat radius), or the impact slower; a smaller O.dt does not hold a piece that cannot keep ",
        "its shape (doc/hard_cases.md, \"Found by the fuzzer\")."));
}

}  // namespace

// One thread's pass over its surface nodes: each node's touches with the
// obstacles its piece can reach, one touch per surface, the contacts
// (ContactLoop.hpp) with their history, reactions and energies.  The
// world's arrays as raw pointers in members of a local: the loop stores
// through int8_t pointers, which may alias anything, so members read
// through w_ would be reloaded.
struct ObstaclePhase::NodePass {
    const int32_t* surfNodes;
    const int32_t* nodePiece;
    const double* X;
    const double* V;
    const double* M;
    const double* W;
    const PieceInfo* pieces;
    const Material* materials;
    const Obstacle* obstacles;
    const int* pieceObstacles;
    const int* pieceObstacleBegin;
    const PairConst* pairConsts;
    int32_t* slotBody;
    double* slotShear;
    int8_t* slotSide;
    double* Fc;
    const double* extent;
    ContactLoop<true, Reference::None> loop;
    bool energyOn;
    // this thread's
    Through* through;
    Deepest* deepest;
    double* react;  // per (piece, obstacle) pair, 6 each
    double* pe;     // per piece energies (nullptr: energy not tracked)
    double* dyn;    // per (piece, obstacle) pair, kDyn each (nullptr: no dynamic obstacle)
    double* load;   // each surface node's contact springs (ContactForces::load; a node is one thread's)
    EnergyTally tally;
    double eBound = 0;
    long nWall = 0;

    NodePass(ObstaclePhase& ph, double dt, int th, std::size_t reactStride, std::size_t dynStride, double* loadRows)
        : surfNodes(ph.w_.surfNodes.data()),
          nodePiece(ph.w_.nodePiece.data()),
          X(ph.w_.pos.data()),
          V(ph.w_.vel.data()),
          M(ph.w_.mass.data()),
          W(ph.w_.surfWeight.data()),
          pieces(ph.w_.pieces.data()),
          materials(ph.w_.materials.data()),
          obstacles(ph.w_.obstacles.data()),
          pieceObstacles(ph.pieceObstacles_.data()),
          pieceObstacleBegin(ph.pieceObstacleBegin_.data()),
          pairConsts(ph.pairConst_.data()),
          slotBody(ph.slotBody_.data()),
          slotShear(ph.slotShear_.data()),
          slotSide(ph.slotSide_.data()),
          Fc(ph.w_.contacts.force.data()),
          extent(ph.pieceExtent_.data()),
          loop(dt, ph.w_.settings.frictionModel == FrictionModel::Regularized, ph.w_.settings.frictionRegVelocity,
               ph.w_.settings.frictionOn),
          energyOn(ph.w_.settings.trackEnergy),
          through(&ph.threadThrough_[th]),
          deepest(&ph.threadDeepest_[th]),
          react(ph.threadReaction_.data() + static_cast<std::size_t>(th) * reactStride),
          pe(energyOn ? ph.w_.threadPieceEnergy[th].data() : nullptr),
          dyn(dynStride ? ph.threadDynamic_.data() + static_cast<std::size_t>(th) * dynStride : nullptr),
          load(loadRows) {}

    struct Touch {
        int j, slot;
        ObstacleHit hit;
    };
    __attribute__((always_inline)) int findTouches(int32_t s, int32_t node, int ip, double radius,
                                                   const int32_t* body, const int8_t* side, Touch* touch);
    __attribute__((always_inline)) uint32_t sameSurface(const Touch* touch, int nt, double radius) const;
    __attribute__((always_inline)) void node(int32_t s);
};

// The obstacles node (surface node s, piece ip) touches; notes the first
// node that went through one.
inline int ObstaclePhase::NodePass::findTouches(int32_t s, int32_t node, int ip, double radius, const int32_t* body,
                                               const int8_t* side, Touch* touch) {
    const double dt = loop.dt();
    const Eigen::Map<const Eigen::Vector3d> x(X + 3 * node);
    const Eigen::Map<const Eigen::Vector3d> v(V + 3 * node);
    int nt = 0;
    for (int j = pieceObstacleBegin[ip]; j < pieceObstacleBegin[ip + 1]; ++j) {
        const int io = pieceObstacles[j];
        const Obstacle& o = obstacles[io];
        const int slot = matchSlot(kSlots, [&](int k) { return body[k] == o.bodyId; });
        // Went through it?  (Checked before the contact: a node that
        // jumped past a thin obstacle is not touching it any more.)
        // (Thin ones only for nodes that did not touch them last
        // step: side memory holds those that did.)
        if (through->node < 0 || node < through->node) {
            const bool thinKind = o.kind == ObstacleKind::Facet || (o.kind == ObstacleKind::Wall && o.sense == 0);
            const bool thin = slot < 0 && thinKind && crossedThin(o, x - dt * (v - o.velocityAt(x, dt)), x);
            const double depth = depthBehind(o, x);
            if (thin || depth > extent[ip]) {
                const double speed = (v - o.velocityAt(x, dt)).norm();
                *through = Through{node, ip, io, thin, dt * speed, depth, speed, M[node],
                                   W[s] * pairLaw(pairConsts[j], M[node]).kn};
            }
        }
        if (nt == kTouches) continue;  // (more than kTouches bodies at once: never seen)
        // Out of the body's box grown by the radius, and no history
        // with it (side memory may hold a node pushed deep): no touch.
        // Every obstacle near the piece is visited per node: a block on
        // the 64-facet fan of a facetCylinder's bottom spent ~25 ns on
        // each (node, facet) pair, where this test costs a few.
        if (slot < 0 && o.kind != ObstacleKind::Wall &&
            ((x.array() + radius < o.lo.array()).any() || (x.array() - radius > o.hi.array()).any()))
            continue;
        if (touchObstacle(o, x, radius, slot >= 0 ? side[slot] : 0, touch[nt].hit)) {
            touch[nt].j = j;
            touch[nt].slot = slot;
            ++nt;
        }
    }
    return nt;
}

// One surface made of several bodies (an STL's facets, boxes side by side, a
// facet on a wall's plane) is touched once: a touch whose contact point lies
// on another touched body's surface, that body being nearer (larger overlap;
// equal: the first), is that body's touch seen again (the closest point on
// the edge they share).  Each body counted for itself, a node near a seam of
// a flat facet floor was pushed by both facets: the seams were stiffer, a
// block rested tilted and a frictionless block slid slower over them (a
// tester).  A touch at a point of its own (a concave corner, a gap between
// two boxes) stays.  Returns the touches dropped, as bits.
inline uint32_t ObstaclePhase::NodePass::sameSurface(const Touch* touch, int nt, double radius) const {
    uint32_t dropped = 0;
    const double onSurface = 1e-6 * radius;
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < nt; ++b) {
            if (b == a) continue;
            const double oa = touch[a].hit.overlap, ob = touch[b].hit.overlap;
            if (ob > oa || (ob == oa && b < a))
                if (distanceToSurface(obstacles[pieceObstacles[touch[b].j]], touch[a].hit.point) <= onSurface) {
                    dropped |= 1u << a;
                    break;
                }
        }
    return dropped;
}

// Surface node s's contacts with the obstacles.
inline void ObstaclePhase::NodePass::node(int32_t s) {
    const double dt = loop.dt();
    const int32_t node = surfNodes[s];
    const int ip = nodePiece[node];
    int32_t* body = slotBody + kSlots * s;
    double* shear = slotShear + 3 * kSlots * s;
    int8_t* side = slotSide + kSlots * s;
    if (pieceObstacleBegin[ip] == pieceObstacleBegin[ip + 1]) {  // nothing near this piece: forget the history
        for (int k = 0; k < kSlots; ++k) body[k] = -1;
        return;
    }
    const Material& m = materials[pieces[ip].material];
    const Eigen::Map<const Eigen::Vector3d> v(V + 3 * node);
    // The obstacles this node touches, then which of them are one touch of
    // one surface.
    Touch touch[kTouches];
    const int nt = findTouches(s, node, ip, m.radius, body, side, touch);
    const uint32_t dropped = nt > 1 ? sameSurface(touch, nt, m.radius) : 0;
    bool oldTaken[kSlots] = {false, false, false, false};
    for (int t = 0; t < nt; ++t)
        if (!(dropped >> t & 1u) && touch[t].slot >= 0) oldTaken[touch[t].slot] = true;
    int32_t newBody[kSlots];
    int8_t newSide[kSlots];
    NewSlots<kSlots> news;
    Eigen::Vector3d fNode = Eigen::Vector3d::Zero();
    for (int t = 0; t < nt; ++t) {
        if (dropped >> t & 1u) continue;
        if (news.full()) break;  // a node never touches more than 4 bodies at once in practice
        const int j = touch[t].j;
        const Obstacle& o = obstacles[pieceObstacles[j]];
        const ObstacleHit& hit = touch[t].hit;
        int slot = touch[t].slot;
        if (slot < 0)  // a new touch takes the spring of one that ended this step: a node sliding
            for (int k = 0; k < kSlots && slot < 0; ++k)  // from facet to facet keeps its friction
                if (body[k] >= 0 && !oldTaken[k]) oldTaken[slot = k] = true;
        // Springs scaled by the node's share of the surface area
        // (surfWeight, World.hpp); the dashpots keep their damping ratio.
        // Their mass is the node's, reduced with a dynamic obstacle's
        // at the contact point (1/g: its mobility there), as for two
        // pieces or a sphere: a node's dashpot on a 2 g box kicked it.
        // (The regularised friction's implicit drag too.)
        const double g = o.dynamic() ? o.mobilityAt((hit.point - o.pos).norm()) : 0.0;
        const double mEff = g > 0 ? M[node] / (1 + M[node] * g) : M[node];
        const double wa = W[s];
        const Eigen::Vector3d vo = o.velocityAt(hit.point, dt);
        ContactGeometry geo;
        geo.n = hit.normal;
        geo.overlap = hit.overlap;
        geo.vRel = v - vo;
        geo.spin = o.angVel.dot(hit.normal);  // a node is a point: the obstacle's spin alone
        geo.mass = geo.slipMass = mEff;
        geo.stiffWeight = wa, geo.dampWeight = std::sqrt(wa);
        ContactHistory h;
        if (slot >= 0) h.shear = shear + 3 * slot;
        newBody[news.n] = o.bodyId;
        newSide[news.n] = static_cast<int8_t>(hit.side);
        ContactParams cp;
        const ContactResult r = loop.touch(pairConsts[j], geo, h, news, pe ? pe + 3 * ip + 1 : nullptr,
                                           energyOn ? &tally : nullptr, &cp);
        if (hit.overlap > deepest->ratio * m.radius)
            *deepest = Deepest{hit.overlap / m.radius, pieceObstacles[j], static_cast<int>(ip)};
        ++nWall;
        fNode += r.force;
        addObstacleContactLoad(load, s, M[node] * g, cp, loop.turns(pairConsts[j]));
        double* R = react + 6 * j;
        if (dyn && o.dynamic()) {
            // Its springs and dashpots on the obstacle's mobility at the
            // contact point, and on the node's mass.
            const double k = std::max(cp.kn, cp.kt), c = std::max(cp.cn, cp.ct);
            double* D = dyn + kDyn * j;
            D[0] += g * k;
            D[1] += g * c;
            D[2] = std::max(D[2], k / M[node]);
            D[3] = std::max(D[3], c / M[node]);
            D[4] += 1;
        }
        const Eigen::Vector3d torque = (hit.point - o.pos).cross(-r.force);
        for (int d = 0; d < 3; ++d) {
            R[d] -= r.force[d];
            R[3 + d] += torque[d];
        }
        if (energyOn) eBound -= r.force.dot(vo) * dt;
    }
    for (int k = 0; k < kSlots; ++k) {
        body[k] = k < news.n ? newBody[k] : -1;
        side[k] = k < news.n ? newSide[k] : 0;
    }
    news.store(shear, nullptr);
    for (int d = 0; d < 3; ++d) Fc[3 * node + d] += fNode[d];
}

void ObstaclePhase::run(double dt) {
    const int nObs = static_cast<int>(w_.obstacles.size());
    for (auto& o : w_.obstacles) {
        o.reactionForce.setZero();
        o.reactionTorque.setZero();
    }
    // Sleeping pieces still push on obstacles with what they pushed when
    // they fell asleep (a moving obstacle near one wakes it).  Held pieces
    // (dynamic = False, which nothing wakes) touch obstacles as a fixed
    // body: their contacts are computed every step, below.  With only
    // their push at the hold, a box dropped on a held block fell through
    // it and a platen driven into it met no force.
    for (std::size_t p = 0; p < w_.pieces.size(); ++p) {
        if (!w_.sleeping.dynamic(p)) continue;
        const std::vector<double>& fr = w_.sleeping.frozenReaction(p);
        for (std::size_t k = 0; k + 7 <= fr.size(); k += 7) {
            Obstacle& o = w_.obstacles[static_cast<int>(fr[k])];
            o.reactionForce += Eigen::Vector3d(fr[k + 1], fr[k + 2], fr[k + 3]);
            o.reactionTorque += Eigen::Vector3d(fr[k + 4], fr[k + 5], fr[k + 6]);
        }
    }
    pieceObstacles_.clear();
    pieceObstacleBegin_.clear();
    pairConst_.clear();
    pairReaction_.clear();
    contacts_ = 0;
    if (!kindSwitchedOn(contactKind(ContactFamily::PieceObstacle), w_.settings)) {
        // Switched off (QdemEngine couple=False): no contact, no push of a
        // sleeping piece, and no spring carried over to when it is on again.
        for (auto& o : w_.obstacles) o.reactionForce.setZero(), o.reactionTorque.setZero();
        slotBody_.fill(-1);
        return;
    }
    if (nObs == 0 || w_.surfNodes.size() == 0) return;

    listReachable();
    checkStartOverlaps();
    if (pieceObstacles_.empty()) return;
    w_.contacts.begin();
    const int nth = omp_get_max_threads();
    const std::array<double, 3> energySum = contactPass(dt, nth);
    finishStep(dt, nth, energySum);
}

// Which obstacles can each piece reach this step (bounding boxes + radius)?
void ObstaclePhase::listReachable() {
    const int nObs = static_cast<int>(w_.obstacles.size());
    pieceObstacleBegin_.assign(w_.pieces.size() + 1, 0);
    pieceObstacles_.clear();
    for (std::size_t ip = 0; ip < w_.pieces.size(); ++ip) {
        const Eigen::Map<const Eigen::Vector3d> lo(&w_.bounds.lo[3 * ip]), hi(&w_.bounds.hi[3 * ip]);
        const double r = w_.materials[w_.pieces[ip].material].radius;
        for (int i = 0; i < nObs; ++i) {
            const Obstacle& o = w_.obstacles[i];
            bool near;
            if (o.kind == ObstacleKind::Wall) {
                // The piece's box is already grown by r; a centre within r of
                // the plane (on an allowed side) can touch it.
                // A one-sided wall is a half-space: a piece anywhere behind
                // it is touched (and pushed out, or refused at the start).
                const double w = o.pos[o.axis];
                if (o.sense > 0) near = lo[o.axis] <= w + r;
                else if (o.sense < 0) near = hi[o.axis] >= w - r;
                else near = lo[o.axis] <= w + r && hi[o.axis] >= w - r;
            } else {
                near = (lo.array() <= o.hi.array()).all() && (hi.array() >= o.lo.array()).all();
            }
            if (near) {
                pieceObstacles_.push_back(i);
                // The pair's constants (ContactModel.hpp), once per step.
                const Material& m = w_.materials[w_.pieces[ip].material];
                pairConst_.push_back(mix(materialSide(m, m.frictionWall), obstacleSide(o.young, o.friction, m.radius)));
            }
        }
        pieceObstacleBegin_[ip + 1] = static_cast<int>(pieceObstacles_.size());
    }
}

// The node contacts of the awake pieces, in parallel: forces into
// ContactForces, reactions per thread and (piece, obstacle) pair; returns
// the energies (damping, slip, boundary work) added in thread order.
std::array<double, 3> ObstaclePhase::contactPass(double dt, int nth) {
    // Reactions per thread and (piece, obstacle) pair: a piece that falls
    // asleep keeps its own.
    const std::size_t nPairs = pieceObstacles_.size();
    // Each thread's block rounded up to whole cache lines (8 doubles), one
    // line apart: two threads adding reactions into a shared line would hand
    // it back and forth on every contact.
    const std::size_t reactStride = (nPairs * 6 + 7) / 8 * 8 + 8;
    threadReaction_.assign(static_cast<std::size_t>(nth) * reactStride, 0.0);
    // Sleeping pieces' nodes are skipped (their history kept as it is);
    // held pieces' are not (above).  (Their velocities are zero: a held
    // node is a fixed point.)
    const bool all = w_.sleeping.everything();
    const int32_t* awakeSurf = w_.sleeping.obstacleSurf().data();
    const auto nSurf =
        all ? static_cast<int32_t>(w_.surfNodes.size()) : static_cast<int32_t>(w_.sleeping.obstacleSurf().size());
    // Dynamic obstacles: the springs on each (piece, obstacle) pair, per
    // thread (checkDynamicObstacles).
    bool anyDynamic = false;
    for (const Obstacle& o : w_.obstacles) anyDynamic = anyDynamic || o.dynamic();
    const std::size_t dynStride = anyDynamic ? kDyn * nPairs + 8 : 0;
    threadDynamic_.assign(static_cast<std::size_t>(nth) * dynStride, 0.0);
    // Each piece's largest extent (its box less the radius it was grown by):
    // a node deeper than that behind a one-sided wall has taken the piece
    // through the solid.  (Not half the thickness, as point-polygon's "past
    // the middle": a rubber cube hitting a floor at 50 m/s pushes nodes 45 %
    // of its size behind the plane and still comes back, test_hard_cases.py.)
    // At most its rest shape's diagonal: a piece crushed through itself
    // spreads its box with the nodes that went through, and a box-only
    // bound grew with them (a soft cube at 9 times its wave speed, nodes
    // 0.27 m behind the wall, its box 0.47 m: unnamed until a NaN).
    pieceExtent_.resize(w_.pieces.size());
    if (restDiagonal_.size() != w_.pieces.size()) measureRestShapes();  // (pieces from a loaded state)
    for (std::size_t ip = 0; ip < w_.pieces.size(); ++ip) {
        const double r = w_.materials[w_.pieces[ip].material].radius;
        double e = 0;
        for (int d = 0; d < 3; ++d) e = std::max(e, w_.bounds.hi[3 * ip + d] - w_.bounds.lo[3 * ip + d] - 2 * r);
        pieceExtent_[ip] = std::min(e, restDiagonal_[ip]);
    }
    double* const load = w_.contacts.beginLoad();  // each node's springs: the run-time stable step (ContactLoad.hpp)
    threadThrough_.assign(nth, Through{});
    threadDeepest_.assign(nth, Deepest{});
    long nWall = 0;
    ThreadPartials<3> energyParts(nth);  // damping, slip, boundary work: added in thread order
#pragma omp parallel num_threads(nth) reduction(+ : nWall)
    {
        const int th = omp_get_thread_num();
        NodePass pass(*this, dt, th, reactStride, dynStride, load);
        // Halves of the surface nodes, as the contact sums and the
        // integration split them: each thread meets the force lines it will
        // touch again.  (Chunks dealt round-robin balanced scenes whose floor
        // pieces come first, but cost the 27-cube stack 15-25 % here: lines
        // passed between the cores, bench/logs/obstacle_deal_2026-11-24.txt.)
#pragma omp for schedule(static) nowait  // (the region ends with the loop: its join is the barrier)
        for (int32_t i = 0; i < nSurf; ++i) pass.node(all ? i : awakeSurf[i]);
        nWall += pass.nWall;
        energyParts.set(th, {pass.tally.damp, pass.tally.slip, pass.eBound});
    }
    contacts_ = nWall;
    return energyParts.sum();
}

// After the pass: the checks (a soft obstacle, a node through an obstacle,
// a piece crushed through itself, a dynamic obstacle launched), the
// reactions summed in thread order, the energies booked.
void ObstaclePhase::finishStep(double dt, int nth, const std::array<double, 3>& energySum) {
    const std::size_t nPairs = pieceObstacles_.size();
    const std::size_t reactStride = threadReaction_.size() / nth;
    const std::size_t dynStride = threadDynamic_.size() / nth;
    Deepest deepest;
    for (const Deepest& d : threadDeepest_)
        if (d.ratio > deepest.ratio) deepest = d;
    if (deepest.ratio > 0.5) warnSoftObstacle(deepest);
    const Through* first = nullptr;
    for (const Through& t : threadThrough_)
        if (t.node >= 0 && (!first || t.node < first->node)) first = &t;
    if (first) reportThrough(*first, dt);
    // An inner node deeper behind a one-sided wall than its piece's extent
    // (the pieces' boxes hold the surface nodes only): inner nodes of a soft
    // cube at nine times its wave speed went 0.27 m behind the wall while
    // the wall held its surface nodes, unnamed until a NaN twenty steps
    // later.  One compare per node.
    for (std::size_t ip = 0; ip < w_.pieces.size(); ++ip)
        for (int j = pieceObstacleBegin_[ip]; j < pieceObstacleBegin_[ip + 1]; ++j) {
            const Obstacle& o = w_.obstacles[pieceObstacles_[j]];
            if (o.kind != ObstacleKind::Wall || o.sense == 0 || w_.sleeping.asleep(ip)) continue;
            const double* x = w_.pos.data() + o.axis;
            const double limit = o.sense * o.pos[o.axis] - pieceExtent_[ip];  // deeper: sense * x below it
            bool deep = false;
            for (int32_t n = w_.pieces[ip].nodeBegin; n < w_.pieces[ip].nodeEnd; ++n)
                deep |= o.sense * x[3 * static_cast<std::size_t>(n)] < limit;
            if (deep) reportCrushedThrough(w_, ip, pieceObstacles_[j], pairConst_[j], pieceExtent_[ip]);
        }
    // Inner nodes through a box, facet or two-sided wall: the same, where no
    // depth says it (ObstacleCrushCheck.cpp).
    checkInnerNodesThrough(w_, pieceObstacles_, pieceObstacleBegin_, pairConst_, surfaceNode_, dt);
    if (dynStride) checkDynamicObstacles(dt, dynStride);
    pairReaction_.assign(6 * nPairs, 0.0);
    for (int th = 0; th < nth; ++th)
        for (std::size_t j = 0; j < 6 * nPairs; ++j)
            pairReaction_[j] += threadReaction_[static_cast<std::size_t>(th) * reactStride + j];
    for (std::size_t j = 0; j < nPairs; ++j) {
        const double* R = &pairReaction_[6 * j];
        Obstacle& o = w_.obstacles[pieceObstacles_[j]];
        o.reactionForce += Eigen::Vector3d(R[0], R[1], R[2]);
        o.reactionTorque += Eigen::Vector3d(R[3], R[4], R[5]);
    }
    if (w_.settings.trackEnergy) {
        w_.energy.contactDamping += energySum[0];
        w_.energy.friction += energySum[1];
        w_.energy.boundaryWork += energySum[2];
    }
}

void ObstaclePhase::checkDynamicObstacles(double dt, std::size_t stride) const {
    const std::size_t nPairs = pieceObstacles_.size();
    const int nth = static_cast<int>(threadDynamic_.size() / stride);
    std::vector<double> sum(kDyn * w_.obstacles.size(), 0.0);
    for (int th = 0; th < nth; ++th)
        for (std::size_t j = 0; j < nPairs; ++j) {
            const double* D = &threadDynamic_[th * stride + kDyn * j];
            double* S = &sum[kDyn * pieceObstacles_[j]];
            S[0] += D[0], S[1] += D[1], S[4] += D[4];
            S[2] = std::max(S[2], D[2]);
            S[3] = std::max(S[3], D[3]);
        }
    for (std::size_t i = 0; i < w_.obstacles.size(); ++i) {
        const double* S = &sum[kDyn * i];
        if (S[4] == 0) continue;
        // As World::dynamicObstacleLimit, on the springs that act now.
        const double w2 = S[0] + S[2];
        const double limit =
            std::isfinite(w2) ? leapfrogLimit(std::sqrt(w2), (S[1] + S[3]) / (2 * std::sqrt(w2))) : 0.0;
        if (limit >= dt) continue;
        const Obstacle& o = w_.obstacles[i];
        throw StabilityError(cat(
            "QDEM: during step ", w_.iter + 1, " the dynamic ", describeDynamic(o), " is touched by ", S[4],
            " surface nodes: their contact springs and dashpots on its mass make its stable time step ", limit,
            " s, below O.dt = ", dt, " s (a light body on stiff springs is launched; the limit before the run ",
            "counted fewer nodes, or none of a body that was fixed then). Lower O.dt below ", limit, " s, ",
            std::isfinite(o.invMass) && std::isfinite(o.invInertia)
                ? "make the body heavier"
                : "give the body a mass and moment of inertia (b.state.mass, b.state.inertia)",
            ", or fix it (fixed=True, or b.dynamic = False)."));
    }
}

void ObstaclePhase::warnSoftObstacle(const Deepest& d) {
    // A YADE body's material sets the contact's stiffness with the piece's
    // (the harmonic mean of E r, ContactModel.hpp): a body left with YADE's
    // default material (E = 1e7 Pa) under a stiff or large piece lets its
    // nodes sink most of their radius into it (a 100 m piece, E = 5e8:
    // 4.1 m of 5 m; a tester), as the materials say but rarely as meant.
    // Named when the body is ten times softer than the piece and a node sinks
    // more than half its radius: impacts of a piece on a body as stiff as
    // itself sink that deep and are not warned of.
    const Obstacle& o = w_.obstacles[d.obstacle];
    const Material& m = w_.materials[w_.pieces[d.piece].material];
    if (!(o.young > 0 && o.young < 0.1 * m.young)) return;
    if (!softWarned_.insert({o.bodyId, d.piece}).second) return;
    const char* kind = o.kind == ObstacleKind::Wall ? "wall" : o.kind == ObstacleKind::Box ? "box" : "facet";
    startWarnings_.push_back(cat(
        "qdem: nodes of piece ", d.piece, " sink ", static_cast<int>(std::lround(100 * d.ratio)),
        " % of their contact radius (", m.radius, " m) into YADE body ", o.bodyId, " (", kind,
        "), whose material (young = ", o.young, " Pa) is ", std::lround(m.young / o.young),
        " times softer than the piece's (", m.young, " Pa): the contact takes the softer stiffness. If the body "
        "is meant to be stiff, give it a material as stiff as the piece, e.g. mat = O.materials.append(FrictMat("
        "young=", m.young, ")) and utils.", kind, "(..., material=mat)"));
}

void ObstaclePhase::reportThrough(const Through& t, double dt) const {
    const Obstacle& o = w_.obstacles[t.obstacle];
    const char* kind = o.kind == ObstacleKind::Wall ? (o.sense != 0 ? "one-sided wall" : "wall")
                       : o.kind == ObstacleKind::Box ? "box" : "facet";
    const double r = w_.materials[w_.pieces[t.piece].material].radius;
    const std::string where = cat("QDEM: during step ", w_.iter + 1, " node ", t.node - w_.pieces[t.piece].nodeBegin,
                                  " of piece ", t.piece, " went through the ", kind, " (YADE body ", o.bodyId, ")");
    if (t.thin)
        throw StabilityError(cat(where, " without touching it: it moved ", t.travel, " m in this step (relative speed ",
                                 t.speed, " m/s, dt = ", dt, " s) from one side to the other, and its contact ",
                                 "zone is only r = ", r, " m thick. Lower O.dt or the speed, or make the contact ",
                                 "zone thicker (QdemMat radius)."));
    const double stop = t.speed * std::sqrt(t.mass / t.kn);
    throw StabilityError(cat(where, ": it is ", t.depth, " m behind the wall's plane, more than the piece's largest ",
                             "extent (", pieceExtent_[t.piece], " m, at most its rest shape's diagonal). The contact ",
                             "is too soft for this load: ",
                             "stopping distance v sqrt(m_node/kn) = ", stop, " m at ", t.speed, " m/s (node mass ",
                             t.mass, " kg, kn ", t.kn, " N/m). Make the contact stiffer (kn = E r: a larger QdemMat ",
                             "young or radius), the impact slower, or check the mesh's units (a mesh in mm with SI ",
                             "material values is 1000 times too large)."));
}

void ObstaclePhase::stateColumns(StateColumns& c) {
    c.add("slotBody", slotBody_, Rows::SurfaceNode);
    c.add("slotShear", slotShear_, Rows::SurfaceNode);
    c.add("slotSide", slotSide_, Rows::SurfaceNode);
}

void ObstaclePhase::addLoadWeights(double* perNode, double work) const {
    const std::size_t ns = w_.surfNodes.size();
    for (std::size_t i = 0; i < ns; ++i)
        for (int j = 0; j < kSlots; ++j)
            if (slotBody_[kSlots * i + j] >= 0) perNode[w_.surfNodes[i]] += work;
}

void ObstaclePhase::piecesAdded() {
    const std::size_t ns = w_.surfNodes.size();
    slotBody_.resize(kSlots * ns, -1);
    slotShear_.resize(3 * kSlots * ns, 0.0);
    slotSide_.resize(kSlots * ns, 0);
    startChecked_.resize(w_.pieces.size(), 0);
    measureRestShapes();
}

void ObstaclePhase::measureRestShapes() {
    restDiagonal_.resize(w_.pieces.size());
    for (std::size_t ip = 0; ip < w_.pieces.size(); ++ip) {
        const PieceInfo& p = w_.pieces[ip];
        Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
        for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) {
            const Eigen::Map<const Eigen::Vector3d> x(&w_.refPos[3 * static_cast<std::size_t>(n)]);
            lo = lo.cwiseMin(x);
            hi = hi.cwiseMax(x);
        }
        restDiagonal_[ip] = p.nodeEnd > p.nodeBegin ? (hi - lo).norm() : INFINITY;
    }
}

}  // namespace qdem
