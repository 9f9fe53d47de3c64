// Closest-point geometry for surface contacts (inline: used in hot loops).
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products
#include <algorithm>
#include <cmath>
#include <cstdint>

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

// closestOnTriangle for kTriLanes triangles and one point at once: the same
// formulas evaluated for every region in every lane, the region picked in the
// same order, as straight-line lane code the compiler turns into SIMD (no
// unpredictable branches).  Equal to closestOnTriangle to rounding.  Also
// returns each triangle's plane height h = (p - a).n and the squared
// distance to the closest point.
//
// Compiled without trapping math: GCC sinks each region's arithmetic into
// the branch that uses it, and will not turn a branch into a blend when its
// body holds a floating-point operation that could raise an exception flag
// - unless the machine has AVX-512's masks.  So on AVX2 machines this loop
// stayed scalar code with a dozen unpredictable branches per triangle (19 %
// of the 27-cube step).  Nothing here reads the exception flags, and the
// operations and their order are unchanged: the same bits, vectorised.
constexpr int kTriLanes = 8;

struct TriLanes {
    alignas(64) double a[3][kTriLanes], b[3][kTriLanes], c[3][kTriLanes], n[3][kTriLanes];
};

struct TriLanesOut {
    alignas(64) double point[3][kTriLanes], w[3][kTriLanes], h[kTriLanes], dist2[kTriLanes];
    alignas(64) int32_t feature[kTriLanes];
};

__attribute__((optimize("no-trapping-math"))) inline void closestOnTriangles(const double* p, const TriLanes& in,
                                                                             TriLanesOut& out) {
    const double px = p[0], py = p[1], pz = p[2];
#pragma omp simd
    for (int l = 0; l < kTriLanes; ++l) {
        const double ax = in.a[0][l], ay = in.a[1][l], az = in.a[2][l];
        const double bx = in.b[0][l], by = in.b[1][l], bz = in.b[2][l];
        const double cx = in.c[0][l], cy = in.c[1][l], cz = in.c[2][l];
        const double abx = bx - ax, aby = by - ay, abz = bz - az;
        const double acx = cx - ax, acy = cy - ay, acz = cz - az;
        const double apx = px - ax, apy = py - ay, apz = pz - az;
        const double bpx = px - bx, bpy = py - by, bpz = pz - bz;
        const double cpx = px - cx, cpy = py - cy, cpz = pz - cz;
        const double d1 = abx * apx + aby * apy + abz * apz, d2 = acx * apx + acy * apy + acz * apz;
        const double d3 = abx * bpx + aby * bpy + abz * bpz, d4 = acx * bpx + acy * bpy + acz * bpz;
        const double d5 = abx * cpx + aby * cpy + abz * cpz, d6 = acx * cpx + acy * cpy + acz * cpz;
        const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        // Face interior (the default), then the regions in the reverse of
        // closestOnTriangle's order, so that its first match wins.
        const double denom = 1.0 / (va + vb + vc);
        double v = vb * denom, w = vc * denom;
        double qx = ax + abx * v + acx * w, qy = ay + aby * v + acy * w, qz = az + abz * v + acz * w;
        double w0 = 1 - v - w, w1 = v, w2 = w;
        int32_t f = 0;
        const double e1 = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {  // edge 1 (b-c)
            qx = bx + e1 * (cx - bx), qy = by + e1 * (cy - by), qz = bz + e1 * (cz - bz);
            w0 = 0, w1 = 1 - e1, w2 = e1, f = 2;
        }
        const double e2 = d2 / (d2 - d6);
        if (vb <= 0 && d2 >= 0 && d6 <= 0) {  // edge 2 (a-c)
            qx = ax + e2 * acx, qy = ay + e2 * acy, qz = az + e2 * acz;
            w0 = 1 - e2, w1 = 0, w2 = e2, f = 3;
        }
        if (d6 >= 0 && d5 <= d6) {  // corner c
            qx = cx, qy = cy, qz = cz;
            w0 = 0, w1 = 0, w2 = 1, f = 6;
        }
        const double e0 = d1 / (d1 - d3);
        if (vc <= 0 && d1 >= 0 && d3 <= 0) {  // edge 0 (a-b)
            qx = ax + e0 * abx, qy = ay + e0 * aby, qz = az + e0 * abz;
            w0 = 1 - e0, w1 = e0, w2 = 0, f = 1;
        }
        if (d3 >= 0 && d4 <= d3) {  // corner b
            qx = bx, qy = by, qz = bz;
            w0 = 0, w1 = 1, w2 = 0, f = 5;
        }
        if (d1 <= 0 && d2 <= 0) {  // corner a
            qx = ax, qy = ay, qz = az;
            w0 = 1, w1 = 0, w2 = 0, f = 4;
        }
        out.point[0][l] = qx, out.point[1][l] = qy, out.point[2][l] = qz;
        out.w[0][l] = w0, out.w[1][l] = w1, out.w[2][l] = w2;
        out.feature[l] = f;
        out.h[l] = apx * in.n[0][l] + apy * in.n[1][l] + apz * in.n[2][l];
        const double dx = px - qx, dy = py - qy, dz = pz - qz;
        out.dist2[l] = dx * dx + dy * dy + dz * dz;
    }
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
