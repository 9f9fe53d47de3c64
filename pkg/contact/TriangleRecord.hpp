// A surface triangle as the point-polygon loop reads it each step: corners,
// unit normal and bounding sphere in one 128-byte record, refreshed once per
// step in triangle order (PieceContactPhase), so that a node's listed
// triangles are read with one load each instead of two dependent lookups
// (triangle -> corner ids -> positions).  And the prefilter that drops, from
// the record alone, triangles the exact test (pointTriangle,
// PointTriangle.hpp) would drop too.
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace qdem::contact_detail {

// Aligned to 64: the prefilter's fields (normal, centre, radius) fill the
// second cache line; the corners (read only for the triangles that pass)
// the first, with c[2].
struct alignas(64) TriRecord {
    double a[3], b[3], c[3];  // corners (copies of the positions: the same bits)
    double n[3];              // unit outward normal
    double centre[3], radius; // centroid, and the largest corner distance from it
};
static_assert(sizeof(TriRecord) == 128);

inline void fillTriRecord(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                          const Eigen::Vector3d& n, TriRecord& r) {
    const Eigen::Vector3d m = (a + b + c) / 3;
    for (int d = 0; d < 3; ++d) r.a[d] = a[d], r.b[d] = b[d], r.c[d] = c[d], r.n[d] = n[d], r.centre[d] = m[d];
    r.radius = std::sqrt(std::max({(a - m).squaredNorm(), (b - m).squaredNorm(), (c - m).squaredNorm()}));
}

// Can point P make a candidate with the triangle (pointTriangle true) for
// some contact reach <= reachMax?  The point is at height h over the plane;
// its projection on the plane lies sqrt(lat2) from the centre.  A candidate
// has its closest point within the reach (then the projection is within
// sqrt(reach^2 - h^2) of the face, so within radius + that of the centre), or
// lies straight behind the face (straightBehind's 1e-9 lets the projection
// lie at most 4.5e-5 |h| off the face: the 1e-4 |h| term).  False: more than
// a reach in front of the plane, or the projection beyond that bound.  The
// margins (1e-9, 1e-6) cover rounding: false only where the exact test says
// no too (tests/cpp/test_triangle_record.cpp), so filtering a list by it
// keeps the same candidates in the same order.
inline bool mayBeCandidate(const double* P, const TriRecord& r, double reachMax) {
    const double dx = P[0] - r.centre[0], dy = P[1] - r.centre[1], dz = P[2] - r.centre[2];
    const double h = dx * r.n[0] + dy * r.n[1] + dz * r.n[2];
    const double reach2 = reachMax * reachMax * (1 + 1e-9);
    const double lim = r.radius * (1 + 1e-9) + std::sqrt(std::max(0.0, reach2 - h * h)) + 1e-4 * std::abs(h);
    const double lat2 = dx * dx + dy * dy + dz * dz - h * h;
    return !(h > reachMax * (1 + 1e-9) || lat2 > lim * lim * (1 + 1e-6));  // (NaN: kept, as the exact test keeps it)
}

}  // namespace qdem::contact_detail
