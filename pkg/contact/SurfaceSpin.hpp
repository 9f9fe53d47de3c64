// The spin of a piece's surface at its nodes: the angular velocity by which a
// piece-piece contact's tangential spring is turned (the twist,
// ContactLaw.hpp).  One vector per surface node, from the node's one-ring of
// surface triangles, so that it is continuous over the surface: a contact
// interpolates its corners' values, and a contact handed over to the next
// triangle keeps its spin.  Derivation: doc/formulation.md, "Twist".
#pragma once
#include <cstdint>

#include "SurfaceIndex.hpp"

namespace qdem {

// The spin of surface node `node` (index s in the surface) into out[0..3):
//  - the angular velocity of the rigid motion nearest, in least squares,
//    to the velocities of its ring's nodes relative to its own,
//      (sum |r|^2 I - r r^T) w = sum r x dv   (r, dv: a ring node's offset
//    and velocity relative to the node's);
//  - with its component along the ring's vector area S = sum A_T n_T
//    replaced by the circulation round the ring over 2 |S|: by Stokes, the
//    circulation of an affine velocity field round a closed polygon is
//    2 w . S exactly, whatever its strain rate (the symmetric part of the
//    gradient is a gradient field and circulates nothing), where the fit
//    takes a share of the strain rate when the ring is not isotropic.
// Exact for a rigid motion; the normal part also for any affine one.  The
// sums run over the ring in its stored order: the same bits on any thread,
// and on every rank whose copy holds the ring (`current`: the nodes whose
// state is current on this rank, null: all; a ring not whole gives 0 and
// false -- no contact reads such a node: doc/formulation.md, "Twist").
inline bool surfaceNodeSpin(const SurfaceIndex& S, int32_t s, int32_t node, const double* X, const double* V,
                            const uint8_t* current, double* out) {
    const double xi0 = X[3 * node], xi1 = X[3 * node + 1], xi2 = X[3 * node + 2];
    const double vi0 = V[3 * node], vi1 = V[3 * node + 1], vi2 = V[3 * node + 2];
    // M = sum |r|^2 I - r r^T (symmetric: 6 entries), b = sum r x dv, the
    // ring's vector area (twice), its circulation (twice): each ring node
    // once, as the corner after the node in its triangle (a closed ring
    // holds each of its nodes there once), which halves the fit's sums.
    double m00 = 0, m11 = 0, m22 = 0, m01 = 0, m02 = 0, m12 = 0, b0 = 0, b1 = 0, b2 = 0;
    double s0 = 0, s1 = 0, s2 = 0, circ = 0;
    bool whole = true;
    for (int32_t q = S.nodeTriStart[s]; q < S.nodeTriStart[s + 1]; ++q) {
        const int32_t* c = &S.tri[3 * S.nodeTris[q]];
        const int k = c[0] == node ? 0 : (c[1] == node ? 1 : 2);
        const int32_t ia = c[k == 2 ? 0 : k + 1], ib = c[k == 0 ? 2 : k - 1];  // i, a, b counter-clockwise from outside
        if (current && !(current[ia] && current[ib])) whole = false;
        const double ra0 = X[3 * ia] - xi0, ra1 = X[3 * ia + 1] - xi1, ra2 = X[3 * ia + 2] - xi2;
        const double rb0 = X[3 * ib] - xi0, rb1 = X[3 * ib + 1] - xi1, rb2 = X[3 * ib + 2] - xi2;
        const double wa0 = V[3 * ia] - vi0, wa1 = V[3 * ia + 1] - vi1, wa2 = V[3 * ia + 2] - vi2;
        const double wb0 = V[3 * ib] - vi0, wb1 = V[3 * ib + 1] - vi1, wb2 = V[3 * ib + 2] - vi2;
        m00 += ra1 * ra1 + ra2 * ra2, m11 += ra0 * ra0 + ra2 * ra2, m22 += ra0 * ra0 + ra1 * ra1;
        m01 -= ra0 * ra1, m02 -= ra0 * ra2, m12 -= ra1 * ra2;
        b0 += ra1 * wa2 - ra2 * wa1, b1 += ra2 * wa0 - ra0 * wa2, b2 += ra0 * wa1 - ra1 * wa0;
        s0 += ra1 * rb2 - ra2 * rb1, s1 += ra2 * rb0 - ra0 * rb2, s2 += ra0 * rb1 - ra1 * rb0;
        // along the ring's outer edge a -> b (trapezoid: exact, the field linear there)
        circ += (wa0 + wb0) * (rb0 - ra0) + (wa1 + wb1) * (rb1 - ra1) + (wa2 + wb2) * (rb2 - ra2);
    }
    // Solved by cofactors (M symmetric positive definite; singular only for
    // a ring on one line: no surface's).
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22, c02 = m01 * m12 - m02 * m11;
    const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12, c22 = m00 * m11 - m01 * m01;
    const double det = m00 * c00 + m01 * c01 + m02 * c02, tr = m00 + m11 + m22;
    const double a2 = s0 * s0 + s1 * s1 + s2 * s2;  // (2 |S|)^2
    if (!whole || !(a2 > 0) || !(det > 1e-12 * tr * tr * tr)) {
        out[0] = out[1] = out[2] = 0;
        return false;
    }
    double w0 = (c00 * b0 + c01 * b1 + c02 * b2) / det;
    double w1 = (c01 * b0 + c11 * b1 + c12 * b2) / det;
    double w2 = (c02 * b0 + c12 * b1 + c22 * b2) / det;
    // w . S = C / 2 with the doubled sums s = 2 S, circ = 2 C: w . s = circ / 2.
    const double f = (0.5 * circ - (w0 * s0 + w1 * s1 + w2 * s2)) / a2;
    w0 += f * s0, w1 += f * s1, w2 += f * s2;
    out[0] = w0, out[1] = w1, out[2] = w2;
    return true;
}

}  // namespace qdem
