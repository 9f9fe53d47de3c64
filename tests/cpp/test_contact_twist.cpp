// The twist of the tangential spring: the spring turned by the contact's spin
// about its normal (ContactLaw.hpp).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "../../pkg/contact/ContactLaw.hpp"

using Eigen::Vector3d;
using namespace qdem;

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
