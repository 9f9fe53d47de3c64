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
// reactions of the other piece's nodes.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>

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

// The smallest run-time stable step over the surface nodes of the last
// step's piece-piece contacts, and where it is (infinite, node -1: none).
struct ContactStepLimit {
    double limit = std::numeric_limits<double>::infinity();
    int32_t node = -1, piece = -1;
    double stiffness = 0, dashpot = 0;  // the node's load
    long step = -1;                     // the step it was measured in
};

}  // namespace qdem
