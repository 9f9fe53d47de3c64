// Contact history keyed by stable ids (piece, local triangle / edge), not by
// global array index (issue 13): the keys a run stores are local, and a state
// saved with the old global keys is converted on load and continues the run
// exactly as the new one does.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "core/Threads.hpp"
#include "material/Material.hpp"
#include "mesh/BoxMesh.hpp"
#include "world/World.hpp"
#include "step/WorldState.hpp"

using namespace qdem;

namespace {

// Piece 0 far away (so the global triangle and edge ids of pieces 1 and 2 do
// not start at 0); piece 2, turned 45 degrees about z, pressed onto piece 1
// and sliding: point-polygon and edge-edge contacts with friction history.
std::unique_ptr<World> scene() {
    auto wp = std::make_unique<World>();
    World& w = *wp;
    Material m;
    m.young = 1e6;
    m.poisson = 0.3;
    m.density = 1000;
    m.radius = 0.01;
    m.frictionPiece = 0.5;
    const int mat = w.addMaterial(m);
    TetMesh far = boxMesh(2, 2, 2, 0.2, 0.2, 0.2, 6);
    for (std::size_t i = 0; i < far.nNodes(); ++i) far.nodes[3 * i] += 5.0;
    w.addPiece(far, mat);
    w.addPiece(boxMesh(3, 3, 2, 0.3, 0.3, 0.2, 6), mat);
    TetMesh top = boxMesh(2, 2, 2, 0.2, 0.2, 0.2, 6);
    const double c = std::cos(M_PI / 4), s = std::sin(M_PI / 4);
    for (std::size_t i = 0; i < top.nNodes(); ++i) {
        const double x = top.nodes[3 * i], y = top.nodes[3 * i + 1];
        top.nodes[3 * i] = c * x - s * y + 0.12;  // a corner out over the lower block's edge
        top.nodes[3 * i + 1] = s * x + c * y;
        top.nodes[3 * i + 2] += 0.2 + 0.019;  // just within the contact reach 2 r = 0.02
    }
    w.addPiece(top, mat);
    for (int32_t n = w.pieces[2].nodeBegin; n < w.pieces[2].nodeEnd; ++n) {
        w.vel[3 * n] = 0.05;
        w.vel[3 * n + 2] = -0.02;
    }
    return wp;
}

double maxDiff(const World& a, const World& b) {
    double d = 0;
    for (std::size_t i = 0; i < a.pos.size(); ++i) d = std::max(d, std::fabs(a.pos[i] - b.pos[i]));
    return d;
}

}  // namespace

TEST(HistoryIds, KeysAreLocalAndOldGlobalKeysAreConverted) {
    // One thread: the contact loops' dynamic schedule sums forces in a
    // different order from run to run with more (rounding-level differences).
    struct OneThread {
        int before = qdemThreads();
        OneThread() { qdemThreads() = 1; }
        ~OneThread() { qdemThreads() = before; }
    } oneThread;
    auto ap = scene();
    World& a = *ap;
    const double dt = 0.5 * a.stableDt().combined;
    for (int i = 0; i < 100; ++i) a.step(dt);
    ASSERT_GT(a.report().count("pointPolygon"), 0);
    ASSERT_GT(a.report().count("edgeEdge"), 0) << "the scene should have edge-edge contacts";
    WorldState st = a.saveState();

    // Keys are local: below 8 x the triangle count of their piece, and their
    // piece is a real neighbour.
    const SurfaceIndex& S = a.surfaceIndex();
    const std::vector<int32_t> key = st.getAll<int32_t>("ppKey"), kp = st.getAll<int32_t>("ppPiece");
    int used = 0;
    for (std::size_t k = 0; k < key.size(); ++k) {
        if (key[k] < 0) continue;
        ++used;
        ASSERT_TRUE(kp[k] == 1 || kp[k] == 2);
        EXPECT_LT(key[k], 8 * (S.pieceTriStart[kp[k] + 1] - S.pieceTriStart[kp[k]]));
    }
    ASSERT_GT(used, 0);

    // The same state written the old way: global triangle and edge ids, no eePiece.
    WorldState old = st;
    std::vector<int32_t> gkey = key;
    for (std::size_t k = 0; k < gkey.size(); ++k)
        if (gkey[k] >= 0) gkey[k] += 8 * S.pieceTriStart[kp[k]];
    old.put("ppKey", gkey.data(), gkey.size());
    std::vector<int32_t> other = st.getAll<int32_t>("eeOther");
    const std::vector<int32_t> ep = st.getAll<int32_t>("eePiece");
    int edgeHist = 0;
    for (std::size_t k = 0; k < other.size(); ++k)
        if (other[k] >= 0) other[k] += S.pieceEdgeStart[ep[k]], ++edgeHist;
    ASSERT_GT(edgeHist, 0);
    old.put("eeOther", other.data(), other.size());
    old.fields.erase("eePiece");

    auto bp = scene(), cp = scene();
    World &b = *bp, &c = *cp;
    b.loadState(st);
    c.loadState(old);
    // The old keys converted are the new ones (the step itself would hide a
    // wrong point-polygon key: a node keeps the spring of any contact with the
    // same piece).
    const WorldState back = c.saveState();
    EXPECT_EQ(back.getAll<int32_t>("ppKey"), key);
    EXPECT_EQ(back.getAll<int32_t>("eeOther"), st.getAll<int32_t>("eeOther"));
    EXPECT_EQ(back.getAll<int32_t>("eePiece"), ep);
    for (int i = 0; i < 100; ++i) {
        a.step(dt);
        b.step(dt);
        c.step(dt);
    }
    EXPECT_EQ(maxDiff(a, b), 0.0);  // a restart continues exactly
    EXPECT_EQ(maxDiff(a, c), 0.0);  // and so does an old file, converted
}
