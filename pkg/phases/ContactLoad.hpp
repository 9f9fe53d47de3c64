// The piece-piece contacts' springs and dashpots as they act on each surface
// node: the run-time stable step of the contacts as they are (doc/
// formulation.md, "Stable time step", "Piece-piece contacts as they are").
//
// A contact spring k acts on g.x, the difference of two surface points each
// a convex combination of nodes (a node against a triangle point, a point of
// an edge against one of another edge), so sum_j |g_j| = 2.  Its matrix
// k g g' is below diag(k |g_j| sum_l |g_l|) = diag(2 k |g_j|) in the Loewner
// order (a symmetric matrix is below the diagonal of its absolute row sums:
// the difference is diagonally dominant), the tangential spring alike (its
// projector <= I), the dashpots alike.  Each node's load is the sum of these
// rows over the contacts on it: as a node pressed on a face, and as a
// triangle corner or edge end carrying the reactions of the other piece's
// nodes.
#pragma once
#include <algorithm>
#include <cstdint>
#include <limits>

#include "../contact/ContactLaw.hpp"

namespace qdem {

// Adds a contact with params p (tangential spring and dashpot when
// `tangential`) to the load of surface node s, whose share of the contact's
// motion is g (1 for the node of a node-triangle contact, a barycentric or
// edge weight otherwise): 2 g max(kn, kt) and 2 g max(cn, ct).  load holds 2
// doubles per surface node: stiffness [N/m], dashpot [N s/m].
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
