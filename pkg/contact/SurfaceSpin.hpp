// The spin of a piece's surface at its nodes: the angular velocity by which a
// piece-piece contact's tangential spring is turned (the twist,
// ContactLaw.hpp).  One vector per surface node, from the node's one-ring of
// surface triangles, so that it is continuous over the surface: a contact
// interpolates its corners' values, and a contact handed over to the next
// triangle keeps its spin.  Derivation: doc/formulation.md, "Twist".
#pragma once
#include <Eigen/Core>
#include <Eigen/LU>
#include <cstdint>

#include "SurfaceIndex.hpp"

namespace qdem {

// The spin of surface node `node` (index s in the surface) into out[0..3):
//  - the angular velocity of the rigid motion nearest, in least squares,
//    to the velocities of its ring's nodes relative to its own,
//      (sum |r|^2 I - r r^T) w = sum r x dv   (r, dv: a ring node's offset
//    and velocity relative to the node's; every ring node twice, once per
//    ring triangle it is a corner of);
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
// false -- no contact reads such a node: doc/parallel.md).
inline bool surfaceNodeSpin(const SurfaceIndex& S, int32_t s, int32_t node, const double* X, const double* V,
                            const uint8_t* current, double* out) {
    using Eigen::Vector3d;
    const Vector3d xi(X[3 * node], X[3 * node + 1], X[3 * node + 2]);
    const Vector3d vi(V[3 * node], V[3 * node + 1], V[3 * node + 2]);
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    Vector3d b = Vector3d::Zero(), area = Vector3d::Zero();
    double circulation = 0;
    bool whole = true;
    for (int32_t q = S.nodeTriStart[s]; q < S.nodeTriStart[s + 1]; ++q) {
        const int32_t* c = &S.tri[3 * S.nodeTris[q]];
        const int k = c[0] == node ? 0 : (c[1] == node ? 1 : 2);
        const int32_t ia = c[(k + 1) % 3], ib = c[(k + 2) % 3];  // i, a, b counter-clockwise seen from outside
        if (current && !(current[ia] && current[ib])) whole = false;
        const Vector3d ra = Vector3d(X[3 * ia], X[3 * ia + 1], X[3 * ia + 2]) - xi;
        const Vector3d rb = Vector3d(X[3 * ib], X[3 * ib + 1], X[3 * ib + 2]) - xi;
        const Vector3d wa = Vector3d(V[3 * ia], V[3 * ia + 1], V[3 * ia + 2]) - vi;
        const Vector3d wb = Vector3d(V[3 * ib], V[3 * ib + 1], V[3 * ib + 2]) - vi;
        M.diagonal().array() += ra.squaredNorm() + rb.squaredNorm();
        M -= ra * ra.transpose() + rb * rb.transpose();
        b += ra.cross(wa) + rb.cross(wb);
        area += 0.5 * ra.cross(rb);
        circulation += 0.5 * (wa + wb).dot(rb - ra);  // along the ring's outer edge a -> b (trapezoid: exact, linear)
    }
    const double a2 = area.squaredNorm(), tr = M.trace();
    // (M is singular only for a ring on one line: no surface's)
    const double det = M.determinant();
    if (!whole || !(a2 > 0) || !(det > 1e-12 * tr * tr * tr)) {
        out[0] = out[1] = out[2] = 0;
        return false;
    }
    Vector3d w = M.inverse() * b;
    w += ((0.5 * circulation - w.dot(area)) / a2) * area;
    out[0] = w[0], out[1] = w[1], out[2] = w[2];
    return true;
}

}  // namespace qdem
