// The piece-piece contacts' springs and dashpots as they act on each surface
// node: the run-time stable step of the contacts as they are (doc/
// formulation.md, "Stable time step", "Piece-piece contacts as they are").
//
// A contact spring k acts on g.x = u.x - v.x, the difference of two surface
// points each a convex combination of nodes (u = e_a for a node against a
// triangle point, v = sum b_j e_j; the two edges' points for edge-edge).  By
// Young's inequality, for any theta > 0,
//     k g g' <= k ((1 + theta) u u' + (1 + 1/theta) v v'),
// and by convexity (u u' <= sum u_j e_j e_j', weights >= 0 summing to 1) the
// matrix is below the diagonal k (1 + theta) u_j on the first side's nodes,
// k (1 + 1/theta) v_j on the other's in the Loewner order; the tangential
// spring alike (its projector <= I), the dashpots alike.  theta = m1/m2, the
// two points' masses, makes both rows k/m_reduced for a single contact (the
// exact frequency of two masses on a spring); any theta keeps it a bound.
// Each node's load is the sum of these over the contacts on it: as a node
// pressed on a face, and as a triangle corner or edge end carrying the
// reactions of the other piece's nodes; with it the springs of the walls,
// boxes and facets it touches and of the YADE spheres pressing the faces it
// is a corner of (their other side checked on its own: a fixed obstacle has
// none, a dynamic one ObstaclePhase::checkDynamicObstacles, a sphere the
// sphere part of the stable step, doc/spheres.md).
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

#include "../contact/ContactLaw.hpp"

namespace qdem {

// Adds a contact with params p (tangential spring and dashpot when
// `tangential`) to the load of surface node s: 2 g max(kn, kt) and
// 2 g max(cn, ct), g half its share (its weight times 1 + theta, or
// 1 + 1/theta).  load holds 2 doubles per surface node: stiffness [N/m],
// dashpot [N s/m].
inline void addContactLoad(double* load, int32_t s, double g, const ContactParams& p, bool tangential) {
    const double k = tangential ? std::max(p.kn, p.kt) : p.kn;
    const double c = tangential ? std::max(p.cn, p.ct) : p.cn;
    load[2 * s] += 2 * g * k;
    load[2 * s + 1] += 2 * g * c;
}

// A node's contact with a wall, box or facet (obstacle side: mobility g at
// the contact point, 0 when fixed): theta = m_node g, the share 1 + m_node g
// (exactly k/m_node on a fixed obstacle).
inline void addObstacleContactLoad(double* load, int32_t s, double nodeMassTimesMobility, const ContactParams& p,
                                   bool tangential) {
    addContactLoad(load, s, 0.5 * (1 + nodeMassTimesMobility), p, tangential);
}

// A YADE sphere of mass mSphere pressing the point of a triangle with
// barycentric weights b (corners' surface indices si) and mass mT = sum b_j
// m_j: theta = m_sphere / m_T on the sphere's side, so each corner carries
// b_j (1 + m_T / m_sphere) of the normal spring and b_j (1 + m_T / m_t) of
// the tangential one, m_t = 2 m_sphere / 7 the ball's mass at its surface
// (a solid ball's 1/m + R^2/I): the rows k/m_s + k/m_T (k (3.5/m_s + 1/m_T))
// that the sphere part of the stable step bounds on the sphere's side.
inline void addSphereContactLoad(double* load, const int32_t si[3], const double b[3], double mT, double mSphere,
                                 const ContactParams& p, bool tangential) {
    const double gn = 1 + mT / mSphere, gt = 1 + 3.5 * mT / mSphere;  // (an infinite mass: 1)
    const double k = tangential ? std::max(gn * p.kn, gt * p.kt) : gn * p.kn;
    const double c = tangential ? std::max(gn * p.cn, gt * p.ct) : gn * p.cn;
    for (int j = 0; j < 3; ++j)
        if (b[j] != 0) load[2 * si[j]] += b[j] * k, load[2 * si[j] + 1] += b[j] * c;
}

// Adds the per-thread load rows s0 .. s1 - 1 (2 per surface node) into load,
// in thread order.
inline void addThreadLoads(const std::vector<std::vector<double>>& threadLoad, int32_t s0, int32_t s1, double* load) {
    for (const std::vector<double>& t : threadLoad)
        for (int32_t s = s0; s < s1; ++s) load[2 * s] += t[2 * s], load[2 * s + 1] += t[2 * s + 1];
}

// The smallest run-time stable step over the surface nodes of the last
// step's contacts (piece-piece, obstacles, spheres), and where it is (infinite, node -1: none).
struct ContactStepLimit {
    double limit = std::numeric_limits<double>::infinity();
    int32_t node = -1, piece = -1;
    double stiffness = 0, dashpot = 0;  // the node's load
    long step = -1;                     // the step it was measured in
};

}  // namespace qdem
