// Property test of the stable time step: on thousands of sampled states, the
// step the engine accepts is never above the exact largest stable step of the
// linearised update of the small system (doc/formulation.md, "Stable time
// step", where the histogram of their ratio is).
//
// The exact step is found from the amplification matrix of the leapfrog
// update with the dashpots lagged half a step, as every phase and YADE's
// NewtonIntegrator integrate them,
//     v' = v + dt M^-1 (-K x - C v),   x' = x + dt v',
// by its spectral radius (<= 1 + 1e-6) over dt.  K, C and M are assembled
// here from the definitions, not from the stable-step code: element forces by
// central differences of the law's stress (law.piola) and of the Kelvin-Voigt
// stress (viscousStress), contact springs and dashpots from the contact model
// (ContactModel.hpp) on the nodes' masses and area weights.  A softening
// direction (a negative eigenvalue of K: a buckling or inverted element)
// grows at any step, so the step is judged on K's positive part.
//
// Sampled: strained, compressed, sheared and inverted tetrahedra of random
// shapes for both laws, Poisson ratios -0.9 to 0.49, without and with
// viscosity (reported: the largest step checkCurrentDt accepts); pieces of
// 5, 6 and 12 tetrahedra per cell resting on a rigid wall (node contacts,
// normal and tangential springs and dashpots); YADE spheres resting on a
// piece (sphere-triangle contacts with the ball's rotation); both reported by
// stableDt(); a piece resting on another (point-polygon both ways, every
// contact the step finds), reported by stableDt() after a step.  QDEM_STABLE_STEP_JSON=<file> writes every ratio (the
// histogram's data: scripts/doc/stable_step_histogram.py).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "contact/ContactModel.hpp"
#include "contact/Geometry.hpp"
#include "core/Errors.hpp"
#include "element/ElementKernel.hpp"
#include "element/MaterialLaw.hpp"
#include "mesh/BoxMesh.hpp"
#include "phases/PointPolygonKind.hpp"
#include "world/World.hpp"
#include "ExactStableStep.hpp"

using namespace qdem;

namespace {

using namespace exact_step;

// The ratios found, by family, for the histogram (QDEM_STABLE_STEP_JSON).
std::map<std::string, std::vector<double>>& ratios() {
    static std::map<std::string, std::vector<double>> r;
    return r;
}

void record(const std::string& family, double reported, double exact) {
    if (std::isfinite(exact)) ratios()[family].push_back(reported / exact);
    EXPECT_LE(reported, exact * (1 + 1e-6)) << family << ": reported " << reported << " s, exact " << exact << " s";
}

Eigen::Matrix3d randomRotation(std::mt19937_64& g) {
    std::normal_distribution<double> n;
    return Eigen::Quaterniond(n(g), n(g), n(g), n(g)).normalized().toRotationMatrix();
}

// The surface triangle of piece p lying in the plane z = level that holds
// the point (x, y) = at: its nodes and the point's barycentric weights
// (tri[0] = -1: none).
void faceTriangleAt(const World& w, int p, const Eigen::Vector2d& at, double level, int32_t tri[3],
                    Eigen::Vector3d& bary) {
    tri[0] = tri[1] = tri[2] = -1;
    const Surface& surf = w.pieces[p].surface;
    for (std::size_t t = 0; t < surf.nTriangles(); ++t) {
        const int32_t* c = &surf.triangles[3 * t];
        Eigen::Vector2d q[3];
        bool inPlane = true;
        for (int k = 0; k < 3; ++k) {
            q[k] = Eigen::Vector2d(w.pos[3 * c[k]], w.pos[3 * c[k] + 1]);
            inPlane = inPlane && std::fabs(w.pos[3 * c[k] + 2] - level) < 1e-9;
        }
        if (!inPlane) continue;
        const Eigen::Vector2d e1 = q[1] - q[0], e2 = q[2] - q[0], r = at - q[0];
        const double det = e1.x() * e2.y() - e1.y() * e2.x();
        const double b1 = (r.x() * e2.y() - r.y() * e2.x()) / det, b2 = (e1.x() * r.y() - e1.y() * r.x()) / det;
        if (b1 < -1e-12 || b2 < -1e-12 || b1 + b2 > 1 + 1e-12) continue;
        bary = Eigen::Vector3d(1 - b1 - b2, b1, b2);
        for (int k = 0; k < 3; ++k) tri[k] = c[k];
        return;
    }
}

}  // namespace

// Single tetrahedra on strained, compressed, sheared and inverted shapes: the
// largest step checkCurrentDt accepts against the exact one of the element.
TEST(StableStepProperty, StrainedElementsOfEveryLaw) {
    std::mt19937_64 g(20261128);
    std::uniform_real_distribution<double> u(0, 1);
    int states = 0;
    for (int trial = 0; trial < 1200; ++trial) {
        // A random tetrahedron (a perturbed regular one), a sliver now and then.
        TetMesh mesh;
        mesh.nodes = {0, 0, 0, 1, 0, 0, 0.5, 0.866, 0, 0.5, 0.289, 0.816};
        for (double& c : mesh.nodes) c += 0.3 * (u(g) - 0.5);
        if (trial % 10 == 0) mesh.nodes[11] = 0.05 + 0.05 * u(g);  // flat: a sliver
        mesh.tets = {0, 1, 2, 3};
        if (tetSixVolume(mesh, 0) < 0) std::swap(mesh.tets[2], mesh.tets[3]);
        if (std::fabs(tetSixVolume(mesh, 0)) < 1e-3) continue;
        Material m;
        m.young = 1e6;
        m.density = 1000;
        m.poisson = -0.9 + 1.39 * u(g);
        if (trial < 8) m.poisson = trial % 2 ? 0.3 : 0.0;
        m.law = trial % 2 ? MaterialLaw::SaintVenantKirchhoff : MaterialLaw::StableNeoHookean;
        m.viscosity = 0;
        World w;
        w.addPiece(mesh, w.addMaterial(m));
        if (trial % 3 != 0) {
            // Kelvin-Voigt damping ratio beta omega / 2 from 1e-3 to 3 at the top mode.
            const double omega = 2 / w.stableDt().elastic, xi = std::pow(10.0, -3 + 3.5 * u(g));
            m.viscosity = 2 * xi / omega * m.mu();
            w.materials[0].viscosity = m.viscosity;
        }
        // The shape: F = Q1 diag(s) Q2, stretches from log-normal strains, one
        // of them negative for an inverted element; the cases first.
        Eigen::Vector3d s;
        const double sigma = std::vector<double>{0.05, 0.15, 0.3}[trial % 3];
        std::normal_distribution<double> n(0, sigma);
        for (int d = 0; d < 3; ++d) s[d] = std::exp(n(g));
        if (trial % 7 == 0) s *= 0.6;                  // compressed
        if (trial % 11 == 0) s[0] = -0.2 - 0.5 * u(g);  // inverted
        if (trial < 4) s = Eigen::Vector3d::Constant(1.1);
        else if (trial < 8) s = Eigen::Vector3d(-0.5, 1, 1);
        const Mat3 F = trial < 8 ? Mat3(s.asDiagonal()) : Mat3(randomRotation(g) * s.asDiagonal() * randomRotation(g));
        for (std::size_t a = 0; a < w.nNodes(); ++a) {
            const Eigen::Vector3d X(w.refPos[3 * a], w.refPos[3 * a + 1], w.refPos[3 * a + 2]);
            const Eigen::Vector3d x = F * X;
            for (int d = 0; d < 3; ++d) w.pos[3 * a + d] = x[d];
        }
        // Reported: the largest dt the check accepts (it is monotone in dt).
        const double ref = w.stableDt().combined;
        auto accepts = [&](double dt) {
            try {
                w.checkCurrentDt(dt);
                return true;
            } catch (const StabilityError&) {
                return false;
            }
        };
        double lo = 0, hi = 4 * ref;
        // (Compressed far enough, an element softens: its positive stiffness
        // and so its own limit can be far above the reference step.)
        for (int k = 0; k < 40 && accepts(hi); ++k) lo = hi, hi *= 4;
        ASSERT_FALSE(accepts(hi)) << trial;
        for (int k = 0; k < 50; ++k) {
            const double mid = 0.5 * (lo + hi);
            (accepts(mid) ? lo : hi) = mid;
        }
        if (lo == 0) continue;  // refused at any step (not expected: a softening direction only)
        // Exact: the element alone, its lumped mass, K's positive part.
        MatX K, C;
        assembleElements(w, K, C);
        VecX im(12);
        for (int a = 0; a < 4; ++a) im.segment<3>(3 * a).setConstant(1.0 / w.mass[a]);
        const double exact = exactStableStep(im, positivePart(K), C, lo);
        record(std::string(m.law == MaterialLaw::StableNeoHookean ? "element, stable Neo-Hookean"
                                                                  : "element, Saint-Venant-Kirchhoff"),
               lo, exact);
        ++states;
    }
    EXPECT_GT(states, 1000);
}

// Pieces resting on a rigid wall: the elements at rest plus each bottom
// node's normal and tangential springs and dashpots (area-weighted), against
// stableDt().combined.
TEST(StableStepProperty, PiecesOnARigidWall) {
    std::mt19937_64 g(7);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 120; ++trial) {
        const int tpc = std::vector<int>{5, 6, 12}[trial % 3];
        const int nc = tpc == 12 ? 1 : 1 + trial % 2;
        Material m;
        m.young = 1e6;
        m.density = 1000;
        m.poisson = -0.9 + 1.39 * u(g);
        if (trial < 6) m.poisson = -0.5;
        m.radius = 0.1 * std::pow(10.0, -2 + 3 * u(g));  // contact from negligible to dominant
        m.restitution = trial % 4 == 0 ? 1.0 : 0.05 + 0.95 * u(g);
        m.viscosity = trial % 2 ? 0.0 : std::pow(10.0, -1 + 3 * u(g));
        World w;
        w.addPiece(boxMesh(nc, nc, nc, 0.1, 0.1, 0.1, tpc), w.addMaterial(m));
        addFloor(w, -0.05 - 0.5 * m.radius);
        const double reported = w.stableDt().combined;
        MatX K, C;
        assembleElements(w, K, C);
        const PairConst pc = mix(materialSide(m, m.frictionWall), rigidSide());
        for (std::size_t s = 0; s < w.surfNodes.size(); ++s) {
            const int32_t node = w.surfNodes[s];
            if (w.pos[3 * node + 2] > -0.05 + 1e-9) continue;  // the bottom face touches the floor
            const PairLaw law = pairLaw(pc, w.mass[node]);
            const double wa = w.surfWeight[s];
            for (int d = 0; d < 3; ++d) {
                VecX e = VecX::Zero(K.rows());
                e[3 * node + d] = 1;
                addSpring(K, e, wa * (d == 2 ? law.kn : law.kt));
                addSpring(C, e, std::sqrt(wa) * (d == 2 ? law.cn : law.ct));
            }
        }
        VecX im(K.rows());
        for (std::size_t a = 0; a < w.nNodes(); ++a) im.segment<3>(3 * a).setConstant(1.0 / w.mass[a]);
        record("node-wall contact", reported, exactStableStep(im, K, C, reported));
    }
}

// A YADE sphere resting on a piece's top face (a ball: 3 translations and 3
// rotations; its tangential spring acts at its surface), against
// stableDt().combined.
TEST(StableStepProperty, SpheresRestingOnAPiece) {
    std::mt19937_64 g(11);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 100; ++trial) {
        Material m;
        m.young = std::pow(10.0, 5 + 3 * u(g));
        m.density = 1000;
        m.poisson = -0.5 + 0.99 * u(g);
        m.radius = 0.002 + 0.01 * u(g);
        m.restitution = trial % 4 == 0 ? 1.0 : 0.05 + 0.95 * u(g);
        m.viscosity = 0;
        World w;
        w.addPiece(boxMesh(2, 2, 1, 0.2, 0.2, 0.05, std::vector<int>{5, 6}[trial % 2]), w.addMaterial(m));
        // The sphere: radius, material and mass from light to heavy against the nodes.
        const double R = 0.005 + 0.03 * u(g), young = std::pow(10.0, 5 + 4 * u(g));
        const double ktRatio = trial % 5 == 0 ? -1.0 : 0.2 + 0.8 * u(g);
        const double friction = trial % 4 == 1 ? 0.0 : 0.5, restitution = trial % 3 == 0 ? 1.0 : 0.1 + 0.9 * u(g);
        const double mass = w.pieces[0].mass * std::pow(10.0, -4 + 4 * u(g));
        const int32_t id = 1, pairStart[2] = {0, 1}, pairPiece[1] = {0};
        w.setSpheres(1, &id, &R, &young, &ktRatio, &friction, &restitution, &mass, pairStart, pairPiece);
        const double reported = w.stableDt().combined;
        // Where it touches: a point of the top face, on one of its triangles.
        const Eigen::Vector2d at(-0.09 + 0.18 * u(g), -0.09 + 0.18 * u(g));
        int32_t tri[3];
        Eigen::Vector3d bary;
        faceTriangleAt(w, 0, at, 0.025, tri, bary);
        ASSERT_GE(tri[0], 0);
        // The pair's constants as sphereContacts makes them.
        const PairConst pc = mix(ContactSide{young * R, ktRatio, restitution, friction, R},
                                 materialSide(m, m.frictionPiece));
        double mT = 0;
        for (int k = 0; k < 3; ++k) mT += bary[k] * w.mass[tri[k]];
        const PairLaw law = pairLaw(pc, mass, mT);
        MatX Kel, Cel;
        assembleElements(w, Kel, Cel);
        const auto nn = Kel.rows(), n = nn + 6;  // nodes, then the sphere's translation and rotation
        MatX K = MatX::Zero(n, n), C = MatX::Zero(n, n);
        K.topLeftCorner(nn, nn) = Kel;
        C.topLeftCorner(nn, nn) = Cel;
        const Eigen::Vector3d normal(0, 0, 1), arm = -R * normal;  // from the centre to the contact point
        for (int d = 0; d < 3; ++d) {
            const Eigen::Vector3d dir = Eigen::Vector3d::Unit(d);
            VecX row = VecX::Zero(n);
            for (int k = 0; k < 3; ++k) row.segment<3>(3 * tri[k]) -= bary[k] * dir;
            row.segment<3>(nn) = dir;
            if (d < 2) row.segment<3>(nn + 3) = arm.cross(dir);  // (w x arm).dir = w.(arm x dir)
            if (d < 2 && !(law.mu > 0)) continue;  // no friction: no tangential spring
            addSpring(K, row, d == 2 ? law.kn : law.kt);
            addSpring(C, row, d == 2 ? law.cn : law.ct);
        }
        VecX im(n);
        for (std::size_t a = 0; a < w.nNodes(); ++a) im.segment<3>(3 * a).setConstant(1.0 / w.mass[a]);
        im.segment<3>(nn).setConstant(1.0 / mass);
        im.segment<3>(nn + 3).setConstant(1.0 / (0.4 * mass * R * R));
        record("sphere-triangle contact", reported, exactStableStep(im, K, C, reported));
    }
}

// One piece resting on another: each node of either face pressed on the
// other's face (point-polygon, both ways) is a spring between the node and
// the triangle point under it, area-weighted, with its dashpots on the
// reduced mass of the two; against stableDt().combined after one step, which
// counts the contacts as they are (pieceContact).  Without that, the estimate
// counting one spring per node was above the exact step in 2 of 60 states
// with the bottom faces' contacts alone (by 1.9 %), and by up to 3.2x with
// every contact the reach makes (a reach above the cell size: the upper
// cube's side nodes touch the lower face too).
TEST(StableStepProperty, PiecesRestingOnPieces) {
    std::mt19937_64 g(23);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 60; ++trial) {
        Material m;
        m.young = 1e6;
        m.density = 1000;
        m.poisson = -0.9 + 1.39 * u(g);
        m.radius = 0.1 * std::pow(10.0, -2 + 3 * u(g));
        m.restitution = trial % 4 == 0 ? 1.0 : 0.05 + 0.95 * u(g);
        m.viscosity = trial % 2 ? 0.0 : std::pow(10.0, -1 + 3 * u(g));
        m.frictionPiece = trial % 3 == 0 ? 0.0 : 0.3;
        World w;
        const int mat = w.addMaterial(m);
        const int tpc = std::vector<int>{5, 6}[trial % 2];
        w.addPiece(boxMesh(2, 2, 1, 0.2, 0.2, 0.1, tpc), mat);  // the lower piece, top at z = 0.05
        TetMesh upper = boxMesh(1, 1, 1, 0.1, 0.1, 0.1, 5 + (trial / 2) % 2);
        const double dx = -0.04 + 0.08 * u(g), dy = -0.04 + 0.08 * u(g);
        for (std::size_t a = 0; a < upper.nNodes(); ++a)
            upper.nodes[3 * a] += dx, upper.nodes[3 * a + 1] += dy, upper.nodes[3 * a + 2] += 0.1;
        w.addPiece(upper, mat);  // its bottom at z = 0.05
        // One step too short to move anything: the contacts as they are
        // (what the engine checks each step: stableDt's pieceContact).
        w.step(1e-12);
        const double reported = w.stableDt().combined;
        MatX K, C;
        assembleElements(w, K, C);
        const PairConst pc = mix(materialSide(m, m.frictionPiece), materialSide(m, m.frictionPiece));
        // The springs of every point-polygon contact the step found (with a
        // reach r_a + r_b above the cell size, nodes of the upper cube's sides
        // touch the lower face too), from the contact model: normal along the
        // node's direction from the triangle point, tangential across it.
        int contacts = 0, bottom = 0;
        const SurfaceIndex& S = w.surfaceIndex();
        constexpr int KP = PointPolygonKind::kSlots;
        for (std::size_t s = 0; s < w.surfNodes.size(); ++s)
            for (int slot = 0; slot < KP; ++slot) {
                const int32_t key = w.pointPolygonKeys()[KP * s + slot];
                if (key < 0) continue;
                const int32_t t = S.pieceTriStart[w.pointPolygonKeyPieces()[KP * s + slot]] + key / 8;
                const int32_t node = w.surfNodes[s], *tri = &S.tri[3 * t];
                auto at = [&](int32_t a) { return Eigen::Vector3d(w.pos[3 * a], w.pos[3 * a + 1], w.pos[3 * a + 2]); };
                const TriPoint cp = closestOnTriangle(at(node), at(tri[0]), at(tri[1]), at(tri[2]));
                const Eigen::Vector3d d = at(node) - cp.point;
                const Eigen::Vector3d n = d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized())
                                                           : Eigen::Vector3d((at(tri[1]) - at(tri[0]))
                                                                                 .cross(at(tri[2]) - at(tri[0]))
                                                                                 .normalized());
                const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
                double mT = 0;
                for (int k = 0; k < 3; ++k) mT += cp.w[k] * w.mass[tri[k]];
                const PairLaw law = pairLaw(pc, w.mass[node], mT);
                const double wa = w.surfWeight[s];
                const Eigen::Vector3d dirs[3] = {n, t1, t2};
                for (int q = 0; q < 3; ++q) {
                    if (q > 0 && !(law.mu > 0)) continue;  // no friction: no tangential spring
                    VecX row = VecX::Zero(K.rows());
                    row.segment<3>(3 * node) += dirs[q];
                    for (int k = 0; k < 3; ++k) row.segment<3>(3 * tri[k]) -= cp.w[k] * dirs[q];
                    addSpring(K, row, wa * (q == 0 ? law.kn : law.kt));
                    addSpring(C, row, std::sqrt(wa) * (q == 0 ? law.cn : law.ct));
                }
                ++contacts;
                bottom += std::fabs(w.pos[3 * node + 2] - 0.05) < 1e-9;
            }
        ASSERT_GE(bottom, 5) << trial;  // the upper cube's 4 bottom nodes, at least one node of the lower face
        ASSERT_GT(contacts, 0);
        VecX im(K.rows());
        for (std::size_t a = 0; a < w.nNodes(); ++a) im.segment<3>(3 * a).setConstant(1.0 / w.mass[a]);
        record("node-triangle contact", reported, exactStableStep(im, K, C, reported));
    }
}

// Writes the ratios (after the tests above, in this binary's order).
TEST(StableStepProperty, ZzWritesTheRatios) {
    const char* path = std::getenv("QDEM_STABLE_STEP_JSON");
    if (!path) GTEST_SKIP() << "QDEM_STABLE_STEP_JSON not set";
    std::ofstream out(path);
    out << "{\n";
    bool first = true;
    for (const auto& [family, r] : ratios()) {
        out << (first ? "" : ",\n") << "  \"" << family << "\": [";
        for (std::size_t i = 0; i < r.size(); ++i) out << (i ? ", " : "") << r[i];
        out << "]";
        first = false;
    }
    out << "\n}\n";
}
