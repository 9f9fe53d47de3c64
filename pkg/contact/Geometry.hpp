// Closest-point geometry for surface contacts (inline: used in hot loops).
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace qdem {

// Where on a triangle the closest point lies: the face interior, one of the
// three edges (edge k joins corner k and k+1), or one of the three corners.
enum class TriFeature : int8_t { Face = 0, Edge0 = 1, Edge1 = 2, Edge2 = 3, Vert0 = 4, Vert1 = 5, Vert2 = 6 };

struct TriPoint {
    Eigen::Vector3d point;  // closest point on the triangle
    double w[3];            // its barycentric weights (>= 0, sum 1): the force split
    TriFeature feature;
};

// Closest point on triangle (a, b, c) to p by Voronoi regions (Ericson,
// Real-Time Collision Detection, 5.1.5), with barycentric weights and region.
inline TriPoint closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c) {
    TriPoint r;
    const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) {
        r.point = a, r.w[0] = 1, r.w[1] = 0, r.w[2] = 0, r.feature = TriFeature::Vert0;
        return r;
    }
    const Eigen::Vector3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) {
        r.point = b, r.w[0] = 0, r.w[1] = 1, r.w[2] = 0, r.feature = TriFeature::Vert1;
        return r;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        r.point = a + v * ab, r.w[0] = 1 - v, r.w[1] = v, r.w[2] = 0, r.feature = TriFeature::Edge0;
        return r;
    }
    const Eigen::Vector3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) {
        r.point = c, r.w[0] = 0, r.w[1] = 0, r.w[2] = 1, r.feature = TriFeature::Vert2;
        return r;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        r.point = a + w * ac, r.w[0] = 1 - w, r.w[1] = 0, r.w[2] = w, r.feature = TriFeature::Edge2;
        return r;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        r.point = b + w * (c - b), r.w[0] = 0, r.w[1] = 1 - w, r.w[2] = w, r.feature = TriFeature::Edge1;
        return r;
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    r.point = a + ab * v + ac * w, r.w[0] = 1 - v - w, r.w[1] = v, r.w[2] = w, r.feature = TriFeature::Face;
    return r;
}

struct SegPoints {
    double s, t;           // parameters on segment 1 (p1 + s d1) and 2 (p2 + t d2), in [0, 1]
    Eigen::Vector3d c1, c2;
    double sin2;           // squared sine of the angle between the segments
};

// Closest points of segments p1-q1 and p2-q2 (Ericson 5.1.9).  Unlike the
// seed paper's formula this never divides by 1 - (n1.n2)^2 when it vanishes:
// for parallel segments it returns the middle of the overlapping stretch, so
// the contact point moves continuously as the segments slide along each other.
inline SegPoints closestSegmentSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1,
                                       const Eigen::Vector3d& p2, const Eigen::Vector3d& q2) {
    SegPoints r;
    const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, rr = p1 - p2;
    const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(rr);
    const double c = d1.dot(rr), b = d1.dot(d2);
    const double denom = a * e - b * b;  // >= 0: a e sin^2(angle)
    r.sin2 = (a > 0 && e > 0) ? std::max(0.0, denom / (a * e)) : 0.0;
    double s, t;
    if (r.sin2 > 1e-12) {
        s = std::clamp((b * f - c * e) / denom, 0.0, 1.0);
    } else {
        // Parallel: project segment 2 onto segment 1 and take the middle of
        // the overlap (or the nearest end when they do not overlap).
        const double t0 = std::clamp(-c / a, 0.0, 1.0);
        const double t1 = std::clamp((d2 - rr).dot(d1) / a, 0.0, 1.0);
        s = 0.5 * (t0 + t1);
    }
    t = (b * s + f) / e;
    if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
    }
    r.s = s;
    r.t = t;
    r.c1 = p1 + d1 * s;
    r.c2 = p2 + d2 * t;
    return r;
}

}  // namespace qdem
