// The regularised friction law (Ft = -mu Fn vt / max(|vt|, vReg)) with its
// drag integrated implicitly (ContactLaw.hpp, doc/contacts.md "Regularised
// friction, implicit"): a block that lands sliding on a floor.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "contact/ContactLaw.hpp"
#include "material/Material.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

struct Landing {
    double reboundHeight;  // highest centroid after the first landing, above its rest height [m]
    double vxAfter;        // horizontal centroid speed when it leaves the floor [m/s]
    double friction;       // booked friction loss [J]
    double ledgerError;    // |total now - total at start| [J]
    double scale;          // m g h of the drop [J]
};

// The README's soft cube (0.4 m, E = 2 MPa, restitution of a contact 0.9),
// bottom 5 cm above a rigid floor, falling flat at 1 m/s: the bottom face's
// Poisson expansion on impact makes its nodes slide outwards.
Landing land(FrictionModel model) {
    World w;
    Material m;
    m.young = 2e6;
    m.poisson = 0.3;
    m.density = 1000;
    m.viscosity = 20;
    m.radius = 0.01;
    m.restitution = 0.9;
    m.frictionWall = 0.5;
    w.addPiece(boxMesh(4, 4, 4, 0.4, 0.4, 0.4, 6), w.addMaterial(m));
    const double z0 = 0.2 + 0.05;
    for (std::size_t i = 0; i < w.nNodes(); ++i) {
        w.pos[3 * i + 2] += z0;
        w.vel[3 * i + 2] = -1.0;
    }
    Obstacle o;
    o.kind = ObstacleKind::Wall;
    o.bodyId = 0;
    o.axis = 2;
    o.sense = 1;
    w.setObstacles({o});
    w.setObstacleState(0, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(),
                       Eigen::Vector3d::Zero());
    w.setGravity(Eigen::Vector3d(0, 0, -9.81));
    w.settings.frictionModel = model;
    w.settings.trackEnergy = true;
    const double dt = 0.8 * w.stableDt().combined;
    auto centroid = [&](int d) {
        double s = 0, ms = 0;
        for (std::size_t i = 0; i < w.nNodes(); ++i) s += w.mass[i] * w.pos[3 * i + d], ms += w.mass[i];
        return s / ms;
    };
    auto meanVel = [&](int d) {
        double s = 0, ms = 0;
        for (std::size_t i = 0; i < w.nNodes(); ++i) s += w.mass[i] * w.vel[3 * i + d], ms += w.mass[i];
        return s / ms;
    };
    w.step(dt);
    const double e0 = w.energy.total();
    Landing r{0, 0, 0, 0, 0};
    const double mass = w.pieces[0].mass;
    r.scale = mass * 9.81 * 0.1;
    bool touched = false, left = false;
    double top = -1;
    for (int i = 0; i < 200000; ++i) {
        w.step(dt);
        const bool inContact = w.obstacles[0].reactionForce.z() < 0;
        if (inContact) touched = true;
        if (touched && !inContact && !left) {
            left = true;
            r.vxAfter = meanVel(0);
        }
        if (left) {
            top = std::max(top, centroid(2));
            if (meanVel(2) < 0) break;  // at the top of the rebound
        }
    }
    r.reboundHeight = top - 0.2;
    r.friction = w.energy.friction;
    r.ledgerError = std::fabs(w.energy.total() - e0);
    return r;
}

}  // namespace

// The drag alone on one contact point (no spring, no other force): the slip
// decays monotonically whatever c dt / m (explicit: it reverses and grows
// once c dt / m > 2), and the booked loss equals the kinetic energy lost.
TEST(RegularizedFriction, ImplicitDragNeverReversesAndBooksWhatIsLost) {
    const double m = 0.01, fn = 100, mu = 0.5, vReg = 1e-3, dt = 1e-4;  // c dt / m = 500
    ContactParams p{1e5, 0, 1e5, 0, mu, vReg, m};
    const Eigen::Vector3d n(0, 0, 1);
    const double overlap = fn / p.kn;
    double v = 0.3, booked = 0;
    const double e0 = 0.5 * m * v * v;
    Eigen::Vector3d shear = Eigen::Vector3d::Zero();  // the previous step's force (the booking's history)
    for (int i = 0; i < 200; ++i) {
        const ContactResult r =
            contactForce<true, true>(p, n, overlap, Eigen::Vector3d(v, 0, 0), dt, shear);
        const double vNew = v + dt * r.force.x() / m;
        ASSERT_GE(vNew, 0.0) << "step " << i;
        ASSERT_LE(vNew, v);
        booked += r.slipWork;
        v = vNew;
    }
    EXPECT_LT(v, 1e-12);
    EXPECT_NEAR(booked, e0 - 0.5 * m * v * v, 1e-12 * e0);
}

// A block landing while sliding: the regularised law books as friction loss
// what the block loses (the ledger closes as well as the spring law's), and
// rebounds as the spring law does.  Before the implicit drag the same scene
// (the README drop) booked 72 J of "friction" in one impact.
TEST(RegularizedFriction, LandingKeepsTheLedgerAndTheRebound) {
    const Landing s = land(FrictionModel::Spring);
    const Landing g = land(FrictionModel::Regularized);
    // Ledger: the spring law's own closure error (contact-onset integration,
    // doc/hard_cases.md) is the yardstick; 2 % of m g h on top of it.
    EXPECT_LT(g.ledgerError, s.ledgerError + 0.02 * s.scale)
        << "regularized " << g.ledgerError << " J, spring " << s.ledgerError << " J";
    // What it books is real: the ledger closes (above), and it rebounds as
    // the spring law does (measured: 0.9 % higher; with the drag implicit
    // but the other forces not lagged in, stuck nodes crept and it booked
    // 2.3 J and rebounded 4.6 % lower; fully explicit it booked 19.5 J with a
    // 17.7 J ledger error).
    EXPECT_LT(g.friction, 0.01 * s.scale);
    EXPECT_NEAR(g.reboundHeight, s.reboundHeight, 0.03 * s.reboundHeight);
    EXPECT_GT(s.reboundHeight, 0.0);
    std::printf("spring: rebound %.5f m, friction %.4f J, ledger %.4f J; regularized: %.5f m, %.4f J, %.4f J; mgh %.3f J\n",
                s.reboundHeight, s.friction, s.ledgerError, g.reboundHeight, g.friction, g.ledgerError, s.scale);
}
