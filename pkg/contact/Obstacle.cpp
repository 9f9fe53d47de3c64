#include "Obstacle.hpp"

#include "Geometry.hpp"
#include "../core/Format.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace qdem {

using Eigen::Vector3d;

std::vector<double> obstacleSignature(const std::vector<Obstacle>& obstacles) {
    std::vector<double> sig;
    sig.reserve(18 * obstacles.size());
    for (const Obstacle& o : obstacles) {
        sig.insert(sig.end(), {static_cast<double>(o.kind), static_cast<double>(o.bodyId), o.young, o.friction,
                               static_cast<double>(o.axis), static_cast<double>(o.sense)});
        sig.insert(sig.end(), o.halfExtents.data(), o.halfExtents.data() + 3);
        for (const auto& v : o.localVerts) sig.insert(sig.end(), v.data(), v.data() + 3);
    }
    return sig;
}

void Obstacle::updateDerived() {
    rot = ori.normalized().toRotationMatrix();
    const double inf = std::numeric_limits<double>::infinity();
    switch (kind) {
        case ObstacleKind::Wall:
            lo = Vector3d::Constant(-inf);
            hi = Vector3d::Constant(inf);
            break;
        case ObstacleKind::Box: {
            const Vector3d ext = rot.cwiseAbs() * halfExtents;
            lo = pos - ext;
            hi = pos + ext;
            break;
        }
        case ObstacleKind::Facet:
            for (int k = 0; k < 3; ++k) worldVerts[k] = pos + rot * localVerts[k];
            lo = worldVerts[0].cwiseMin(worldVerts[1]).cwiseMin(worldVerts[2]);
            hi = worldVerts[0].cwiseMax(worldVerts[1]).cwiseMax(worldVerts[2]);
            break;
    }
}

std::string describeDynamic(const Obstacle& o) {
    const char* kind = o.kind == ObstacleKind::Wall ? "wall" : o.kind == ObstacleKind::Box ? "box" : "facet";
    std::string what;
    if (o.invMass > 0) what = cat("mass ", 1 / o.invMass, " kg");
    else what = "translations blocked";
    if (o.invInertia > 0) what += cat(", smallest moment of inertia ", 1 / o.invInertia, " kg m^2");
    if (o.armOffset > 0) what += cat(", in a clump whose centre is ", o.armOffset, " m away");
    return cat(kind, " (YADE body ", o.bodyId, ", ", what, ")");
}

double Obstacle::extentRadius() const {
    switch (kind) {
        case ObstacleKind::Wall: return std::numeric_limits<double>::infinity();
        case ObstacleKind::Box: return halfExtents.norm();
        case ObstacleKind::Facet: {
            double r = 0;
            for (const auto& v : localVerts) r = std::max(r, v.norm());
            return r;
        }
    }
    return std::numeric_limits<double>::infinity();
}

bool crossedThin(const Obstacle& o, const Vector3d& from, const Vector3d& to) {
    if (o.kind == ObstacleKind::Wall) {
        if (o.sense != 0) return false;
        const double a = from[o.axis] - o.pos[o.axis], b = to[o.axis] - o.pos[o.axis];
        return (a > 0 && b < 0) || (a < 0 && b > 0);
    }
    if (o.kind != ObstacleKind::Facet) return false;
    const Vector3d& p0 = o.worldVerts[0];
    const Vector3d n = (o.worldVerts[1] - p0).cross(o.worldVerts[2] - p0);
    const double a = (from - p0).dot(n), b = (to - p0).dot(n);
    if (!((a > 0 && b < 0) || (a < 0 && b > 0))) return false;
    // Where the segment meets the plane: inside the triangle (edge functions
    // of one sign)?
    const Vector3d c = from + (a / (a - b)) * (to - from);
    double sgn = 0;
    for (int k = 0; k < 3; ++k) {
        const Vector3d& u = o.worldVerts[k];
        const Vector3d& v = o.worldVerts[(k + 1) % 3];
        const double e = (v - u).cross(c - u).dot(n);
        if (e * sgn < 0) return false;
        if (e != 0) sgn = e;
    }
    return true;
}

double distanceToSurface(const Obstacle& o, const Vector3d& p) {
    switch (o.kind) {
        case ObstacleKind::Wall:
            return std::fabs(p[o.axis] - o.pos[o.axis]);
        case ObstacleKind::Box: {
            const Vector3d q = o.rot.transpose() * (p - o.pos);
            const Vector3d& e = o.halfExtents;
            const Vector3d clamped = q.cwiseMax(-e).cwiseMin(e);
            if (clamped != q) return (q - clamped).norm();
            return (e - q.cwiseAbs()).minCoeff();
        }
        case ObstacleKind::Facet:
            return (p - closestOnTriangle(p, o.worldVerts[0], o.worldVerts[1], o.worldVerts[2]).point).norm();
    }
    return std::numeric_limits<double>::infinity();
}

double depthBehind(const Obstacle& o, const Vector3d& x) {
    if (o.kind != ObstacleKind::Wall || o.sense == 0) return 0;
    return -o.sense * (x[o.axis] - o.pos[o.axis]);
}

bool touchObstacle(const Obstacle& o, const Vector3d& x, double r, int prevSide, ObstacleHit& hit) {
    switch (o.kind) {
        case ObstacleKind::Wall: {
            // One-sided walls push towards their sense however deep the
            // particle is (as YADE does); two-sided ones towards the side the
            // contact started on.
            const double d = x[o.axis] - o.pos[o.axis];
            const int s = o.sense != 0 ? o.sense : (prevSide != 0 ? prevSide : (d >= 0 ? 1 : -1));
            hit.side = s;
            hit.overlap = r - s * d;
            if (hit.overlap <= 0) return false;
            hit.normal = Vector3d::Zero();
            hit.normal[o.axis] = double(s);
            hit.point = x;
            hit.point[o.axis] = o.pos[o.axis];
            return true;
        }
        case ObstacleKind::Box: {
            const Vector3d q = o.rot.transpose() * (x - o.pos);
            const Vector3d& e = o.halfExtents;
            const Vector3d clamped = q.cwiseMax(-e).cwiseMin(e);
            // hit.side: the face the contact is on, +-(local axis + 1), kept
            // as history.  A node still behind the face its contact came in
            // by (inside the box, or out through a thin plate's far face) and
            // within that face's extent is pushed back out of it: side
            // memory, as facets and two-sided walls keep their side.  By the
            // nearest face, a node pushed more than half way into a thin
            // plate went out of the far face, and a block dropped at 8 m/s on
            // a 4 mm box fell through it (a tester).
            Vector3d nLocal = Vector3d::Zero(), pLocal;
            if (prevSide >= -3 && prevSide <= 3 && prevSide != 0) {
                const int k = std::abs(prevSide) - 1;
                const double sign = prevSide > 0 ? 1.0 : -1.0;
                const double h = sign * q[k] - e[k];  // height above the entry face (< 0: behind it)
                bool within = true;
                for (int a = 0; a < 3; ++a)
                    if (a != k) within = within && std::fabs(q[a]) <= e[a];
                if (h < 0 && within) {
                    nLocal[k] = sign;
                    pLocal = q;
                    pLocal[k] = sign * e[k];
                    hit.overlap = r - h;
                    hit.side = prevSide;
                    hit.normal = o.rot * nLocal;
                    hit.point = o.pos + o.rot * pLocal;
                    return true;
                }
            }
            if (clamped != q) {  // outside: nearest point on the surface
                const Vector3d d = q - clamped;
                const double dist = d.norm();
                hit.overlap = r - dist;
                if (hit.overlap <= 0) return false;
                nLocal = d / dist;
                pLocal = clamped;
                int k = 0;  // the face it is over (at an edge or corner, the one it is farthest out of)
                for (int a = 1; a < 3; ++a)
                    if (std::fabs(d[a]) > std::fabs(d[k])) k = a;
                hit.side = (d[k] >= 0 ? 1 : -1) * (k + 1);
            } else {  // inside, no contact before: push out through the nearest face
                int k = 0;
                double best = std::numeric_limits<double>::infinity();
                for (int a = 0; a < 3; ++a) {
                    const double depth = e[a] - std::fabs(q[a]);
                    if (depth < best) {
                        best = depth;
                        k = a;
                    }
                }
                nLocal[k] = q[k] >= 0 ? 1.0 : -1.0;
                pLocal = q;
                pLocal[k] = nLocal[k] * e[k];
                hit.overlap = r + best;
                hit.side = (q[k] >= 0 ? 1 : -1) * (k + 1);
            }
            hit.normal = o.rot * nLocal;
            hit.point = o.pos + o.rot * pLocal;
            return true;
        }
        case ObstacleKind::Facet: {
            const Vector3d c = closestOnTriangle(x, o.worldVerts[0], o.worldVerts[1], o.worldVerts[2]).point;
            const Vector3d nf =
                (o.worldVerts[1] - o.worldVerts[0]).cross(o.worldVerts[2] - o.worldVerts[0]).normalized();
            const Vector3d d = x - c;
            const double dist = d.norm();
            const double h = d.dot(nf);
            const int sideNow = h >= 0 ? 1 : -1;
            hit.point = c;
            if (prevSide != 0 && sideNow != prevSide && std::fabs(h) >= 0.5 * dist) {
                // Pushed through the facet's face: keep pushing back.
                hit.side = prevSide;
                hit.normal = double(prevSide) * nf;
                hit.overlap = r + dist;
                return true;
            }
            hit.side = sideNow;
            hit.overlap = r - dist;
            if (hit.overlap <= 0) return false;
            hit.normal = dist > 1e-14 * r ? Vector3d(d / dist) : Vector3d(double(sideNow) * nf);
            return true;
        }
    }
    return false;
}

}  // namespace qdem
