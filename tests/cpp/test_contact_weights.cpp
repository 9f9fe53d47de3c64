// Contact stiffness per surface node weighted by its share of the surface
// area (World::surfWeight, doc/contacts.md "Area weights").
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "material/Material.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

double materialRadius(const World& w) { return w.materials[0].radius; }

// A one-sided rigid floor z = 0 (normal +z).
Obstacle floorWall() {
    Obstacle o;
    o.kind = ObstacleKind::Wall;
    o.bodyId = 0;
    o.axis = 2;
    o.sense = 1;
    return o;
}

// Steps a world once, with every node still, its lowest nodes at overlap
// delta with the floor; returns the reaction centre (x, y) of the floor
// (sum x_i f_i / sum f_i, from the wall's reaction torque about its origin:
// the contact points lie on the plane z = 0, so tau = sum x_i x (-f_i)).
Eigen::Vector2d reactionCentre(World& w, double delta, double& fz) {
    double zmin = 1e300;
    for (std::size_t i = 0; i < w.nNodes(); ++i) zmin = std::min(zmin, w.pos[3 * i + 2]);
    const double shift = materialRadius(w) - delta - zmin;
    for (std::size_t i = 0; i < w.nNodes(); ++i) w.pos[3 * i + 2] += shift;
    w.setObstacles({floorWall()});
    w.setObstacleState(0, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(),
                       Eigen::Vector3d::Zero());
    w.step(1e-7);
    const Obstacle& o = w.obstacles[0];
    fz = -o.reactionForce.z();  // on the block
    return Eigen::Vector2d(-o.reactionTorque.y() / o.reactionForce.z(), o.reactionTorque.x() / o.reactionForce.z());
}

// A 0.4 m block whose cells are graded along x and y (spacing growing from
// the -x, -y sides: u -> u^p on [0, 1]), so its bottom face has small
// triangles on one side and large ones on the other; the face is still the
// full square, its area centre at (0, 0).
TetMesh gradedBlock(int tetsPerCell) {
    TetMesh m = boxMesh(6, 6, 4, 0.4, 0.4, 0.2, tetsPerCell);
    for (std::size_t i = 0; i < m.nNodes(); ++i) {
        m.nodes[3 * i] = 0.4 * (std::pow(m.nodes[3 * i] / 0.4 + 0.5, 2.0) - 0.5);
        m.nodes[3 * i + 1] = 0.4 * (std::pow(m.nodes[3 * i + 1] / 0.4 + 0.5, 1.6) - 0.5);
    }
    return m;
}

Material softMaterial() {
    Material m;
    m.young = 2e6;
    m.poisson = 0.3;
    m.density = 1000;
    m.viscosity = 0;
    m.radius = 0.01;
    return m;
}

}  // namespace

// A uniform overlap of the bottom face (a uniform pressure on the floor):
// with area weights the reaction centre is the face's area centre; with one
// stiffness per node it is the centre of the node positions, pulled towards
// the finely meshed side.
TEST(ContactWeights, ReactionCentreIsTheAreaCentre) {
    for (int k : {5, 6, 12}) {
        World w;
        w.addPiece(gradedBlock(k), w.addMaterial(softMaterial()));
        double fz = 0;
        const Eigen::Vector2d c = reactionCentre(w, 1e-3, fz);
        // Perimeter nodes also count their share of the side faces
        // (doc/contacts.md "Area weights"): 1.3 mm here with 6 and 12 tets per
        // cell, 0.4 mm with 5, against 55 mm without the weights.
        EXPECT_LT(c.norm(), 1.5e-3) << k << " tets/cell: reaction centre (" << c.x() << ", " << c.y() << ")";
        // The same with every weight set to 1 (the law before the weights):
        // the test can fail.
        World u;
        u.addPiece(gradedBlock(k), u.addMaterial(softMaterial()));
        for (std::size_t s = 0; s < u.surfWeight.size(); ++s) u.surfWeight[s] = 1.0;
        double fu = 0;
        const Eigen::Vector2d cu = reactionCentre(u, 1e-3, fu);
        EXPECT_GT(cu.norm(), 20 * c.norm()) << k << " tets/cell";
        EXPECT_GT(cu.norm(), 0.02);
        std::printf("%d tets/cell: weighted (%.5f, %.5f), unweighted (%.5f, %.5f)\n", k, c.x(), c.y(), cu.x(), cu.y());
        // Total stiffness: the weights of a closed surface average 1.
        double sum = 0;
        for (std::size_t s = 0; s < w.surfWeight.size(); ++s) sum += w.surfWeight[s];
        EXPECT_NEAR(sum / w.surfWeight.size(), 1.0, 1e-12);
    }
}

// A mesh whose surface nodes all have the same share of the area (a regular
// tetrahedron) keeps the unweighted stiffness kn = 2 E r exactly.
TEST(ContactWeights, EqualSharesKeepTheStiffness) {
    TetMesh m;
    m.nodes = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
    m.tets = {0, 1, 2, 3};
    orientPositive(m);
    World w;
    const Material mat = softMaterial();
    w.addPiece(m, w.addMaterial(mat));
    for (std::size_t s = 0; s < w.surfWeight.size(); ++s) EXPECT_NEAR(w.surfWeight[s], 1.0, 1e-14);
    // An edge down: its two nodes on the floor.
    double fz = 0;
    reactionCentre(w, 1e-3, fz);
    EXPECT_NEAR(fz, 2 * (2 * mat.young * mat.radius) * 1e-3, 1e-9 * fz);
}

// The largest step for which a node of mass m on springs k (x, y, z) with
// dashpots c stays bounded, found from the scheme itself (the velocity lagging
// half a step, as the integrator treats dashpots): the spectral radius of the
// one-step map of (x_n, v_{n-1/2}) at most 1, by bisection on dt.  No formula
// of the implementation is used.
static double nodeStableStep(double m, const Eigen::Vector3d& k, const Eigen::Vector3d& c) {
    auto radius = [&](double dt) {
        Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
        for (int d = 0; d < 3; ++d) {
            const double keep = 1 - dt * c[d] / m;  // v_{n+1/2} = keep v_{n-1/2} - dt k/m x_n
            A(3 + d, d) = -dt * k[d] / m;
            A(3 + d, 3 + d) = keep;
            A(d, d) = 1 - dt * dt * k[d] / m;  // x_{n+1} = x_n + dt v_{n+1/2}
            A(d, 3 + d) = dt * keep;
        }
        return A.eigenvalues().cwiseAbs().maxCoeff();
    };
    double lo = 0, hi = 1e-3 * std::sqrt(m / k.maxCoeff());
    while (radius(hi) <= 1 + 1e-12) lo = hi, hi *= 2;
    for (int i = 0; i < 80; ++i) {
        const double mid = 0.5 * (lo + hi);
        (radius(mid) <= 1 + 1e-12 ? lo : hi) = mid;
    }
    return lo;
}

// The contact stable step is that of the node whose springs, scaled by its
// area weight, are stiffest for its mass, with BOTH its normal spring kn and
// its two tangential springs kt (sticking friction): for Poisson's ratio < 0
// Mindlin's kt / kn = 2 (1 - nu) / (2 - nu) is above 1 and the tangential
// mode is the fastest.  Computed here node by node from the springs of the
// contact law (doc/contacts.md: kn = 2 E r against a rigid wall, kt from
// Mindlin, dashpots 2 xi sqrt(k m) in both directions, springs x w, dashpots
// x sqrt(w)).
TEST(ContactWeights, StableStepIsTheFastestNodeOnItsNormalAndTangentialSprings) {
    for (double nu : {0.3, 0.0, -0.5}) {
        World w;
        Material mat = softMaterial();
        mat.poisson = nu;
        mat.viscosity = 0;
        w.addPiece(gradedBlock(6), w.addMaterial(mat));
        w.setObstacles({floorWall()});
        const double kn = 2 * mat.young * mat.radius, kt = kn * 2 * (1 - nu) / (2 - nu);
        const double le = std::log(mat.restitution), xi = -le / std::sqrt(M_PI * M_PI + le * le);
        double expected = 1e300, unweighted = 1e300;
        const PieceInfo& p = w.pieces[0];
        for (int32_t s = p.surfBegin; s < p.surfEnd; ++s) {
            const double m = w.mass[w.surfNodes[s]], ws = w.surfWeight[s];
            const Eigen::Vector3d k(ws * kt, ws * kt, ws * kn);
            const Eigen::Vector3d c(2 * xi * std::sqrt(k.x() * m), 2 * xi * std::sqrt(k.y() * m),
                                    2 * xi * std::sqrt(k.z() * m));
            expected = std::min(expected, nodeStableStep(m, k, c));
            const Eigen::Vector3d k1(kt, kt, kn);
            const Eigen::Vector3d c1(2 * xi * std::sqrt(kt * m), 2 * xi * std::sqrt(kt * m), 2 * xi * std::sqrt(kn * m));
            unweighted = std::min(unweighted, nodeStableStep(m, k1, c1));
        }
        const double got = w.stableDt().contact;
        std::printf("nu = %4.1f: kt/kn = %.3f, contact stable step %.6e s, the fastest node's %.6e s (ratio %.4f)\n", nu,
                    kt / kn, got, expected, got / expected);
        EXPECT_NEAR(got, expected, 1e-6 * expected) << "nu = " << nu << ", kt/kn = " << kt / kn;
        // The graded mesh's stiffest node is not its lightest: the weights count.
        EXPECT_GT(std::fabs(unweighted / expected - 1), 0.01) << nu;
    }
}
