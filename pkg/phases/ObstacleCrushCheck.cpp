// A piece crushed through itself against a box, a facet or a two-sided wall
// (doc/hard_cases.md, "Crushed through boxes and facets"): the obstacle holds
// the surface nodes (side memory pushes back those pushed through) while the
// inner nodes, which no contact sees, are driven past them and through it.
// Against a one-sided wall the depth behind the plane says it (ObstaclePhase
// .cpp); here an inner node's motion in this step is tested against the
// obstacle: crossing a facet's triangle or a two-sided wall's plane, or
// entering a box deeper than the contact radius (a plate thinner than twice
// the radius: crossing its mid-plane).  Caught the step it happens, before
// the elements it inverted blow up.
#include <algorithm>
#include <cmath>

#include "../contact/ContactModel.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "ObstacleCrushCheck.hpp"

namespace qdem {

namespace {

using Eigen::Vector3d;

// Does the segment a -> b (obstacle frame) meet the box |q_i| <= e_i?  Slab
// test; e_i may be 0 (a plane).
bool segmentMeetsBox(const Vector3d& a, const Vector3d& b, const Vector3d& e) {
    double t0 = 0, t1 = 1;
    for (int i = 0; i < 3; ++i) {
        const double d = b[i] - a[i];
        if (d == 0) {
            if (std::fabs(a[i]) > e[i]) return false;
            continue;
        }
        double lo = (-e[i] - a[i]) / d, hi = (e[i] - a[i]) / d;
        if (lo > hi) std::swap(lo, hi);
        t0 = std::max(t0, lo), t1 = std::min(t1, hi);
        if (t0 > t1) return false;
    }
    return true;
}

// Did an inner node that moved from `from` to `to` go through obstacle o
// (module comment)?  r: its piece's contact radius.
bool innerThrough(const Obstacle& o, const Vector3d& from, const Vector3d& to, double r) {
    if (o.kind != ObstacleKind::Box) return crossedThin(o, from, to);
    const Vector3d e = (o.halfExtents.array() - r).max(0.0).matrix();
    return segmentMeetsBox(o.rot.transpose() * (from - o.pos), o.rot.transpose() * (to - o.pos), e);
}

[[noreturn]] void reportInnerThrough(const ObstaclePhase::Data& w, std::size_t ip, int io, const PairConst& pc,
                                     int32_t node) {
    const PieceInfo& p = w.pieces[ip];
    const Obstacle& o = w.obstacles[io];
    const Material& m = w.materials[p.material];
    Vector3d momentum = Vector3d::Zero();
    double mass = 0;
    for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) {
        mass += w.mass[n];
        momentum += w.mass[n] * Eigen::Map<const Vector3d>(&w.vel[3 * static_cast<std::size_t>(n)]);
    }
    const Vector3d x(w.pos[3 * static_cast<std::size_t>(node)], w.pos[3 * static_cast<std::size_t>(node) + 1],
                     w.pos[3 * static_cast<std::size_t>(node) + 2]);
    const double speed = (momentum / mass - o.vel).norm();  // the piece's centre, against the obstacle
    const double wave = std::sqrt(m.young / m.density);
    const double stop = speed * std::sqrt(p.minSurfaceMassPerWeight / pairLaw(pc, 1.0).kn);
    const char* kind = o.kind == ObstacleKind::Box ? "box" : o.kind == ObstacleKind::Facet ? "facet" : "wall";
    throw StabilityError(cat(
        "QDEM: during step ", w.iter + 1, " inner node ", node - p.nodeBegin, " of piece ", ip, " went through the ",
        kind, " (YADE body ", o.bodyId, ", now ", distanceToSurface(o, x), " m from its surface): the piece was ",
        "crushed through itself against the ", kind, ", its inner nodes driven past the surface nodes the ", kind,
        " holds. The impact is too fast for its elements and contacts: its centre moves at ", speed,
        " m/s against the ", kind, ", ", speed / wave, " times the material's wave speed sqrt(E/rho) = ", wave,
        " m/s, and a surface node needs v sqrt(m/kn) = ", stop, " m to stop on its contact spring, against a ",
        "contact radius of ", m.radius, " m. Make the material stiffer (QdemMat young), the contact stiffer or ",
        "thicker (QdemMat radius), or the impact slower; a smaller O.dt does not hold a piece that cannot keep ",
        "its shape (doc/hard_cases.md, \"Crushed through boxes and facets\")."));
}

}  // namespace

void checkInnerNodesThrough(const ObstaclePhase::Data& w, const std::vector<int>& pieceObstacles,
                            const std::vector<int>& pieceObstacleBegin, const std::vector<PairConst>& pairConst,
                            std::vector<uint8_t>& surfaceNode, double dt) {
    const std::size_t nNodes = w.mass.size();
    if (surfaceNode.size() != nNodes) {
        surfaceNode.assign(nNodes, 0);
        for (std::size_t s = 0; s < w.surfNodes.size(); ++s) surfaceNode[w.surfNodes[s]] = 1;
    }
    for (std::size_t ip = 0; ip < w.pieces.size(); ++ip) {
        const int j0 = pieceObstacleBegin[ip], j1 = pieceObstacleBegin[ip + 1];
        bool any = false;
        for (int j = j0; j < j1 && !any; ++j) {
            const Obstacle& o = w.obstacles[pieceObstacles[j]];
            any = o.kind != ObstacleKind::Wall || o.sense == 0;
        }
        if (!any || w.sleeping.asleep(ip)) continue;
        const PieceInfo& p = w.pieces[ip];
        // The box of the inner nodes' paths this step: an obstacle whose box
        // it misses is passed by none (a piece resting on a facet floor keeps
        // its inner nodes an element above it: one pass, no per-node test).
        Vector3d lo = Vector3d::Constant(INFINITY), hi = -lo;
        for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) {
            if (surfaceNode[n]) continue;
            const Eigen::Map<const Vector3d> x(&w.pos[3 * static_cast<std::size_t>(n)]);
            const Eigen::Map<const Vector3d> v(&w.vel[3 * static_cast<std::size_t>(n)]);
            lo = lo.cwiseMin(x).cwiseMin(x - dt * v);
            hi = hi.cwiseMax(x).cwiseMax(x - dt * v);
        }
        if (!(lo[0] <= hi[0])) continue;  // no inner node
        const double r = w.materials[p.material].radius;
        for (int j = j0; j < j1; ++j) {
            const int io = pieceObstacles[j];
            const Obstacle& o = w.obstacles[io];
            if (o.kind == ObstacleKind::Wall && o.sense != 0) continue;  // (ObstaclePhase.cpp)
            const double grow = dt * o.vel.norm();  // (its translation this step; a spin is caught a step later)
            if ((lo.array() > o.hi.array() + grow).any() || (hi.array() < o.lo.array() - grow).any()) continue;
            for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) {
                if (surfaceNode[n]) continue;
                const Eigen::Map<const Vector3d> x(&w.pos[3 * static_cast<std::size_t>(n)]);
                const Eigen::Map<const Vector3d> v(&w.vel[3 * static_cast<std::size_t>(n)]);
                if (innerThrough(o, x - dt * (v - o.velocityAt(x, dt)), x, r))
                    reportInnerThrough(w, ip, io, pairConst[j], n);
            }
        }
    }
}

}  // namespace qdem
