// The spin of a piece's surface at its nodes (contact/SurfaceSpin.hpp), by
// which piece-piece springs turn: exact at every surface node (faces, edges,
// corners) for a rigid motion; along a face's normal, untouched by any
// strain rate; and a stuck spring turned by it follows a turning body,
// storing what it stored.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "contact/ContactLaw.hpp"
#include "contact/SurfaceSpin.hpp"
#include "material/Material.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"

using Eigen::Matrix3d;
using Eigen::Vector3d;
using namespace qdem;

namespace {

// One 0.1 x 0.08 x 0.06 block, 3 x 3 x 2 cells, centred at the origin.
void block(World& w) {
    Material m;
    m.young = 1e6, m.poisson = 0.3, m.density = 1000, m.radius = 0.005, m.frictionPiece = 0.5;
    w.addPiece(boxMesh(3, 3, 2, 0.1, 0.08, 0.06, 6), w.addMaterial(m));
}

// Every node's velocity v0 + G (x - c).
void setVelocity(World& w, const Vector3d& v0, const Matrix3d& G, const Vector3d& c) {
    for (std::size_t i = 0; i < w.pos.size() / 3; ++i) {
        const Vector3d v = v0 + G * (Vector3d(w.pos[3 * i], w.pos[3 * i + 1], w.pos[3 * i + 2]) - c);
        for (int d = 0; d < 3; ++d) w.vel[3 * i + d] = v[d];
    }
}

Matrix3d cross(const Vector3d& a) {
    Matrix3d m;
    m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    return m;
}

Vector3d spinAt(const World& w, int32_t s) {
    double o[3];
    EXPECT_TRUE(surfaceNodeSpin(w.surfaceIndex(), s, w.surfNodes[s], w.pos.data(), w.vel.data(), nullptr, o));
    return Vector3d(o[0], o[1], o[2]);
}

}  // namespace

TEST(SurfaceSpin, ARigidMotionGivesItsAngularVelocityAtEveryNode) {
    World w;
    block(w);
    const Vector3d omega(0.3, -1.2, 2.5);
    setVelocity(w, Vector3d(4, -2, 1), cross(omega), Vector3d(0.5, 0.2, -0.1));  // fast, about a point off the block
    ASSERT_GT(w.surfNodes.size(), 40u);
    for (std::size_t s = 0; s < w.surfNodes.size(); ++s)
        EXPECT_LT((spinAt(w, static_cast<int32_t>(s)) - omega).norm(), 1e-12 * omega.norm()) << "surface node " << s;
}

TEST(SurfaceSpin, AStrainRateAddsNothingAboutAFaceNormal) {
    // A shear and stretch rate on top of the spin: at the nodes inside a
    // face (flat ring), the spin about the face's normal is the rigid one
    // (the ring's circulation); the fit alone took a share of the strain.
    World w;
    block(w);
    const Vector3d omega(0.7, 0.4, -1.5);
    Matrix3d E;
    E << 2.0, 0.9, -0.4, 0.9, -1.1, 0.6, -0.4, 0.6, 0.5;
    setVelocity(w, Vector3d(0.1, 0, 0), cross(omega) + E, Vector3d::Zero());
    const Vector3d half(0.05, 0.04, 0.03);
    int inside = 0;
    for (std::size_t s = 0; s < w.surfNodes.size(); ++s) {
        const Vector3d x(w.pos[3 * w.surfNodes[s]], w.pos[3 * w.surfNodes[s] + 1], w.pos[3 * w.surfNodes[s] + 2]);
        int onFace = -1, bounds = 0;
        for (int d = 0; d < 3; ++d)
            if (std::abs(std::abs(x[d]) - half[d]) < 1e-12) onFace = d, ++bounds;
        if (bounds != 1) continue;  // on an edge or a corner
        ++inside;
        const Vector3d n = Vector3d::Unit(onFace);
        EXPECT_NEAR(spinAt(w, static_cast<int32_t>(s)).dot(n), omega.dot(n), 1e-12) << "surface node " << s;
    }
    EXPECT_GT(inside, 10);
}

TEST(SurfaceSpin, AStuckSpringTurnedByItFollowsTheBodyAndKeepsItsEnergy) {
    // The block turning rigidly at w about z (positions stepped with it):
    // a stuck spring at a point of its top face, turned each step by the
    // mean of the two sides' spins there (the contact's other side turning
    // with it), ends turned with the body, its energy unchanged.
    World w;
    block(w);
    const double wz = 3.0, dt = 1e-4;
    const int steps = 5000;  // 1.5 rad
    const SurfaceIndex& S = w.surfaceIndex();
    int32_t top = -1;  // a triangle of the top face
    for (std::size_t t = 0; t < S.nTris() && top < 0; ++t) {
        bool up = true;
        for (int k = 0; k < 3; ++k) up = up && std::abs(w.pos[3 * S.tri[3 * t + k] + 2] - 0.03) < 1e-12;
        if (up) top = static_cast<int32_t>(t);
    }
    ASSERT_GE(top, 0);
    const ContactParams p{1e4, 0, 8e3, 0, 0.5};
    const Vector3d u0(2e-4, -1e-4, 0);
    Vector3d shear = u0;
    const double overlap = 1e-3;  // cap 5 N > kt |u| = 1.8 N: stuck
    double elastic0 = -1, worst = 0;
    const Vector3d bary(0.2, 0.3, 0.5);
    for (int i = 0; i < steps; ++i) {
        setVelocity(w, Vector3d::Zero(), cross(Vector3d(0, 0, wz)), Vector3d::Zero());
        Vector3d spin = Vector3d::Zero();
        for (int k = 0; k < 3; ++k) spin += bary[k] * spinAt(w, S.surfIndexOfNode[S.tri[3 * top + k]]);
        const Vector3d n(0, 0, 1);
        const double s = 0.5 * (spin + spin).dot(n);  // both sides turn alike: stuck
        const ContactResult r = contactForce<true>(p, n, overlap, Vector3d::Zero(), dt, shear, s);
        if (elastic0 < 0) elastic0 = r.elastic;
        worst = std::max(worst, std::abs(r.elastic - elastic0) / elastic0);
        // The body turns by wz dt (exactly, not by its velocities).
        const Matrix3d Rz = Eigen::AngleAxisd(wz * dt, Vector3d::UnitZ()).toRotationMatrix();
        for (std::size_t j = 0; j < w.pos.size() / 3; ++j) {
            const Vector3d x = Rz * Vector3d(w.pos[3 * j], w.pos[3 * j + 1], w.pos[3 * j + 2]);
            for (int d = 0; d < 3; ++d) w.pos[3 * j + d] = x[d];
        }
    }
    // Kept to rounding: the rotations' last bits add up over the steps
    // (measured 1.8e-14 after 5000).
    EXPECT_LT(worst, 1e-12);
    const Vector3d expected = Eigen::AngleAxisd(wz * dt * steps, Vector3d::UnitZ()) * u0;
    EXPECT_LT((shear - expected).norm(), 1e-9 * u0.norm());
}
