// Contact stiffness per surface node weighted by its share of the surface
// area (World::surfWeight, doc/contacts.md "Area weights").
#include <gtest/gtest.h>

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

// The contact stable step follows the stiffest weighted spring: the largest
// w_i kn / m_i over the surface nodes.
TEST(ContactWeights, StableStepUsesTheLargestWeightedStiffness) {
    World w;
    const Material mat = softMaterial();
    w.addPiece(gradedBlock(6), w.addMaterial(mat));
    w.setObstacles({floorWall()});
    double best = 0, unweighted = 0;
    const PieceInfo& p = w.pieces[0];
    for (int32_t s = p.surfBegin; s < p.surfEnd; ++s) {
        best = std::max(best, w.surfWeight[s] / w.mass[w.surfNodes[s]]);
        unweighted = std::max(unweighted, 1.0 / w.mass[w.surfNodes[s]]);
    }
    const double kn = 2 * mat.young * mat.radius;
    const double xi = dampingRatioFromRestitution(mat.restitution);
    EXPECT_NEAR(w.stableDt().contact, leapfrogLimit(std::sqrt(kn * best), xi), 1e-12);
    EXPECT_NE(best, unweighted);  // the graded mesh's stiffest node is not its lightest
}
