// A piece that starts inside a YADE wall, box or facet is refused (issue 12):
// the contact spring would meet an overlap of many radii at once and throw the
// piece out (a one-sided floor launched a cube at 2.9 m/s), or a two-sided
// wall would hold the nodes past it on the wrong side.
//
// The check runs once per piece and obstacle: the first step after the
// piece is added, or the obstacle is (a new body, or a new shape of one), on
// the obstacles the piece can reach.  Contacts that grow during the run are
// the contact law's business, and a loaded state keeps its contacts: both are
// never refused here.  A piece resting on an obstacle overlaps it by less than
// the particle radius (its node centres are outside): it passes.  For a facet
// "past its surface" means behind the triangle (the foot of the node's
// perpendicular on its plane inside it), on the other side from the piece's
// centroid: a facet hanging beside or above a piece is not inside it.
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "../contact/ContactModel.hpp"
#include "../contact/Geometry.hpp"
#include "../core/Errors.hpp"
#include "../step/WorldState.hpp"
#include "ObstaclePhase.hpp"

namespace qdem {

namespace {

const char* kindName(const Obstacle& o) {
    switch (o.kind) {
        case ObstacleKind::Wall: return o.sense == 0 ? "two-sided wall" : "one-sided wall";
        case ObstacleKind::Box: return "box";
        case ObstacleKind::Facet: return "facet";
    }
    return "obstacle";
}

}  // namespace

namespace {

// An obstacle's identity for the start check: its body, kind and shape (a
// moved one, or one of another material, is the same: pieces meet it in the
// run).  16 numbers, also what the state saves per obstacle.
constexpr int kShapeNumbers = 16;

void shapeNumbers(const Obstacle& o, double* v) {
    v[0] = o.bodyId, v[1] = static_cast<int>(o.kind), v[2] = o.axis, v[3] = o.sense;
    for (int d = 0; d < 3; ++d) v[4 + d] = o.halfExtents[d];
    for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 3; ++d) v[7 + 3 * k + d] = o.localVerts[k][d];
}

std::string shapeKey(const double* v) {
    return std::string(reinterpret_cast<const char*>(v), kShapeNumbers * sizeof(double));
}

std::string shapeKey(const Obstacle& o) {
    double v[kShapeNumbers];
    shapeNumbers(o, v);
    return shapeKey(v);
}

}  // namespace

void ObstaclePhase::stateLoaded() {
    // A loaded state continues a run: its contacts are no set-up mistake, and
    // the obstacles its run had are known (loadFields); the list in force at
    // the next check is compared with them.
    startChecked_.assign(startChecked_.size(), 1);
    shapesPending_ = true;
}

void ObstaclePhase::saveFields(WorldState& s) const {
    std::vector<double> v(kShapeNumbers * w_.obstacles.size());
    for (std::size_t j = 0; j < w_.obstacles.size(); ++j) shapeNumbers(w_.obstacles[j], &v[kShapeNumbers * j]);
    s.put("obstacleShapes", v.data(), v.size());
}

void ObstaclePhase::loadFields(const WorldState& s) {
    checkedShapes_.clear();
    // (a state saved before the shapes were: every obstacle at the next check taken as known)
    adoptCurrent_ = s.fields.count("obstacleShapes") == 0;
    if (adoptCurrent_) return;
    const std::vector<double> v = s.getAll<double>("obstacleShapes");
    for (std::size_t i = 0; i + kShapeNumbers <= v.size(); i += kShapeNumbers) checkedShapes_.insert(shapeKey(&v[i]));
}

void ObstaclePhase::knowCurrentObstacles() {
    checkedShapes_.clear();
    for (const Obstacle& o : w_.obstacles) checkedShapes_.insert(shapeKey(o));
}

bool ObstaclePhase::updateFresh() {
    if (!shapesPending_) return false;
    shapesPending_ = false;
    if (adoptCurrent_) {
        adoptCurrent_ = false;
        knowCurrentObstacles();
    }
    freshObstacle_.assign(w_.obstacles.size(), 0);
    for (std::size_t j = 0; j < w_.obstacles.size(); ++j)
        freshObstacle_[j] = checkedShapes_.count(shapeKey(w_.obstacles[j])) == 0;
    return true;
}

void ObstaclePhase::checkStartOverlaps() {
    startChecked_.resize(w_.pieces.size(), 0);
    const bool listChanged = updateFresh();
    bool anyFresh = false;
    for (const uint8_t f : freshObstacle_) anyFresh = anyFresh || f;
    for (std::size_t ip = 0; ip < w_.pieces.size(); ++ip) {
        // A piece checked before meets only the obstacles added since.
        const bool onlyFresh = startChecked_[ip] != 0;
        if (onlyFresh && !anyFresh) continue;
        const PieceInfo& p = w_.pieces[ip];
        const double r = w_.materials[p.material].radius;
        // The side of two-sided walls and facets the piece is on: that of its centroid.
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (int32_t n = p.nodeBegin; n < p.nodeEnd; ++n) c += Eigen::Map<const Eigen::Vector3d>(&w_.pos[3 * n]);
        c /= double(p.nodeEnd - p.nodeBegin);
        for (int j = pieceObstacleBegin_[ip]; j < pieceObstacleBegin_[ip + 1]; ++j) {
            if (onlyFresh && !freshObstacle_[pieceObstacles_[j]]) continue;
            const Obstacle& o = w_.obstacles[pieceObstacles_[j]];
            int side = 0;
            if (o.kind == ObstacleKind::Wall && o.sense == 0) {
                side = c[o.axis] >= o.pos[o.axis] ? 1 : -1;
            } else if (o.kind == ObstacleKind::Facet) {
                const Eigen::Vector3d nf =
                    (o.worldVerts[1] - o.worldVerts[0]).cross(o.worldVerts[2] - o.worldVerts[0]);
                side = nf.dot(c - o.worldVerts[0]) >= 0 ? 1 : -1;
            }
            double depth = 0;  // how far the deepest node centre is past the obstacle's surface
            int nPast = 0;
            Eigen::Vector3d normal = Eigen::Vector3d::Zero();
            // Not past, but pressed in: the deepest spring compression and
            // the energy the springs hold (what throws a piece placed with
            // its mesh face flush on a floor: compression r, a full radius).
            double pressed = 0, stored = 0;
            Eigen::Vector3d pressedNormal = Eigen::Vector3d::Zero();
            // (a facet's unit normal, towards the piece)
            const Eigen::Vector3d facetNormal =
                o.kind == ObstacleKind::Facet
                    ? Eigen::Vector3d(side * (o.worldVerts[1] - o.worldVerts[0])
                                                 .cross(o.worldVerts[2] - o.worldVerts[0])
                                                 .normalized())
                    : Eigen::Vector3d::Zero();
            for (int32_t s = p.surfBegin; s < p.surfEnd; ++s) {
                const Eigen::Map<const Eigen::Vector3d> x(&w_.pos[3 * w_.surfNodes[s]]);
                // The node's spring compression and normal, and (d) how far
                // its centre is past the obstacle's surface, if it is.
                double ov = 0, d = 0;
                Eigen::Vector3d np = Eigen::Vector3d::Zero();
                bool past = false;
                if (o.kind == ObstacleKind::Facet) {
                    const TriPoint tp = closestOnTriangle(x, o.worldVerts[0], o.worldVerts[1], o.worldVerts[2]);
                    const double dist = (x - tp.point).norm();
                    ov = r - dist;
                    np = dist > 1e-12 * r ? Eigen::Vector3d((x - tp.point) / dist) : facetNormal;
                    // Past the triangle itself: on the far side of its plane
                    // with the foot of the perpendicular inside it.  (Not its
                    // plane: a node beside or below the triangle's edge, on the
                    // plane's far side, is not inside anything; one within r of
                    // the edge is an ordinary contact.  A fence whose lower edge
                    // hung 3 mm above a slab was refused as 58 nodes 9 cm deep.)
                    if (tp.feature == TriFeature::Face) {
                        d = -facetNormal.dot(x - tp.point);
                        past = true;
                    }
                } else {
                    ObstacleHit hit;
                    if (touchObstacle(o, x, r, side, hit)) {
                        ov = hit.overlap, np = hit.normal;
                        d = hit.overlap - r;
                        past = true;
                    }
                }
                if (ov > 0 && ov <= r) {
                    const double kn = w_.surfWeight[s] * pairLaw(pairConst_[j], w_.mass[w_.surfNodes[s]]).kn;
                    stored += 0.5 * kn * ov * ov;
                    if (ov > pressed) pressed = ov, pressedNormal = np;
                }
                if (!past) continue;
                const Eigen::Vector3d nd = o.kind == ObstacleKind::Facet ? facetNormal : np;
                if (!(d > 1e-9 * r)) continue;
                ++nPast;
                if (d > depth) {
                    depth = d;
                    normal = nd;
                }
            }
            if (nPast == 0) {
                if (pressed > 0.25 * r) {
                    // The piece rests where its springs carry its weight, a
                    // compression of m g / (n kn), a small part of r.
                    std::ostringstream m;
                    m.precision(3);
                    const double speed = std::sqrt(2 * stored / p.mass);
                    m << "qdem: piece " << ip << " starts pressed " << pressed << " m (" << 100 * pressed / r
                      << " % of its node radius " << r << " m) into obstacle body " << o.bodyId << " ("
                      << kindName(o) << "): its contact springs hold " << stored
                      << " J, enough to throw it off at up to " << speed
                      << " m/s. A piece's surface is its nodes' spheres, r outside the mesh: to start it at rest ";
                    if (std::fabs(pressedNormal[2]) > 0.999)
                        m << "place it " << pressed << " m " << (pressedNormal[2] > 0 ? "higher" : "lower")
                          << " (a block on a floor: centre at half its height + r)";
                    else
                        m << "move it " << pressed << " m along (" << pressedNormal[0] << ", " << pressedNormal[1]
                          << ", " << pressedNormal[2] << ")";
                    m << ".";
                    startWarnings_.push_back(m.str());
                }
                continue;
            }
            std::ostringstream m;
            m.precision(3);
            m << "piece " << ip << " starts inside obstacle body " << o.bodyId << " (" << kindName(o)
              << "): " << nPast << " of its " << (p.surfEnd - p.surfBegin)
              << " surface nodes are past its surface, the deepest by " << depth
              << " m; the contact would throw the piece out (or hold it across the obstacle) instead of "
                 "letting it rest. Move the piece out: ";
            const double clear = depth + r;  // node centres out, and their radius r clear of the surface
            if (std::fabs(normal[2]) > 0.999)  // straight up or down: say so
                m << "start it at least " << clear << " m " << (normal[2] > 0 ? "higher" : "lower");
            else
                m << "move it at least " << clear << " m along (" << normal[0] << ", " << normal[1] << ", "
                  << normal[2] << ")";
            m << " (depth + node radius " << r << " m), or move the obstacle";
            // (left unchecked: a script that catches this and runs again
            // unchanged, or moved not far enough, is refused again; it ran
            // and launched the piece)
            throw InputError(m.str());
        }
        startChecked_[ip] = 1;  // accepted (its warnings given once)
    }
    // Every piece accepted: the obstacles in force are the known ones now
    // (an obstacle erased and added again later is checked again).
    if (listChanged || anyFresh) knowCurrentObstacles();
    std::fill(freshObstacle_.begin(), freshObstacle_.end(), 0);
}

}  // namespace qdem
