// Obstacles touch QDEM pieces only through the pieces' nodes (particles of
// radius r, doc/contacts.md).  An obstacle edge or corner narrower than the
// node spacing - a thin plate edge-on, a knife, a ridge - can therefore pass
// between the nodes and cut into a piece unresisted, which is wrong physics
// that no contact force reports.  Checked every check period: an edge of a
// Box (12) or a Facet (3) that crosses a surface triangle of a piece (whose
// corners are node centres, r inside the contact skin) has gone through it.
#include <cmath>

#include "World.hpp"

namespace qdem {

namespace {

// Does segment p->q cross triangle (a, b, c)?  Moeller-Trumbore; the crossing
// point in *x.  Grazing and parallel segments do not count.
bool segmentCrossesTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c, Eigen::Vector3d* x) {
    const Eigen::Vector3d d = q - p, e1 = b - a, e2 = c - a;
    const Eigen::Vector3d h = d.cross(e2);
    const double det = e1.dot(h);
    const double scale = d.norm() * e1.norm() * e2.norm();
    if (!(std::abs(det) > 1e-12 * scale)) return false;
    const double inv = 1.0 / det;
    const Eigen::Vector3d s = p - a;
    const double u = inv * s.dot(h);
    if (u < 0 || u > 1) return false;
    const Eigen::Vector3d qv = s.cross(e1);
    const double v = inv * d.dot(qv);
    if (v < 0 || u + v > 1) return false;
    const double t = inv * e2.dot(qv);
    if (t < 0 || t > 1) return false;
    *x = p + t * d;
    return true;
}

// The edges of an obstacle in world coordinates (none for a wall: an
// infinite plane has no edge).
int obstacleEdges(const Obstacle& o, Eigen::Vector3d (*ends)[2]) {
    if (o.kind == ObstacleKind::Facet) {
        for (int k = 0; k < 3; ++k) ends[k][0] = o.worldVerts[k], ends[k][1] = o.worldVerts[(k + 1) % 3];
        return 3;
    }
    if (o.kind != ObstacleKind::Box) return 0;
    int n = 0;
    for (int axis = 0; axis < 3; ++axis) {
        const int i = (axis + 1) % 3, j = (axis + 2) % 3;
        for (int si = -1; si <= 1; si += 2)
            for (int sj = -1; sj <= 1; sj += 2) {
                Eigen::Vector3d a = Eigen::Vector3d::Zero();
                a[i] = si * o.halfExtents[i];
                a[j] = sj * o.halfExtents[j];
                Eigen::Vector3d b = a;
                a[axis] = -o.halfExtents[axis];
                b[axis] = o.halfExtents[axis];
                ends[n][0] = o.pos + o.rot * a;
                ends[n][1] = o.pos + o.rot * b;
                ++n;
            }
    }
    return n;
}

}  // namespace

ObstacleEdgeCrossing World::obstacleEdgeCrossing() const {
    requireGathered("obstacleEdgeCrossing");
    ObstacleEdgeCrossing r;
    if (obstacles.empty()) return r;
    const std::size_t np = pieces.size();
    std::vector<Eigen::Vector3d> lo(np, Eigen::Vector3d::Constant(1e300)), hi(np, Eigen::Vector3d::Constant(-1e300));
    for (std::size_t p = 0; p < np; ++p)
        for (int32_t s = pieces[p].surfBegin; s < pieces[p].surfEnd; ++s) {
            const Eigen::Vector3d x(&pos[3 * surfNodes[s]]);
            lo[p] = lo[p].cwiseMin(x);
            hi[p] = hi[p].cwiseMax(x);
        }
    Eigen::Vector3d ends[12][2];
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
        const int ne = obstacleEdges(obstacles[k], ends);
        for (int e = 0; e < ne; ++e) {
            const Eigen::Vector3d elo = ends[e][0].cwiseMin(ends[e][1]), ehi = ends[e][0].cwiseMax(ends[e][1]);
            for (std::size_t p = 0; p < np; ++p) {
                if ((elo.array() > hi[p].array()).any() || (ehi.array() < lo[p].array()).any()) continue;
                for (int32_t t = surf_.pieceTriStart[p]; t < surf_.pieceTriStart[p + 1]; ++t) {
                    const int32_t* c = &surf_.tri[3 * t];
                    Eigen::Vector3d x;
                    if (!segmentCrossesTriangle(ends[e][0], ends[e][1], Eigen::Vector3d(&pos[3 * c[0]]),
                                                Eigen::Vector3d(&pos[3 * c[1]]), Eigen::Vector3d(&pos[3 * c[2]]), &x))
                        continue;
                    ++r.count;
                    if (r.obstacle < 0) {
                        r.obstacle = static_cast<int>(k);
                        r.bodyId = obstacles[k].bodyId;
                        r.piece = static_cast<int>(p);
                        r.point = x;
                    }
                }
            }
        }
    }
    return r;
}

}  // namespace qdem
