// Stable time step: the leapfrog limit formula and the engine's refusal.
#include <gtest/gtest.h>

#include <cmath>

#include "core/Errors.hpp"
#include "material/Material.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {
// Damped oscillator with the velocity lagging half a step (the scheme's
// treatment of dashpots); returns the amplitude growth after n steps.
double growth(double omega, double xi, double dt, int n = 4000) {
    double x = 1, v = 0;
    for (int i = 0; i < n; ++i) {
        const double a = -omega * omega * x - 2 * xi * omega * v;
        v += dt * a;
        x += dt * v;
    }
    return std::fabs(x) + std::fabs(v) / omega;
}
}  // namespace

TEST(Stability, LeapfrogLimitIsSharp) {
    for (double xi : {0.0, 0.3, 2.0, 30.0}) {
        const double w = 1000, dt = leapfrogLimit(w, xi);
        // Bounded just below the limit (near it the velocity amplitude is
        // large but constant), exploding (or overflowing) just above it.
        EXPECT_LT(growth(w, xi, 0.99 * dt), 100.0) << xi;
        EXPECT_FALSE(growth(w, xi, 1.02 * dt) < 1e6) << xi;
    }
}

TEST(Stability, RestitutionDampingRatio) {
    EXPECT_DOUBLE_EQ(dampingRatioFromRestitution(1.0), 0.0);
    // e = exp(-pi xi / sqrt(1 - xi^2)) inverted
    const double xi = dampingRatioFromRestitution(0.5);
    EXPECT_NEAR(std::exp(-M_PI * xi / std::sqrt(1 - xi * xi)), 0.5, 1e-12);
}

TEST(Stability, EngineRefusesUnstableStepNamingTheLimit) {
    World w;
    Material m;
    w.addPiece(boxMesh(4, 4, 4, 1, 1, 1, 6), w.addMaterial(m));
    const StableDt s = w.stableDt();
    EXPECT_EQ(s.limitedBy, "viscosity");  // Table 1 at metre scale: viscosity dominates
    EXPECT_NO_THROW(w.checkDt(0.99 * s.combined));
    try {
        w.checkDt(2 * s.combined);
        FAIL() << "no exception";
    } catch (const StabilityError& e) {
        EXPECT_NE(std::string(e.what()).find("viscosity"), std::string::npos);
    }
}

TEST(Stability, ElasticBlockStaysBoundedAtTheLimit) {
    World w;
    Material m;
    m.viscosity = 0;
    w.addPiece(boxMesh(3, 3, 3, 1, 1, 1, 5), w.addMaterial(m));
    for (std::size_t i = 0; i < w.pos.size(); ++i) w.pos[i] += 1e-3 * std::sin(7.0 * i);
    const double dt = 0.99 * w.stableDt().combined;
    for (int i = 0; i < 20000; ++i) w.step(dt);
    EXPECT_NO_THROW(w.checkFinite());
    double vmax = 0;
    for (std::size_t i = 0; i < w.vel.size(); ++i) vmax = std::max(vmax, std::fabs(w.vel[i]));
    EXPECT_LT(vmax, 100.0);
}
