// The one point-triangle kernel: a query point P (a surface node, or a YADE
// sphere's centre) against the surface triangles of another piece, with
// contact reach `reach` (the two radii).  Both the point-polygon contacts
// (PointPolygon.cpp) and the sphere contacts (SpherePhase.cpp) gather their
// candidates with it, keep them by one policy and run the same inside test;
// the rules (doc/contacts.md §3) then pick the touches (TouchSelection.hpp).
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "ContactDetail.hpp"
#include "Geometry.hpp"

namespace qdem::contact_detail {

// The feature a closest point is reported as, with rounding-level weights
// snapped (doc/contacts.md §3): three weights above 1e-9 make a face, one a
// corner (4 + its index); otherwise (an edge) the feature stays, a face
// becoming Edge0 (on an edge: not a face).  Applied when a candidate is made
// (CandidateList::add, and point-polygon's lanes), after its behind test,
// which reads the feature as found.  Branch-free: point-polygon evaluates it
// for kTriLanes lanes at once.
inline int32_t snappedFeature(double w0, double w1, double w2, int32_t f) {
    const double tol = 1e-9;
    const bool p0 = w0 > tol, p1 = w1 > tol, p2 = w2 > tol;
    const int32_t nz = int32_t{p0} + int32_t{p1} + int32_t{p2};
    const int32_t corner = p0 ? 4 : (p1 ? 5 : 6);
    const int32_t other = f == 0 ? 1 : f;
    return nz == 3 ? 0 : (nz == 1 ? corner : other);
}

// A point behind a triangle's plane (h < 0) is inside the other piece when it
// lies straight behind the triangle: its closest point is inside the face, or
// on the face's boundary with the point straight below it (dist = |h|, to
// rounding).  The second case is a point right behind an edge or corner
// shared by coplanar triangles of a flat face - every adjacent triangle then
// reports an edge or corner closest point.  Without it such a point (common:
// meshes of equal cells meet node under edge) was taken as outside, dropped
// its contact and let pieces pass through each other (issue 12,
// doc/hard_cases.md).
inline bool straightBehind(bool faceFeature, double dist, double h) {
    return faceFeature || dist + h <= 1e-9 * dist;
}

// The candidate P makes with triangle (a, b, c) of unit outward normal n, if
// any: within reach in front of the plane, or behind it (possibly inside the
// piece: decided by insideTest below).  regions = false: the seed's inside
// test (§3.1), the projection must fall inside the triangle.  Returns false
// when the triangle cannot touch P.
inline bool pointTriangle(const Eigen::Vector3d& P, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c, const Eigen::Vector3d& n, double reach, bool regions,
                          TriPoint& cp, double& dist, bool& behind) {
    const double h = (P - a).dot(n);
    if (h > reach) return false;
    cp = closestOnTriangle(P, a, b, c);
    dist = (P - cp.point).norm();
    if (!regions && dist - std::abs(h) > 1e-9 * reach) return false;
    behind = h < 0 && straightBehind(cp.feature == TriFeature::Face, dist, h);
    return behind || dist < reach;
}

// Does triangle (a, b, c, normal n), facing P, hold a point nearer than db?
// Then P, db behind another face of the same piece, is outside it: an
// outside point's nearest surface point faces it and is strictly nearer than
// any point of a face seen from behind.
inline bool frontFaceNearer(const Eigen::Vector3d& P, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, const Eigen::Vector3d& n, double db) {
    const double h = (P - a).dot(n);
    if (h >= db) return false;  // cannot be nearer
    const TriPoint cp = closestOnTriangle(P, a, b, c);
    const double dw = (P - cp.point).norm();
    const bool behind = h < 0 && straightBehind(cp.feature == TriFeature::Face, dw, h);
    return !behind && dw < db;
}

// The candidate policy: the kCandidates (32) nearest triangles, in the order
// they were found (a farther one is replaced when a nearer one comes), their
// features snapped (snappedFeature).  32
// covers a node among the finest meshes' corners many times over; a big
// sphere on small triangles sees more, and its nearest are the ones that
// touch.
struct CandidateList {
    Candidate c[kCandidates];
    int n = 0;
    bool anyBehind = false;

    void clear() { n = 0, anyBehind = false; }
    // Adds the candidate P makes with triangle tri (a, b, c, normal nrm), if any.
    void consider(const Eigen::Vector3d& P, int32_t tri, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                  const Eigen::Vector3d& c3, const Eigen::Vector3d& nrm, double reach, bool regions) {
        TriPoint cp;
        double dist;
        bool behind;
        if (pointTriangle(P, a, b, c3, nrm, reach, regions, cp, dist, behind)) add(Candidate{tri, cp, dist, behind});
    }
    // The slot a candidate at distance dist goes to (written there by the
    // caller, its feature snapped), or nullptr when the list is full of
    // nearer ones: add() without building the candidate first and copying it
    // (~80 bytes; 51,840 times a step in the 27-cube stack).  The caller
    // passes the candidate's behind flag to noteBehind.
    Candidate* slotFor(double dist) {
        if (n < kCandidates) return &c[n++];
        int slot = 0;
        for (int k = 1; k < n; ++k)
            if (c[k].dist > c[slot].dist) slot = k;
        return dist >= c[slot].dist ? nullptr : &c[slot];
    }
    void noteBehind(bool behind) { anyBehind = anyBehind || behind; }
    void add(const Candidate& x) {
        int slot = n;
        if (n == kCandidates) {
            slot = 0;
            for (int k = 1; k < n; ++k)
                if (c[k].dist > c[slot].dist) slot = k;
            if (x.dist >= c[slot].dist) return;
        } else {
            ++n;
        }
        c[slot] = x;
        TriPoint& cp = c[slot].cp;
        cp.feature = static_cast<TriFeature>(snappedFeature(cp.w[0], cp.w[1], cp.w[2], static_cast<int32_t>(cp.feature)));
        anyBehind = anyBehind || x.behind;
    }
};

}  // namespace qdem::contact_detail
