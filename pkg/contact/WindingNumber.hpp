// Inside or outside a piece's closed surface: the winding number.
#pragma once
#include <cmath>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace qdem {

// Winding number of the closed, outward-oriented triangle surface tris[t0..t1)
// around x: 1 inside, 0 outside (sum of the triangles' solid angles over 4 pi;
// Van Oosterom and Strackee, IEEE Trans. Biomed. Eng. 30(2), 1983).
inline double windingNumber(const Eigen::Vector3d& x, const int32_t* tris, int32_t t0, int32_t t1, const double* X) {
    double omega = 0;
    for (int32_t t = t0; t < t1; ++t) {
        const Eigen::Vector3d a = Eigen::Map<const Eigen::Vector3d>(X + 3 * tris[3 * t]) - x;
        const Eigen::Vector3d b = Eigen::Map<const Eigen::Vector3d>(X + 3 * tris[3 * t + 1]) - x;
        const Eigen::Vector3d c = Eigen::Map<const Eigen::Vector3d>(X + 3 * tris[3 * t + 2]) - x;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        const double num = a.dot(b.cross(c));
        const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        omega += 2 * std::atan2(num, den);
    }
    return omega / (4 * M_PI);
}

}  // namespace qdem
