// Reference-force tests per contact kernel (issue 13 item 8), in the manner of
// LAMMPS' force-style tests: a tiny fixed geometry (one or two tetrahedra, a
// wall, box, facet or YADE sphere), one step, and every force and torque
// compared with the value computed here by hand from the documented law
// (doc/contacts.md §3-5, doc/formulation.md §4, doc/spheres.md §2-3):
//
//   kn = 2 (E_a r_a)(E_b r_b) / (E_a r_a + E_b r_b)  (2 E r for a rigid obstacle)
//   kn_i = w_i kn, kt_i = w_i kt      w_i: the node's area weight
//   kt = 2 (1 - nu) / (2 - nu) kn     (Mindlin; nu the mean Poisson ratio)
//   cn = 2 xi sqrt(kn_i m), ct = 2 xi sqrt(kt_i m),  xi = -ln e / sqrt(pi^2 + ln^2 e)
//   Fn = max(0, kn_i delta - cn v_n); Ft = -kt_i v_t dt - ct v_t (first step),
//   capped at mu Fn; regularised: |Ft| = min(mu Fn, c |v_t| / (1 + c dt / m_eff)), c = mu Fn / vReg
//
// Every expected number is derived in this file from positions, materials and
// velocities; nothing is read back from the code under test except the
// outputs being checked.  Velocities are rigid-body motions of whole pieces,
// so the (zero) viscosity and the undeformed elements add no force: the
// element forces at the reference shape are rounding, ~1e-13 of the contact
// forces here: the largest deviation measured over all checks is 2e-13 of
// the checked force (point-polygon, B's nodes: ~1.5e-10 N of element-force
// rounding against ~1.7e3 N), so the 1e-12 tolerance has a margin of 5.
//
// Only World's public set-up/step/output members are used, and only through
// the helpers of the first block below, so that a change of World's
// interface is adapted in one place.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "material/Material.hpp"
#include "mesh/TetMesh.hpp"
#include "world/World.hpp"

using namespace qdem;
using Eigen::Vector3d;

namespace {

// =====================================================================
// The only calls into World (adapt here when its interface changes).
// =====================================================================

using Tet = std::array<Vector3d, 4>;

int addTetPiece(World& w, const Tet& x, int material) {
    TetMesh m;
    for (const Vector3d& p : x) m.nodes.insert(m.nodes.end(), {p.x(), p.y(), p.z()});
    m.tets = {0, 1, 2, 3};
    orientPositive(m);  // swaps connectivity only: node k stays node k
    return w.addPiece(m, material);
}
int32_t nodeId(const World& w, int piece, int k) { return w.pieces[piece].nodeBegin + k; }
Vector3d forceOn(const World& w, int32_t n) { return Vector3d(w.force[3 * n], w.force[3 * n + 1], w.force[3 * n + 2]); }
void setPieceVelocity(World& w, int piece, const Vector3d& v) {
    for (int32_t n = w.pieces[piece].nodeBegin; n < w.pieces[piece].nodeEnd; ++n)
        for (int d = 0; d < 3; ++d) w.vel[3 * n + d] = v[d];
}
void setObstacle(World& w, const Obstacle& o, const Vector3d& pos, const Eigen::Quaterniond& ori,
                 const Vector3d& vel = Vector3d::Zero(), const Vector3d& angVel = Vector3d::Zero()) {
    w.setObstacles({o});
    w.setObstacleState(0, pos, ori, vel, angVel);
}
Vector3d reactionForce(const World& w) { return w.obstacles[0].reactionForce; }
Vector3d reactionTorque(const World& w) { return w.obstacles[0].reactionTorque; }
struct SphereSpec {
    double radius, young, ktRatio, friction, restitution, mass;
    Vector3d pos, vel, angVel;
};
void setSphere(World& w, const SphereSpec& s, int piece) {
    const int32_t id = 7, pairStart[2] = {0, 1}, pairPiece[1] = {piece};
    w.setSpheres(1, &id, &s.radius, &s.young, &s.ktRatio, &s.friction, &s.restitution, &s.mass, pairStart, pairPiece);
    for (int d = 0; d < 3; ++d) {
        w.spheres.pos[d] = s.pos[d];
        w.spheres.vel[d] = s.vel[d];
        w.spheres.angVel[d] = s.angVel[d];
    }
}
Vector3d sphereForce(const World& w) { return Eigen::Map<const Vector3d>(w.spheres.forceTorque.data()); }
Vector3d sphereTorque(const World& w) { return Eigen::Map<const Vector3d>(w.spheres.forceTorque.data() + 3); }
long ppCount(const World& w) { return w.report().count("pointPolygon"); }
long eeCount(const World& w) { return w.report().count("edgeEdge"); }
long wallCount(const World& w) { return w.report().count("wall"); }
long sphereCount(const World& w) { return w.report().count("sphere"); }
void useRegularized(World& w, double vReg) {
    w.settings.frictionModel = FrictionModel::Regularized;
    w.settings.frictionRegVelocity = vReg;
}

// =====================================================================
// The law, written out from the docs (independent of pkg/contact).
// =====================================================================

constexpr double kDt = 1e-6;
constexpr double kTol = 1e-12;  // relative to the scale of the checked force

double xiOf(double e) {  // doc/formulation.md §4
    if (e >= 1) return 0;
    const double l = std::log(e);
    return -l / std::sqrt(M_PI * M_PI + l * l);
}
double mindlin(double nu) { return 2 * (1 - nu) / (2 - nu); }
double frictPhys(double ea, double eb) { return 2 * ea * eb / (ea + eb); }  // ea = E_a r_a

struct Law {
    double kn, cn, kt, ct, mu;
};

// First step of a new contact (no tangential history): spring-dashpot with
// no tension, tangential spring v_t dt plus dashpot, Coulomb cap along the
// trial force.
Vector3d springLaw(const Law& L, const Vector3d& n, double delta, const Vector3d& vRel, double dt, bool friction) {
    const double vn = vRel.dot(n);
    const double fn = std::max(0.0, L.kn * delta - L.cn * vn);
    Vector3d f = fn * n;
    if (friction) {
        const Vector3d vt = vRel - vn * n;
        Vector3d ft = -L.kt * (vt * dt) - L.ct * vt;
        if (ft.norm() > L.mu * fn) ft *= L.mu * fn / ft.norm();
        f += ft;
    }
    return f;
}

// Whether the first step's trial tangential force exceeds mu Fn (the
// sliding branch): each friction test below runs one stuck and one sliding
// case, and checks that it did.
bool slides(const Law& L, const Vector3d& n, double delta, const Vector3d& vRel, double dt) {
    const double vn = vRel.dot(n);
    const Vector3d vt = vRel - vn * n;
    return (L.kt * vt * dt + L.ct * vt).norm() > L.mu * std::max(0.0, L.kn * delta - L.cn * vn);
}

// Regularised friction, first step of a new contact (doc/contacts.md §5,
// "Regularised friction, implicit": v_free = v_t without history).
Vector3d regularizedLaw(const Law& L, const Vector3d& n, double delta, const Vector3d& vRel, double dt, double vReg,
                        double mEff) {
    const double vn = vRel.dot(n);
    const double fn = std::max(0.0, L.kn * delta - L.cn * vn);
    const Vector3d vt = vRel - vn * n;
    const double c = L.mu * fn / vReg;
    const double f = std::min(L.mu * fn, c * vt.norm() / (1 + c * dt / mEff));
    return fn * n - f * vt / vt.norm();
}

// Area weights of the four nodes of a lone tetrahedron (doc/contacts.md,
// "Area weights"): A_i = a third of the faces around node i, i.e. of every
// face but the one opposite; over the mean share (total area / 4).
std::array<double, 4> tetWeights(const Tet& x) {
    std::array<double, 4> opp{};
    double total = 0;
    for (int i = 0; i < 4; ++i) {
        const Vector3d& a = x[(i + 1) % 4];
        const Vector3d& b = x[(i + 2) % 4];
        const Vector3d& c = x[(i + 3) % 4];
        opp[i] = 0.5 * (b - a).cross(c - a).norm();
        total += opp[i];
    }
    std::array<double, 4> w{};
    for (int i = 0; i < 4; ++i) w[i] = (total - opp[i]) / 3.0 / (total / 4.0);
    return w;
}
double tetVolume(const Tet& x) { return std::abs((x[1] - x[0]).dot((x[2] - x[0]).cross(x[3] - x[0]))) / 6.0; }

// Barycentric weights of a point p in the plane of triangle (a, b, c), as the
// seed's area ratios (eq. 5).
std::array<double, 3> areaRatios(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
    const Vector3d n = (b - a).cross(c - a);
    const double A = n.squaredNorm();
    return {(b - p).cross(c - p).dot(n) / A, (c - p).cross(a - p).dot(n) / A, (a - p).cross(b - p).dot(n) / A};
}

// A tetrahedron with its apex at p and the other three nodes at distance
// L beyond it along n (spread across n): only the apex can touch what lies
// on the -n side.
Tet apexTet(const Vector3d& p, const Vector3d& n, double L = 1.0) {
    const Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    return {p, p + L * (n + 0.5 * e1), p + L * (n - 0.25 * e1 + 0.433 * e2), p + L * (n - 0.25 * e1 - 0.433 * e2)};
}

void expectVec(const Vector3d& got, const Vector3d& want, double scale, const std::string& what,
               double tol = kTol) {
    for (int d = 0; d < 3; ++d)
        EXPECT_NEAR(got[d], want[d], tol * scale)
            << what << " [" << d << "]: got (" << got.transpose() << "), want (" << want.transpose() << ")";
}

// Materials (dyadic radii: overlaps exact).  Viscosity 0: the element forces
// of a rigidly moving, undeformed tet are then rounding only.
Material matA() {
    Material m;
    m.young = 1e6;
    m.poisson = 0.3;
    m.density = 1000;
    m.viscosity = 0;
    m.frictionPiece = 0.4;
    m.frictionWall = 0.5;
    m.radius = 1.0 / 16;
    m.restitution = 0.5;
    return m;
}
Material matB() {
    Material m;
    m.young = 3e6;
    m.poisson = 0.2;
    m.density = 2000;
    m.viscosity = 0;
    m.frictionPiece = 0.3;
    m.frictionWall = 0.6;
    m.radius = 3.0 / 32;
    m.restitution = 0.7;
    return m;
}

constexpr double kDelta = 1.0 / 64;  // overlap of every contact below

// =====================================================================
// 1. Node - obstacle (wall, box, facet)
// =====================================================================

// One node of a tet touching an obstacle at overlap kDelta along normal n,
// contact point pc; the obstacle at pos (torque reference).
struct ObstacleCase {
    World w;
    Tet x;
    int piece = 0;
    double wApex = 0, mNode = 0;
};

void buildObstacleCase(ObstacleCase& c, const Obstacle& o, const Vector3d& pc, const Vector3d& n, const Vector3d& pos,
                       const Eigen::Quaterniond& ori, const Vector3d& oVel = Vector3d::Zero(),
                       const Vector3d& oAngVel = Vector3d::Zero()) {
    const Material m = matA();
    c.x = apexTet(pc + (m.radius - kDelta) * n, n);
    c.piece = addTetPiece(c.w, c.x, c.w.addMaterial(m));
    c.wApex = tetWeights(c.x)[0];
    c.mNode = m.density * tetVolume(c.x) / 4;
    setObstacle(c.w, o, pos, ori, oVel, oAngVel);
}

// Checks the apex force, the other nodes' (none) and the obstacle's reaction
// force and torque about its position, for an expected force f on the node
// applied at the contact point pc.
void checkObstacle(const ObstacleCase& c, const Vector3d& f, const Vector3d& pc, const Vector3d& pos,
                   const std::string& what) {
    const double F = f.norm();
    ASSERT_GT(F, 0) << what;
    EXPECT_EQ(wallCount(c.w), 1) << what;
    expectVec(forceOn(c.w, nodeId(c.w, c.piece, 0)), f, F, what + ": force on the node");
    for (int k = 1; k < 4; ++k) expectVec(forceOn(c.w, nodeId(c.w, c.piece, k)), Vector3d::Zero(), F, what + ": other node");
    expectVec(reactionForce(c.w), -f, F, what + ": reaction force");
    expectVec(reactionTorque(c.w), (pc - pos).cross(-f), F * (pc - pos).norm(), what + ": reaction torque");
}

Obstacle wallZ(double sense) {
    Obstacle o;
    o.kind = ObstacleKind::Wall;
    o.bodyId = 3;
    o.axis = 2;
    o.sense = static_cast<int>(sense);
    return o;
}

const Vector3d kWallPos(0.75, -0.5, -0.125);  // the plane z = -0.125; x, y: the torque reference
const Vector3d kWallPoint(0.25, 0.5, -0.125);  // contact point of the node below

Law wallLaw(const ObstacleCase& c, double obstacleYoung = 0, double mu = -1) {
    const Material m = matA();
    const double kn0 = obstacleYoung > 0 ? frictPhys(m.young * m.radius, obstacleYoung * m.radius)
                                         : 2 * m.young * m.radius;
    const double kn = c.wApex * kn0, kt = kn * mindlin(m.poisson), xi = xiOf(m.restitution);
    return {kn, 2 * xi * std::sqrt(kn * c.mNode), kt, 2 * xi * std::sqrt(kt * c.mNode), mu >= 0 ? std::min(mu, m.frictionWall) : m.frictionWall};
}

TEST(ReferenceForces, WallStaticNormalSpring) {
    for (double sense : {1.0, 0.0}) {  // one-sided and two-sided wall
        ObstacleCase c;
        buildObstacleCase(c, wallZ(sense), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity());
        c.w.step(kDt);
        const Law L = wallLaw(c);
        // kn = w 2 E r, not the unweighted spring: the weight is not 1 here.
        ASSERT_GT(std::abs(c.wApex - 1), 0.05);
        checkObstacle(c, L.kn * kDelta * Vector3d::UnitZ(), kWallPoint, kWallPos,
                      "wall sense " + std::to_string(static_cast<int>(sense)));
    }
}

// Normal dashpot: the piece approaching at 0.2 m/s and the wall rising at
// 0.1 m/s: closing speed 0.3; then separating so fast that the dashpot would
// pull: no force at all.
TEST(ReferenceForces, WallNormalDashpotAndNoTension) {
    {
        ObstacleCase c;
        buildObstacleCase(c, wallZ(1), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity(),
                          Vector3d(0, 0, 0.1));
        setPieceVelocity(c.w, c.piece, Vector3d(0, 0, -0.2));
        c.w.settings.frictionOn = false;
        c.w.step(kDt);
        const Law L = wallLaw(c);
        checkObstacle(c, (L.kn * kDelta + L.cn * 0.3) * Vector3d::UnitZ(), kWallPoint, kWallPos, "approaching");
    }
    {
        ObstacleCase c;
        buildObstacleCase(c, wallZ(1), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity());
        const Law L = wallLaw(c);
        const double vOut = 2 * L.kn * kDelta / L.cn;  // kn delta - cn v < 0
        setPieceVelocity(c.w, c.piece, Vector3d(0, 0, vOut));
        c.w.step(kDt);
        EXPECT_EQ(wallCount(c.w), 1);
        expectVec(forceOn(c.w, nodeId(c.w, c.piece, 0)), Vector3d::Zero(), L.kn * kDelta, "separating: no tension");
        expectVec(reactionForce(c.w), Vector3d::Zero(), L.kn * kDelta, "separating: no reaction");
    }
}

// Tangential spring, first step: stuck (|Ft| < mu Fn: Ft = -kt vt dt - ct vt)
// and sliding (Ft = mu Fn against the trial force).
TEST(ReferenceForces, WallSpringFrictionStuckAndSliding) {
    for (double speed : {0.1, 3.0}) {
        ObstacleCase c;
        buildObstacleCase(c, wallZ(1), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity());
        const Vector3d v = speed * Vector3d(0.6, -0.8, 0);
        setPieceVelocity(c.w, c.piece, v);
        c.w.step(kDt);
        const Law L = wallLaw(c);
        const Vector3d f = springLaw(L, Vector3d::UnitZ(), kDelta, v, kDt, true);
        const Vector3d trial = -L.kt * v * kDt - L.ct * v;
        const bool slipping = trial.norm() > L.mu * L.kn * kDelta;
        EXPECT_EQ(slipping, speed > 1) << "the two cases must test both branches";
        checkObstacle(c, f, kWallPoint, kWallPos, slipping ? "sliding" : "stuck");
        if (slipping) {
            EXPECT_NEAR(Vector3d(f.x(), f.y(), 0).norm(), L.mu * L.kn * kDelta, 1e-12 * f.norm());
        }
    }
}

// Velocity of a body's material point now at arm r from its spin centre,
// spinning at w, at the time level of the nodes' velocities (the step just
// made): the arm half a step back, r - (w x r) dt/2 (Obstacle::velocityAt).
Vector3d spinVelocity(const Vector3d& w, const Vector3d& r, double dt) { return w.cross(r - 0.5 * dt * w.cross(r)); }

// A spinning wall (angular velocity about z through its position): the
// relative velocity at the contact point is -(w x (pc - pos)), the arm taken
// half a step back.
TEST(ReferenceForces, WallSpinningDrivesFriction) {
    const Vector3d omega(0, 0, 0.4);
    ObstacleCase c;
    buildObstacleCase(c, wallZ(1), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity(),
                      Vector3d::Zero(), omega);
    c.w.step(kDt);
    const Vector3d vRel = -spinVelocity(omega, kWallPoint - kWallPos, kDt);
    const Vector3d f = springLaw(wallLaw(c), Vector3d::UnitZ(), kDelta, vRel, kDt, true);
    ASSERT_GT(Vector3d(f.x(), f.y(), 0).norm(), 1e-3 * f.norm());
    checkObstacle(c, f, kWallPoint, kWallPos, "spinning wall");
}

// Regularised law, first step: below vReg + mu Fn dt/m the implicit drag
// c_eff |vt|, above it mu Fn.
TEST(ReferenceForces, WallRegularizedFriction) {
    const double vReg = 1e-3;
    for (double speed : {2e-4, 0.3}) {
        ObstacleCase c;
        buildObstacleCase(c, wallZ(1), kWallPoint, Vector3d::UnitZ(), kWallPos, Eigen::Quaterniond::Identity());
        useRegularized(c.w, vReg);
        const Vector3d v = speed * Vector3d(0.6, -0.8, 0);
        setPieceVelocity(c.w, c.piece, v);
        c.w.step(kDt);
        const Law L = wallLaw(c);
        const Vector3d f = regularizedLaw(L, Vector3d::UnitZ(), kDelta, v, kDt, vReg, c.mNode);
        const double ft = Vector3d(f.x(), f.y(), 0).norm(), cap = L.mu * L.kn * kDelta;
        if (speed < vReg) {
            EXPECT_LT(ft, 0.5 * cap) << "viscous branch";
        } else {
            EXPECT_NEAR(ft, cap, 1e-12 * cap) << "sliding branch";
        }
        checkObstacle(c, f, kWallPoint, kWallPos, speed < vReg ? "regularised, viscous" : "regularised, sliding");
    }
}

// Box: rotated, elastic (kn by FrictPhys with the box's Young modulus), its
// own friction coefficient; the node in the region of the box's edge
// (+x, +y): normal from the closest point on that edge.
const Vector3d kBoxPos(0.3, -0.2, 0.1);
Eigen::Quaterniond boxOri() { return Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3d(1, 2, 3).normalized())); }
Obstacle box() {
    Obstacle o;
    o.kind = ObstacleKind::Box;
    o.bodyId = 5;
    o.halfExtents = Vector3d(0.5, 0.25, 0.125);
    o.young = 4e6;
    o.friction = 0.25;
    return o;
}

TEST(ReferenceForces, BoxStaticFaceAndEdge) {
    const Eigen::Matrix3d R = boxOri().toRotationMatrix();
    struct Where {
        Vector3d pLocal, nLocal;
        const char* name;
    };
    for (const Where& h : {Where{Vector3d(0.5, 0.1, 0.05), Vector3d(1, 0, 0), "face"},
                           Where{Vector3d(0.5, 0.25, 0.05), Vector3d(0.6, 0.8, 0), "edge"},
                           Where{Vector3d(-0.5, 0.25, -0.125), Vector3d(-2, 2, -1) / 3, "corner"}}) {
        ObstacleCase c;
        const Vector3d pc = kBoxPos + R * h.pLocal, n = R * h.nLocal;
        buildObstacleCase(c, box(), pc, n, kBoxPos, boxOri());
        c.w.step(kDt);
        const Law L = wallLaw(c, 4e6);
        checkObstacle(c, L.kn * kDelta * n, pc, kBoxPos, std::string("box ") + h.name);
    }
}

// A moving, spinning box against a still node: normal dashpot and friction
// (the box's own coefficient) from the box's velocity at the contact point.
TEST(ReferenceForces, BoxMovingDashpotAndFriction) {
    const Eigen::Matrix3d R = boxOri().toRotationMatrix();
    const Vector3d pc = kBoxPos + R * Vector3d(0.5, 0.1, 0.05), n = R * Vector3d(1, 0, 0);
    const Vector3d vBox = Vector3d(0.05, -0.02, 0.03) + 0.1 * n, wBox(0.2, -0.1, 0.3);
    ObstacleCase c;
    buildObstacleCase(c, box(), pc, n, kBoxPos, boxOri(), vBox, wBox);
    c.w.step(kDt);
    const Vector3d vRel = -(vBox + spinVelocity(wBox, pc - kBoxPos, kDt));
    const Law L = wallLaw(c, 4e6, 0.25);
    const Vector3d f = springLaw(L, n, kDelta, vRel, kDt, true);
    ASSERT_GT(std::abs(vRel.dot(n)), 0.01);  // the dashpot acts
    checkObstacle(c, f, pc, kBoxPos, "moving box");
}

// Facet: a rotated rigid triangle; the node above and below its interior
// (two-sided) and in the region of an edge.
const Vector3d kFacetPos(0.1, 0.2, -0.3);
Eigen::Quaterniond facetOri() { return Eigen::Quaterniond(Eigen::AngleAxisd(-0.7, Vector3d(2, -1, 1).normalized())); }
Obstacle facet() {
    Obstacle o;
    o.kind = ObstacleKind::Facet;
    o.bodyId = 9;
    o.localVerts[0] = Vector3d(0, 0, 0);
    o.localVerts[1] = Vector3d(1, 0, 0);
    o.localVerts[2] = Vector3d(0, 1, 0);
    return o;
}

TEST(ReferenceForces, FacetStaticInteriorBothSidesAndEdge) {
    const Eigen::Matrix3d R = facetOri().toRotationMatrix();
    const double phi = 0.7;  // elevation of the edge-region node above the facet's plane
    const Vector3d outEdge = Vector3d(1, 1, 0).normalized();
    struct Where {
        Vector3d pLocal, nLocal;
        const char* name;
    };
    for (const Where& h : {Where{Vector3d(0.2, 0.3, 0), Vector3d(0, 0, 1), "above"},
                           Where{Vector3d(0.2, 0.3, 0), Vector3d(0, 0, -1), "below"},
                           Where{Vector3d(0.3, 0.7, 0), std::cos(phi) * outEdge + std::sin(phi) * Vector3d::UnitZ(),
                                 "edge"}}) {
        ObstacleCase c;
        const Vector3d pc = kFacetPos + R * h.pLocal, n = R * h.nLocal;
        buildObstacleCase(c, facet(), pc, n, kFacetPos, facetOri());
        c.w.step(kDt);
        checkObstacle(c, wallLaw(c).kn * kDelta * n, pc, kFacetPos, std::string("facet ") + h.name);
    }
}

// =====================================================================
// 2. Point - polygon between two pieces
// =====================================================================

// Piece B: a tet whose top face (b0, b1, b2) is the plane z = 0, outward +z.
const Tet kB = {Vector3d(-1, -1, 0), Vector3d(2, -1, 0), Vector3d(-1, 2, 0), Vector3d(0, 0, -1)};

struct PairCase {
    World w;
    Tet xa, xb;
    int pa = 0, pb = 0;
    std::array<double, 4> wa{}, wb{};
    double ma = 0, mb = 0;  // node masses
};

// Piece A: an apex tet whose apex is at reach - kDelta from the point c of
// B's surface, along n.
void buildPair(PairCase& c, const Vector3d& pc, const Vector3d& n) {
    const Material A = matA(), B = matB();
    c.xb = kB;
    c.xa = apexTet(pc + (A.radius + B.radius - kDelta) * n, n);
    c.pb = addTetPiece(c.w, c.xb, c.w.addMaterial(B));
    c.pa = addTetPiece(c.w, c.xa, c.w.addMaterial(A));
    c.wa = tetWeights(c.xa);
    c.wb = tetWeights(c.xb);
    c.ma = A.density * tetVolume(c.xa) / 4;
    c.mb = B.density * tetVolume(c.xb) / 4;
}

// The pair law of A's node against B's surface (or B's node against A's:
// symmetric), weighted by the query node's weight wq; m the reduced mass.
Law pairLaw(double wq, double m) {
    const Material A = matA(), B = matB();
    const double kn = wq * frictPhys(A.young * A.radius, B.young * B.radius);
    const double kt = kn * 0.5 * (mindlin(A.poisson) + mindlin(B.poisson));  // the mean of the two ratios
    const double xi = xiOf(std::sqrt(A.restitution * B.restitution));
    return {kn, 2 * xi * std::sqrt(kn * m), kt, 2 * xi * std::sqrt(kt * m), std::min(A.frictionPiece, B.frictionPiece)};
}

// Expected node forces: fa on A's apex, the rest of A's nodes nothing, B's
// nodes fb[k].  Checks each, the sums (Newton's third law) and, when
// torqueFree, the torque about the origin.
void checkPair(const PairCase& c, const Vector3d& fa, const std::array<Vector3d, 4>& fb, const std::string& what,
               bool torqueFree = true) {
    const double F = fa.norm();
    Vector3d sum = Vector3d::Zero(), torque = Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
        const int32_t na = nodeId(c.w, c.pa, k), nb = nodeId(c.w, c.pb, k);
        const Vector3d ga = forceOn(c.w, na), gb = forceOn(c.w, nb);
        expectVec(ga, k == 0 ? fa : Vector3d::Zero(), F, what + ": A node " + std::to_string(k));
        expectVec(gb, fb[k], F, what + ": B node " + std::to_string(k));
        sum += ga + gb;
        torque += c.xa[k].cross(ga) + c.xb[k].cross(gb);
    }
    expectVec(sum, Vector3d::Zero(), F, what + ": total force");
    if (torqueFree) expectVec(torque, Vector3d::Zero(), 3 * F, what + ": total torque about the origin");
}

// A's apex above the interior of B's top face: the force on the apex along
// +z, its opposite split over the face's nodes by the area ratios.
TEST(ReferenceForces, PointPolygonFaceStatic) {
    const Vector3d pc(0.2, -0.5, 0);
    PairCase c;
    buildPair(c, pc, Vector3d::UnitZ());
    c.w.step(kDt);
    EXPECT_EQ(ppCount(c.w), 1);
    EXPECT_EQ(eeCount(c.w), 0);
    const Vector3d f = pairLaw(c.wa[0], 1.0).kn * kDelta * Vector3d::UnitZ();
    const auto wk = areaRatios(pc, kB[0], kB[1], kB[2]);
    checkPair(c, f, {-wk[0] * f, -wk[1] * f, -wk[2] * f, Vector3d::Zero()}, "face, static");
}

// The same with A moving rigidly: dashpot on the reduced mass m_A m_T/(m_A +
// m_T) (m_T = sum w_k m_k), friction min(mu_A, mu_B); spring and regularised.
TEST(ReferenceForces, PointPolygonFaceDashpotAndFriction) {
    const Vector3d pc(0.2, -0.5, 0), n = Vector3d::UnitZ();
    const auto wk = areaRatios(pc, kB[0], kB[1], kB[2]);
    for (int regularized = 0; regularized < 2; ++regularized)
        for (const Vector3d& v : {Vector3d(0.02, -0.01, -0.15), Vector3d(3, 1.5, -0.15), Vector3d(2e-4, 1e-4, -0.15)}) {
            if (!regularized && v.x() < 1e-3) continue;  // the slow case is for the regularised law
            PairCase c;
            buildPair(c, pc, n);
            if (regularized) useRegularized(c.w, 1e-3);
            setPieceVelocity(c.w, c.pa, v);
            c.w.step(kDt);
            EXPECT_EQ(ppCount(c.w), 1);
            const double mT = (wk[0] + wk[1] + wk[2]) * c.mb;
            const double m = c.ma * mT / (c.ma + mT);
            const Law L = pairLaw(c.wa[0], m);
            const Vector3d f = regularized ? regularizedLaw(L, n, kDelta, v, kDt, 1e-3, m)
                                           : springLaw(L, n, kDelta, v, kDt, true);
            if (!regularized) {
                EXPECT_EQ(slides(L, n, kDelta, v, kDt), v.x() > 1) << "stuck and sliding cases";
            }
            const std::string what = std::string(regularized ? "regularised" : "spring") + ", v = (" +
                                     std::to_string(v.x()) + ", " + std::to_string(v.y()) + ")";
            checkPair(c, f, {-wk[0] * f, -wk[1] * f, -wk[2] * f, Vector3d::Zero()}, what, false);
        }
}

// A's apex beside the edge b0-b1 of B's top face (outside both faces at the
// edge, in the edge's region): one contact, normal from the edge point, the
// force split linearly over the edge's two nodes.
TEST(ReferenceForces, PointPolygonEdgeRegionStatic) {
    const Vector3d pc(0.2, -1, 0);  // 0.4 of the way from b0 to b1
    const double phi = 0.6;
    const Vector3d n(0, -std::cos(phi), std::sin(phi));
    PairCase c;
    buildPair(c, pc, n);
    c.w.step(kDt);
    EXPECT_EQ(ppCount(c.w), 1);
    EXPECT_EQ(eeCount(c.w), 0);
    const Vector3d f = pairLaw(c.wa[0], 1.0).kn * kDelta * n;
    const double s = (pc - kB[0]).norm() / (kB[1] - kB[0]).norm();
    checkPair(c, f, {-(1 - s) * f, -s * f, Vector3d::Zero(), Vector3d::Zero()}, "edge region");
}

// A's apex beyond B's corner b1, along the mean of its faces' normals: the
// corner region.  Both nodes are surface nodes facing each other, so the
// touch is seen both ways (doc/contacts.md §3): A's apex against B's corner
// with A's weight, and B's corner node against A's apex with B's weight.
TEST(ReferenceForces, PointPolygonCornerRegionBothWays) {
    Vector3d n = Vector3d::Zero();
    const Vector3d inside = (kB[0] + kB[1] + kB[2] + kB[3]) / 4;
    for (int skip : {0, 2, 3}) {  // the three faces around b1: each omits one of the other nodes
        std::vector<Vector3d> f;
        for (int k = 0; k < 4; ++k)
            if (k != skip) f.push_back(kB[k]);
        Vector3d nf = (f[1] - f[0]).cross(f[2] - f[0]).normalized();
        if (nf.dot(f[0] - inside) < 0) nf = -nf;
        n += nf;
    }
    n.normalize();
    PairCase c;
    buildPair(c, kB[1], n);
    c.w.step(kDt);
    EXPECT_EQ(ppCount(c.w), 2);
    EXPECT_EQ(eeCount(c.w), 0);
    const Vector3d f = (pairLaw(c.wa[0], 1.0).kn + pairLaw(c.wb[1], 1.0).kn) * kDelta * n;
    checkPair(c, f, {Vector3d::Zero(), -f, Vector3d::Zero(), Vector3d::Zero()}, "corner region");
}

// =====================================================================
// 3. Edge - edge
// =====================================================================

// B's ridge along x (z = 0) and A's bottom edge along y (z = gap) crossing
// at right angles at (0.25, 0): closest points at 0.625 of B's ridge and
// 0.25 of A's edge; every node more than a reach from the other piece's
// faces, so only the edge-edge contact acts.
struct EdgeCase {
    World w;
    Tet xa, xb;
    int pa = 0, pb = 0;
    double ma = 0, mb = 0;
    double aw = 0;                  // the contact's area weight
    std::array<double, 4> sa{}, sb{};  // each node's share of the force (its edge's linear split)
};

void buildEdgeCase(EdgeCase& c) {
    const Material A = matA(), B = matB();
    const double gap = A.radius + B.radius - kDelta;
    // (Irregular: a symmetric tet has all faces equal and every weight 1.)
    c.xb = {Vector3d(-1, 0, 0), Vector3d(1, 0, 0), Vector3d(0, -1, -1), Vector3d(0.6, 1.5, -2)};
    c.xa = {Vector3d(0.25, -0.5, gap), Vector3d(0.25, 1.5, gap), Vector3d(-0.75, 0.3, gap + 1),
            Vector3d(1.25, 1.2, gap + 2)};
    c.pa = addTetPiece(c.w, c.xa, c.w.addMaterial(A));
    c.pb = addTetPiece(c.w, c.xb, c.w.addMaterial(B));
    const Vector3d ca(0.25, 0, gap), cb(0.25, 0, 0);  // the closest points
    // Linear split along each edge: a node's share is 1 - its distance to
    // the crossing over the edge length.
    c.sa = {1 - (c.xa[0] - ca).norm() / 2, 1 - (c.xa[1] - ca).norm() / 2, 0, 0};
    c.sb = {1 - (c.xb[0] - cb).norm() / 2, 1 - (c.xb[1] - cb).norm() / 2, 0, 0};
    const auto wa = tetWeights(c.xa), wb = tetWeights(c.xb);
    c.aw = 0.5 * (c.sa[0] * wa[0] + c.sa[1] * wa[1] + c.sb[0] * wb[0] + c.sb[1] * wb[1]);
    c.ma = A.density * tetVolume(c.xa) / 4;
    c.mb = B.density * tetVolume(c.xb) / 4;
}

// The contact's area weight as a function of the four edge ends: the closest
// points of the two (infinite) lines, the nodes' weights interpolated there.
double edgeAreaWeight(const EdgeCase& c, const std::array<Vector3d, 4>& x) {
    const auto wa = tetWeights(c.xa), wb = tetWeights(c.xb);
    const Vector3d e1 = x[1] - x[0], e2 = x[3] - x[2], r = x[0] - x[2];
    // (r + s e1 - t e2) . e1 = 0, (r + s e1 - t e2) . e2 = 0
    const double a = e1.dot(e1), b = e1.dot(e2), e = e2.dot(e2), d = a * e - b * b;
    const double s = (b * e2.dot(r) - e * e1.dot(r)) / d, t = (a * e2.dot(r) - b * e1.dot(r)) / d;
    return 0.5 * ((1 - s) * wa[0] + s * wa[1] + (1 - t) * wb[0] + t * wb[1]);
}

// The force's part from the varying weight (doc/contacts.md §4, "Conservative
// weights"): -1/2 kn delta^2 grad(aw) on the edges' ends, by central
// differences.  out: A's ends 0, 1 then B's ends 0, 1.
std::array<Vector3d, 4> weightForce(const EdgeCase& c, double knUnweighted) {
    std::array<Vector3d, 4> x = {c.xa[0], c.xa[1], c.xb[0], c.xb[1]}, out;
    const double h = 1e-6;
    for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) {
            auto xp = x, xm = x;
            xp[k][d] += h;
            xm[k][d] -= h;
            out[k][d] = -0.5 * knUnweighted * kDelta * kDelta * (edgeAreaWeight(c, xp) - edgeAreaWeight(c, xm)) / (2 * h);
        }
    return out;
}

void checkEdgeCase(const EdgeCase& c, const Vector3d& f, const std::string& what, bool torqueFree,
                   const std::array<Vector3d, 4>& fw) {
    EXPECT_EQ(eeCount(c.w), 1) << what;
    EXPECT_EQ(ppCount(c.w), 0) << what;
    const double F = f.norm();
    Vector3d sum = Vector3d::Zero(), torque = Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
        const Vector3d ga = forceOn(c.w, nodeId(c.w, c.pa, k)), gb = forceOn(c.w, nodeId(c.w, c.pb, k));
        const Vector3d wA = k < 2 ? fw[k] : Vector3d::Zero(), wB = k < 2 ? fw[2 + k] : Vector3d::Zero();
        expectVec(ga, c.sa[k] * f + wA, F, what + ": A node " + std::to_string(k));
        expectVec(gb, -c.sb[k] * f + wB, F, what + ": B node " + std::to_string(k));
        sum += ga + gb;
        torque += c.xa[k].cross(ga) + c.xb[k].cross(gb);
    }
    expectVec(sum, Vector3d::Zero(), F, what + ": total force");
    if (torqueFree) expectVec(torque, Vector3d::Zero(), 2 * F, what + ": total torque about the origin");
}

TEST(ReferenceForces, EdgeEdgeStatic) {
    EdgeCase c;
    buildEdgeCase(c);
    c.w.step(kDt);
    const Law L = pairLaw(c.aw, 1.0);  // right angle, far from the ends: fade weights 1
    ASSERT_GT(std::abs(c.aw - 1), 0.01) << "the weight must matter";
    checkEdgeCase(c, L.kn * kDelta * Vector3d::UnitZ(), "edge-edge static", true, weightForce(c, L.kn / c.aw));
}

// A moving rigidly down and sideways: dashpot and friction on the reduced
// mass of the two crossing points (node masses interpolated along the edges).
TEST(ReferenceForces, EdgeEdgeDashpotAndFriction) {
    for (const Vector3d& v : {Vector3d(0.03, -0.02, -0.2), Vector3d(3, -2, -0.2)}) {
        EdgeCase c;
        buildEdgeCase(c);
        setPieceVelocity(c.w, c.pa, v);
        c.w.step(kDt);
        const double m1 = c.ma, m2 = c.mb;  // equal node masses along each edge
        const Law L = pairLaw(c.aw, m1 * m2 / (m1 + m2));
        EXPECT_EQ(slides(L, Vector3d::UnitZ(), kDelta, v, kDt), v.x() > 1) << "stuck and sliding cases";
        checkEdgeCase(c, springLaw(L, Vector3d::UnitZ(), kDelta, v, kDt, true),
                      v.x() > 1 ? "edge-edge sliding" : "edge-edge stuck", false, weightForce(c, L.kn / c.aw));
    }
}

// =====================================================================
// 4. YADE sphere - triangle
// =====================================================================

// A sphere over the interior of B's top face at overlap kDelta with the
// face's skin (reach R + r_B).  Unweighted stiffness (doc/contacts.md, "Area
// weights"); kt/kn the mean of the sphere's ratio and Mindlin's; restitution
// QDEM's for a FrictMat (restitution <= 0), the geometric mean otherwise.
struct SphereCase {
    World w;
    int pb = 0;
    double mb = 0;
    SphereSpec s;
};

void buildSphereCase(SphereCase& c, const Vector3d& pc, const Vector3d& vel, const Vector3d& angVel,
                     double restitution) {
    const Material B = matB();
    c.pb = addTetPiece(c.w, kB, c.w.addMaterial(B));
    c.mb = B.density * tetVolume(kB) / 4;
    c.s = SphereSpec{0.2, 5e6, 0.5, 0.6, restitution, 3.0, Vector3d::Zero(), vel, angVel};
    c.s.pos = pc + (c.s.radius + B.radius - kDelta) * Vector3d::UnitZ();
    setSphere(c.w, c.s, c.pb);
}

Law sphereLaw(const SphereCase& c, double mT) {
    const Material B = matB();
    const double kn = frictPhys(c.s.young * c.s.radius, B.young * B.radius);
    const double kt = kn * 0.5 * (c.s.ktRatio + mindlin(B.poisson));
    const double e = c.s.restitution > 0 ? std::sqrt(c.s.restitution * B.restitution) : B.restitution;
    const double m = c.s.mass * mT / (c.s.mass + mT), xi = xiOf(e);
    return {kn, 2 * xi * std::sqrt(kn * m), kt, 2 * xi * std::sqrt(kt * m), std::min(c.s.friction, B.frictionPiece)};
}

void checkSphere(const SphereCase& c, const Vector3d& f, const Vector3d& torque, const Vector3d& pc,
                 const std::string& what) {
    EXPECT_EQ(sphereCount(c.w), 1) << what;
    const double F = f.norm();
    expectVec(sphereForce(c.w), f, F, what + ": sphere force");
    expectVec(sphereTorque(c.w), torque, F * c.s.radius, what + ": sphere torque");
    const auto wk = areaRatios(pc, kB[0], kB[1], kB[2]);
    for (int k = 0; k < 4; ++k)
        expectVec(forceOn(c.w, nodeId(c.w, c.pb, k)), k < 3 ? Vector3d(-wk[k] * f) : Vector3d::Zero(), F,
                  what + ": node " + std::to_string(k));
}

TEST(ReferenceForces, SphereTriangleStatic) {
    const Vector3d pc(0.2, -0.5, 0);
    SphereCase c;
    buildSphereCase(c, pc, Vector3d::Zero(), Vector3d::Zero(), -1);
    c.w.step(kDt);
    // A normal force through the centre: no torque.
    checkSphere(c, sphereLaw(c, c.mb).kn * kDelta * Vector3d::UnitZ(), Vector3d::Zero(), pc, "sphere static");
}

// Sliding and spinning: relative velocity v + w x a - v_T at the lever arm
// a = -(R - delta/2) n (YADE's contact point; in w x a taken half a step
// back, spinVelocity), the torque a x F.
TEST(ReferenceForces, SphereTriangleDashpotFrictionTorque) {
    const Vector3d pc(0.2, -0.5, 0), n = Vector3d::UnitZ();
    for (const Vector3d& v : {Vector3d(0.01, -0.02, -0.05), Vector3d(6, 4, -0.05)}) {
        const Vector3d omega(1, 2, -3);
        SphereCase c;
        buildSphereCase(c, pc, v, omega, 0.4);  // a ViscElMat sphere: its restitution counts
        c.w.step(kDt);
        const Vector3d arm = -(c.s.radius - 0.5 * kDelta) * n;
        const Vector3d vRel = v + spinVelocity(omega, arm, kDt);
        const Law L = sphereLaw(c, c.mb);
        EXPECT_EQ(slides(L, n, kDelta, vRel, kDt), v.x() > 1) << "stuck and sliding cases";
        const Vector3d f = springLaw(L, n, kDelta, vRel, kDt, true);
        checkSphere(c, f, arm.cross(f), pc, "sphere moving, v = (" + std::to_string(v.x()) + ", ...)");
    }
}

}  // namespace
