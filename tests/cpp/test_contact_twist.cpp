// The twist of the tangential spring: the spin of a contact about its normal
// (ContactSpin.hpp) and the spring turned by it (ContactLaw.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "../../pkg/contact/ContactLaw.hpp"
#include "../../pkg/contact/ContactSpin.hpp"

using Eigen::Vector3d;
using namespace qdem;

namespace {
// A rigid motion: velocity v + w x (x - c) of the point x.
Vector3d rigid(const Vector3d& v, const Vector3d& w, const Vector3d& c, const Vector3d& x) { return v + w.cross(x - c); }
}  // namespace

TEST(ContactTwist, TriangleSpinOfARigidMotionIsItsAngularVelocityAboutTheNormal) {
    const Vector3d x0(0.1, -0.2, 0.3), x1(0.4, 0.1, 0.25), x2(0.05, 0.3, 0.5);
    const Vector3d nt = (x1 - x0).cross(x2 - x0).normalized();
    const Vector3d v(0.3, -1.0, 2.0), w(0.7, -1.3, 2.1), c(1, 2, 3);
    const Vector3d n = (nt + Vector3d(0.1, 0.05, -0.02)).normalized();  // a contact normal off the face normal
    const double s = triangleSpin(x0, x1, x2, rigid(v, w, c, x0), rigid(v, w, c, x1), rigid(v, w, c, x2), n);
    EXPECT_NEAR(s, w.dot(nt) * nt.dot(n), 1e-12);
    // Either orientation of the corners: the spin is about n, not about the winding.
    EXPECT_NEAR(triangleSpin(x0, x2, x1, rigid(v, w, c, x0), rigid(v, w, c, x2), rigid(v, w, c, x1), n), s, 1e-12);
    // A translating triangle has none, exactly (non-spinning contacts keep their forces bit for bit).
    EXPECT_EQ(triangleSpin(x0, x1, x2, v, v, v, n), 0.0);
}

TEST(ContactTwist, TriangleSpinIgnoresStrain) {
    // A pure in-plane stretch and a pure shear strain (symmetric velocity
    // gradients) turn nothing: the spin is the gradient's antisymmetric part.
    const Vector3d x0(0, 0, 0), x1(1, 0.2, 0), x2(0.3, 0.8, 0), n(0, 0, 1);
    Eigen::Matrix3d L;
    L << 0.5, 0.2, 0, 0.2, -0.3, 0, 0, 0, 0;
    EXPECT_NEAR(triangleSpin(x0, x1, x2, L * x0, L * x1, L * x2, n), 0.0, 1e-14);
    L(0, 1) += 0.4;  // plus a spin of (0.2 - 0.6) / 2 = -0.2 about z
    EXPECT_NEAR(triangleSpin(x0, x1, x2, L * x0, L * x1, L * x2, n), -0.2, 1e-14);
}

TEST(ContactTwist, SegmentSpinOfARigidMotion) {
    const Vector3d p(0.1, 0.2, 0.3), q(0.5, -0.1, 0.3), n(0, 0, 1);
    const Vector3d v(1, 2, 3), w(0.4, -0.2, 1.7), c(0, 0, 0);
    EXPECT_NEAR(segmentSpin(p, q, rigid(v, w, c, p), rigid(v, w, c, q), n), w.z(), 1e-12);
    EXPECT_EQ(segmentSpin(p, q, v, v, n), 0.0);
}

TEST(ContactTwist, ASpinningStuckSpringTurnsKeepingItsLengthAndEnergy) {
    // A contact turning at spin about n with no relative velocity: the spring
    // turns with it, by spin * t, and stores what it stored.
    const ContactParams p{1e4, 0, 8e3, 0, 0.5};
    const Vector3d n(0, 0, 1);
    Vector3d shear(1e-4, 0, 0);
    const double dt = 1e-4, spin = 2.0, overlap = 1e-3;  // Fn = 10 N, cap 5 N > kt |u| = 0.8 N
    double elastic0 = 0;
    const int steps = 5000;
    for (int i = 0; i < steps; ++i) {
        const ContactResult r = contactForce<true>(p, n, overlap, Vector3d::Zero(), dt, shear, spin);
        if (i == 0) elastic0 = r.elastic;
        EXPECT_NEAR(r.elastic, elastic0, 1e-15);
        EXPECT_EQ(r.slipWork, 0.0);
        EXPECT_NEAR(r.dampPower, 0.0, 1e-15);
    }
    const double a = spin * dt * steps;
    EXPECT_NEAR(shear.x(), 1e-4 * std::cos(a), 1e-15);
    EXPECT_NEAR(shear.y(), 1e-4 * std::sin(a), 1e-15);
    EXPECT_NEAR(shear.z(), 0.0, 1e-18);
    // The force follows the spring: -kt u, turned by the same angle.
    Vector3d s2 = shear;
    const ContactResult r = contactForce<true>(p, n, overlap, Vector3d::Zero(), dt, s2, 0.0);
    EXPECT_NEAR((r.force - p.kn * overlap * n + p.kt * shear).norm(), 0.0, 1e-12);
}
