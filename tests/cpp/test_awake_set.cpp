// The awake set is data (pkg/step/AwakeSet.hpp): the sleep phase writes it,
// every other reader holds it const, and no two phases hold each other
// writable.  And its readers see every change: a piece put to sleep and
// woken between two steps, or held and let go, steps as one never asleep.
#include <gtest/gtest.h>

#include <type_traits>

#include "mesh/BoxMesh.hpp"
#include "phases/ElementPhase.hpp"
#include "phases/IntegrationPhase.hpp"
#include "phases/ObstaclePhase.hpp"
#include "phases/PieceContactPhase.hpp"
#include "phases/SleepPhase.hpp"
#include "phases/ViscousSolve.hpp"
#include "step/ContactForces.hpp"
#include "step/PieceBounds.hpp"
#include "world/World.hpp"

using namespace qdem;

TEST(AwakeSet, WrittenBySleepOnlyReadByTheOthers) {
    static_assert(std::is_same_v<decltype(SleepPhase::Data::awake), AwakeSet&>);
    static_assert(std::is_same_v<decltype(ObstaclePhase::Data::sleeping), const AwakeSet&>);
    static_assert(std::is_same_v<decltype(PieceContactData::sleeping), const AwakeSet&>);
    static_assert(std::is_same_v<decltype(ElementPhase::Data::sleeping), const AwakeSet&>);
    static_assert(std::is_same_v<decltype(IntegrationPhase::Data::sleeping), const AwakeSet&>);
    static_assert(std::is_same_v<decltype(ViscousSolve::Data::sleeping), const AwakeSet&>);
    static_assert(std::is_same_v<decltype(PieceBounds::Data::sleeping), const AwakeSet&>);
    static_assert(std::is_constructible_v<ContactForces, const std::vector<PieceInfo>&, const Column<int32_t>&,
                                          const AwakeSet&>);
    // The sleep phase reads the piece-contact phase's lists, never writes them.
    static_assert(std::is_same_v<decltype(SleepPhase::Data::pieceContacts), const PieceContactPhase&>);
    SUCCEED();
}

namespace {

// Two unit cubes of 2^3 cells side by side, 1 mm apart (within the contact
// reach: they push each other apart), falling under gravity.
void twoCubes(World& w) {
    Material m;
    m.young = 1e6;
    m.poisson = 0.3;
    m.density = 1000;
    m.radius = 0.02;
    const int mat = w.addMaterial(m);
    TetMesh cube = boxMesh(2, 2, 2, 1, 1, 1, 6);
    w.addPiece(cube, mat);
    for (std::size_t i = 0; i < cube.nNodes(); ++i) cube.nodes[3 * i] += 1.001;
    w.addPiece(cube, mat);
    w.setGravity(Eigen::Vector3d(0, 0, -9.81));
}

}  // namespace

TEST(AwakeSet, ASleepAndWakeBetweenStepsChangesNothing) {
    World a, b;
    twoCubes(a);
    twoCubes(b);
    // Half the limit with the contacts as they are (the run-time piece
    // contact step): one short step forms them.
    const double dt0 = 0.1 * a.stableDt().combined;
    a.step(dt0), b.step(dt0);
    const double dt = 0.5 * a.stableDt().combined;
    for (int i = 0; i < 20; ++i) a.step(dt), b.step(dt);
    // b: the second cube held (asleep, velocities zeroed) and let go before
    // its next step; a: the same velocities zeroed by hand, never asleep.
    b.setDynamic(1, false);
    EXPECT_TRUE(b.asleep(1));
    b.setDynamic(1, true);
    EXPECT_FALSE(b.asleep(1));
    for (std::size_t n = a.pieces[1].nodeBegin; n < static_cast<std::size_t>(a.pieces[1].nodeEnd); ++n)
        for (int d = 0; d < 3; ++d) a.vel[3 * n + d] = 0;
    for (int i = 0; i < 20; ++i) a.step(dt), b.step(dt);
    for (std::size_t k = 0; k < a.pos.size(); ++k) {
        ASSERT_EQ(a.pos[k], b.pos[k]) << k;
        ASSERT_EQ(a.vel[k], b.vel[k]) << k;
    }
}
