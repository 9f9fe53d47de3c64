// A contact kind with history added by one file and one row (and its switch
// line): nodeSpringTest (pkg/phases/NodeSpringKind.cpp), a bond between
// surface nodes of different pieces born within the reach R = r_a + r_b at
// its distance then, f = k (d - d0), k = E r / 10, broken at R.  Its force
// comes out as hand-computed from the rest length it remembers, the bond
// survives a restart (its history columns are saved), and breaks at R.
// (tests/arch/check_kind_files.py counts the files it took; the MPI run with
// a halo: tests/python/test_mpi_contact_kind_history.py.)
#include <gtest/gtest.h>

#include <cmath>

#include "material/Material.hpp"
#include "step/WorldState.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

// A tet with its apex at (0, 0, z) pointing up (sign +1) or down (-1).
TetMesh apexTet(double z, int sign) {
    TetMesh m;
    const double s = 0.1;
    m.nodes = {0, 0, z, s, 0, z + sign * s, -0.5 * s, 0.8 * s, z + sign * s, -0.5 * s, -0.8 * s, z + sign * s};
    m.tets = {0, 1, 2, 3};
    orientPositive(m);
    return m;
}

// Two apexes d0 = 0.015 m apart (R = 0.02 m), only the test kind on.
void build(World& w) {
    Material m;
    m.radius = 0.01;
    const int mat = w.addMaterial(m);
    w.addPiece(apexTet(0.0, -1), mat);
    w.addPiece(apexTet(0.015, +1), mat);
    w.settings.pointPolygonOn = false;
    w.settings.edgeEdgeOn = false;
    w.settings.nodeSpringTestOn = true;
}

// Piece 1 moved rigidly along z (no element force: only the bond acts).
void lift(World& w, double dz) {
    for (int32_t n = w.pieces[1].nodeBegin; n < w.pieces[1].nodeEnd; ++n) w.pos[3 * n + 2] += dz;
}

// The nodes stopped: the speed a bond force gave them in the last step
// would add the elements' damping to the forces read next.
void atRest(World& w) {
    for (std::size_t i = 0; i < w.vel.size(); ++i) w.vel[i] = 0;
}

// The two apexes' distance now [m].
double apexDistance(const World& w) {
    const int32_t a0 = w.pieces[0].nodeBegin, a1 = w.pieces[1].nodeBegin;
    double d2 = 0;
    for (int c = 0; c < 3; ++c) d2 += (w.pos[3 * a1 + c] - w.pos[3 * a0 + c]) * (w.pos[3 * a1 + c] - w.pos[3 * a0 + c]);
    return std::sqrt(d2);
}

}  // namespace

TEST(ContactKindHistory, BondRemembersItsRestLengthAcrossStepsAndRestarts) {
    World w;
    build(w);
    const double k = 0.1 * w.materials[0].young * w.materials[0].radius;
    const int32_t a0 = w.pieces[0].nodeBegin, a1 = w.pieces[1].nodeBegin;
    const double dt = 1e-9;
    const double d0 = apexDistance(w);
    w.step(dt);  // born at rest: no force
    EXPECT_EQ(w.report().count("nodeSpringTest"), 1);
    const double f0 = std::abs(w.force[3 * a1 + 2]);
    EXPECT_LT(f0, 1e-6);
    // Stretched by 1 mm: pulled back by k x 1 mm (a history-free kind would
    // see a contact born at 16 mm with no force, or a repulsion).
    const double dz = 1e-3;
    lift(w, dz);
    const double f = k * (apexDistance(w) - d0);  // (the first step moved the apexes by ~1e-14 m)
    EXPECT_NEAR(f, k * dz, 1e-6 * k * dz);
    w.step(dt);
    EXPECT_EQ(w.report().count("nodeSpringTest"), 1);
    EXPECT_NEAR(w.force[3 * a1 + 2], -f, 1e-6 * f);
    EXPECT_NEAR(w.force[3 * a0 + 2], f, 1e-6 * f);
    // Saved and loaded into a fresh world: the bond and its rest length go on.
    const WorldState st = w.saveState();
    World back;
    build(back);
    back.loadState(st);
    atRest(back);
    lift(back, dz);  // stretched by 2 mm now
    const double f2 = k * (apexDistance(back) - d0);
    back.step(dt);
    EXPECT_EQ(back.report().count("nodeSpringTest"), 1);
    EXPECT_NEAR(back.force[3 * a1 + 2], -f2, 1e-6 * f2);
    EXPECT_NEAR(f2, 2 * k * dz, 1e-3 * k * dz);
    // Stretched to the reach (apexes 20.5 mm apart): broken, and no new bond
    // forms until they come within R again.
    lift(back, 0.0035);
    atRest(back);
    back.step(dt);
    EXPECT_EQ(back.report().count("nodeSpringTest"), 0);
    EXPECT_LT(std::abs(back.force[3 * a1 + 2]), 1e-6);
    // Back to 19 mm: a new bond, at rest there.
    lift(back, -0.0015);
    EXPECT_LT(apexDistance(back), 0.02);
    atRest(back);
    back.step(dt);
    EXPECT_EQ(back.report().count("nodeSpringTest"), 1);
    EXPECT_LT(std::abs(back.force[3 * a1 + 2]), 1e-6);
}
