// A contact kind added in one file plus one row (issue 13): a test-only
// repulsive node-node kind, f = k (R - d) along the line of centres for
// surface nodes of different pieces closer than R = r_a + r_b.  It is defined
// and registered here only (addContactKind), runs through the same phase as
// the seed's kinds, and its force and counter come out as hand-computed.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "material/Material.hpp"
#include "phases/ContactKind.hpp"
#include "phases/PieceContactState.hpp"
#include "world/World.hpp"

using namespace qdem;

namespace {

constexpr double kStiffness = 1000.0;  // [N/m]

// ---- the kind: one class ---------------------------------------------------
class NodeNodeRepulsion final : public ContactKind {
public:
    long run(KindStep& s) override {
        const PieceContactData& w = s.world;
        const PieceContactState& L = s.lists;  // neighbour pieces from the broad phase
        double* buf = s.threadForce[0].data();  // (runs on one thread)
        long n = 0;
        for (std::size_t pa = 0; pa < w.pieces.size(); ++pa)
            for (int32_t q = L.nbrStart[pa]; q < L.nbrStart[pa + 1]; ++q) {
                const auto pb = static_cast<std::size_t>(L.nbrs[q]);
                if (pb < pa) continue;  // each pair once
                const double R = w.materials[w.pieces[pa].material].radius + w.materials[w.pieces[pb].material].radius;
                for (int32_t i = w.pieces[pa].surfBegin; i < w.pieces[pa].surfEnd; ++i)
                    for (int32_t j = w.pieces[pb].surfBegin; j < w.pieces[pb].surfEnd; ++j) {
                        const int32_t a = w.surfNodes[i], b = w.surfNodes[j];
                        double d[3], d2 = 0;
                        for (int k = 0; k < 3; ++k) d[k] = w.pos[3 * a + k] - w.pos[3 * b + k], d2 += d[k] * d[k];
                        const double dist = std::sqrt(d2);
                        if (dist >= R || dist == 0) continue;
                        const double f = kStiffness * (R - dist) / dist;
                        for (int k = 0; k < 3; ++k) buf[3 * i + k] += f * d[k], buf[3 * j + k] -= f * d[k];
                        ++n;
                    }
            }
        return n;
    }
};

std::unique_ptr<ContactKind> makeNodeNode() { return std::make_unique<NodeNodeRepulsion>(); }

// ---- the row -------------------------------------------------------------
const ContactKindRow kRow{"nodeNodeTest", "nothing (surface nodes of neighbour pieces, all pairs)", "none",
                          nullptr, &makeNodeNode};

// Registered for this test's worlds only.
struct Registered {
    Registered() { addContactKind(kRow); }
    ~Registered() { removeContactKind(kRow.name); }
};

// A tet with its apex at (0, 0, z) pointing up (sign +1) or down (-1).
TetMesh apexTet(double z, int sign) {
    TetMesh m;
    const double s = 0.1;
    m.nodes = {0, 0, z, s, 0, z + sign * s, -0.5 * s, 0.8 * s, z + sign * s, -0.5 * s, -0.8 * s, z + sign * s};
    m.tets = {0, 1, 2, 3};
    orientPositive(m);
    return m;
}

}  // namespace

TEST(ContactKindTable, TestOnlyKindAddedByOneRowActsAsWritten) {
    const Registered reg;
    World w;
    Material m;
    m.radius = 0.01;
    const int mat = w.addMaterial(m);
    const double gap = 0.015;  // the two apexes: R = 0.02 apart by 0.015
    w.addPiece(apexTet(0.0, -1), mat);
    w.addPiece(apexTet(gap, +1), mat);
    // The seed's kinds off: only the new one can act.
    w.settings.pointPolygonOn = false;
    w.settings.edgeEdgeOn = false;
    w.step(1e-9);
    const PhaseReport r = w.report();
    EXPECT_EQ(r.count("nodeNodeTest"), 1);
    EXPECT_EQ(r.count("pointPolygon"), 0);
    // Apex of piece 1 pushed up, apex of piece 0 down, by k (R - d).
    const double f = kStiffness * (0.02 - gap);
    const int32_t a0 = w.pieces[0].nodeBegin, a1 = w.pieces[1].nodeBegin;
    // (tolerance: the element forces of the undeformed tets are rounding,
    // ~1e-10 N with the default E = 5e8 Pa, against f = 5 N)
    const double tol = 1e-8 * f;
    EXPECT_NEAR(w.force[3 * a1 + 2], f, tol);
    EXPECT_NEAR(w.force[3 * a0 + 2], -f, tol);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(w.force[3 * a1 + k], 0.0, tol);
    // Nothing else: the other nodes feel no force.
    for (std::size_t n = 0; n < w.nNodes(); ++n) {
        if (static_cast<int32_t>(n) == a0 || static_cast<int32_t>(n) == a1) continue;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(w.force[3 * n + k], 0.0, tol);
    }
}

TEST(ContactKindTable, SeedKindsAreRowsWithSwitches) {
    const auto& t = contactKinds();
    ASSERT_GE(t.size(), 2u);
    EXPECT_STREQ(t[0].name, "pointPolygon");
    EXPECT_EQ(t[0].on, &Settings::pointPolygonOn);
    EXPECT_STREQ(t[1].name, "edgeEdge");
    EXPECT_EQ(t[1].on, &Settings::edgeEdgeOn);
}

// The broad phase builds the lists the switched-on rows declare, and no
// others: a row's Registration bits are all it takes (no switch of the seed's
// kinds is read for that).
TEST(ContactKindTable, BroadPhaseBuildsTheListsTheRowsDeclare) {
    const auto lists = [](unsigned declared) {
        const ContactKindRow row{"listsTest", "as declared", "none", nullptr, &makeNodeNode, declared};
        addContactKind(row);
        World w;
        Material m;
        m.radius = 0.01;
        const int mat = w.addMaterial(m);
        w.addPiece(apexTet(0.0, -1), mat);
        w.addPiece(apexTet(0.015, +1), mat);
        w.settings.pointPolygonOn = false;
        w.settings.edgeEdgeOn = false;
        w.step(1e-9);
        removeContactKind(row.name);
        // Verlet lists of triangles built, feature edges registered.
        return std::pair<long, std::size_t>{w.verletRebuilds(), static_cast<std::size_t>(w.pieceContactState().registeredEdges())};
    };
    EXPECT_EQ(lists(RegisterNothing), (std::pair<long, std::size_t>{0, 0}));
    const auto tris = lists(RegisterSurfaceTriangles);
    EXPECT_EQ(tris.first, 1);
    EXPECT_EQ(tris.second, 0u);
    const auto edges = lists(RegisterFeatureEdges);
    EXPECT_EQ(edges.first, 0);
    EXPECT_GT(edges.second, 0u);  // the tets' edges are all feature edges
    const auto both = lists(RegisterSurfaceTriangles | RegisterFeatureEdges);
    EXPECT_EQ(both.first, 1);
    EXPECT_EQ(both.second, edges.second);
}
