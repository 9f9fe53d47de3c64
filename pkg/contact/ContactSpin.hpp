// The spin of a contact about its normal: the rate at which the tangential
// spring's far end turns about n, so that the spring is carried round with
// it (ContactLaw.hpp, contactForce).  Which side's spin each contact kind
// uses and why: doc/formulation.md, "Tangential law", "Twist".
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace qdem {

// Spin about the unit vector n of a triangle whose corners x0, x1, x2 move at
// v0, v1, v2: the in-plane spin of its (linear) velocity field, half the
// vorticity, from the circulation round its edges (Stokes: the circulation is
// 2 A omega).  With the velocities taken relative to corner 0 (w1 = v1 - v0,
// w2 = v2 - v0; e1 = x1 - x0, e2 = x2 - x0, c = e1 x e2 = 2 A nt):
//   omega . nt = (w1 . e2 - w2 . e1) / (2 |c|),
// and about n its component nt . n.  A translating triangle gives exactly 0
// (w1 = w2 = 0), a rigidly turning one its angular velocity about its normal.
inline double triangleSpin(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                           const Eigen::Vector3d& v0, const Eigen::Vector3d& v1, const Eigen::Vector3d& v2,
                           const Eigen::Vector3d& n) {
    const Eigen::Vector3d e1 = x1 - x0, e2 = x2 - x0;
    const Eigen::Vector3d w1 = v1 - v0, w2 = v2 - v0;
    const double circ = w1.dot(e2) - w2.dot(e1);
    if (circ == 0) return 0.0;
    const Eigen::Vector3d c = e1.cross(e2);
    const double c2 = c.squaredNorm();
    return c2 > 0 ? circ * c.dot(n) / (2 * c2) : 0.0;
}

// Spin about the unit vector n of a segment p-q moving at vp, vq: the rate
// at which its direction, projected on the plane normal to n, turns about n,
//   n . (e x de/dt) / |n x e|^2,  e = q - p.
// 0 for a segment along n (it has no direction in the plane).
inline double segmentSpin(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& vp,
                          const Eigen::Vector3d& vq, const Eigen::Vector3d& n) {
    const Eigen::Vector3d e = q - p, de = vq - vp;
    const double turn = n.dot(e.cross(de));
    if (turn == 0) return 0.0;
    const double inPlane2 = n.cross(e).squaredNorm();
    return inPlane2 > 1e-12 * e.squaredNorm() ? turn / inPlane2 : 0.0;
}

}  // namespace qdem
