// Touches that split and merge (contact/TouchSelection.hpp, doc/contacts.md
// §3): a touch that ends while pressing hands its stored energy to the
// survivor nearest its normal, exactly; a touch that ended out of reach or at
// rest hands nothing; history follows a touch across its triangle's features.
#include <gtest/gtest.h>

#include <cmath>

#include "contact/TouchSelection.hpp"

using namespace qdem;
using namespace qdem::contact_detail;

namespace {

Candidate faceCandidate(int32_t tri, const Vector3d& A, const Vector3d& n, double dist) {
    Candidate c;
    c.tri = tri;
    c.behind = false;
    c.dist = dist;
    c.cp.point = A - dist * n;
    c.cp.w[0] = c.cp.w[1] = c.cp.w[2] = 1.0 / 3.0;
    c.cp.feature = TriFeature::Face;
    return c;
}

}  // namespace

TEST(TouchHandover, EndedPressingTouchHandsItsEnergyToTheSurvivorNearestItsNormal) {
    // One point, one piece (triangles 0..3), reach 0.1.  Last step: touches on
    // triangles 1 (reference 0) and 3 (reference 0.02).  Now triangle 1 ends
    // (not kept) at overlap 0.03; survivors: triangle 2 (normal 10 deg from
    // triangle 1's) and triangle 3 (normal 60 deg away).
    const double reach = 0.1;
    const Vector3d A(0, 0, 0);
    const double a10 = 10 * M_PI / 180, a60 = 60 * M_PI / 180;
    Candidate cand[3] = {faceCandidate(1, A, Vector3d(0, 0, 1), reach - 0.03),
                         faceCandidate(2, A, Vector3d(std::sin(a10), 0, std::cos(a10)), reach - 0.04),
                         faceCandidate(3, A, Vector3d(0, std::sin(a60), std::cos(a60)), reach - 0.05)};
    const bool keep[3] = {false, true, true};
    const int32_t triPiece[4] = {0, 0, 0, 0};
    const int32_t pieceTriStart[1] = {0};
    const int K = 4;
    const int32_t key[K] = {historyKey(1, TriFeature::Face), historyKey(3, TriFeature::Face), -1, -1};
    const int32_t kpiece[K] = {0, 0, -1, -1};
    const double ref[K] = {0.0, 0.02, 0.0, 0.0};
    bool usedOld[K] = {false, false, false, false};
    // Triangle 2 has no touch of its own: historySlot gives it the ended
    // touch's slot (a point sliding onto the next triangle keeps its spring).
    const int s2 = historySlot(key, kpiece, usedOld, K, historyKey(2, TriFeature::Face), 0, cand, keep, 3, triPiece,
                               pieceTriStart);
    EXPECT_EQ(s2, 0);
    // Here the survivor on triangle 2 is taken as new (slot -1) to test the
    // hand-over on its own: usedOld marks triangle 3's touch continued.
    usedOld[1] = true;
    double handed[3] = {0, 0, 0};
    ASSERT_TRUE(handOver(A, cand, 3, keep, triPiece, pieceTriStart, key, kpiece, ref, usedOld, K, 1e-14,
                         [&](int32_t) { return reach; }, handed));
    EXPECT_DOUBLE_EQ(handed[1], 0.03 * 0.03);  // to triangle 2, the nearest normal
    EXPECT_EQ(handed[2], 0.0);
    // Survivor at overlap 0.06, reference 0.03 (depth 0.03): its new depth holds both energies.
    const double r = handOverRef(0.06, 0.03, handed[1]);
    const double before = 0.5 * (0.03 * 0.03) + 0.5 * (0.03 * 0.03), after = 0.5 * (0.06 - r) * (0.06 - r);
    EXPECT_NEAR(after, before, 1e-15);
    // A survivor not deep enough takes reference 0: it never pulls.
    EXPECT_EQ(handOverRef(0.01, 0.0, handed[1]), 0.0);
}

TEST(TouchHandover, TouchesThatEndAtRestOrOutOfReachHandNothing) {
    const double reach = 0.1;
    const Vector3d A(0, 0, 0);
    Candidate cand[2] = {faceCandidate(1, A, Vector3d(0, 0, 1), reach - 0.01),
                         faceCandidate(2, A, Vector3d(0.1, 0, 1).normalized(), reach - 0.04)};
    const bool keep[2] = {false, true};
    const int32_t triPiece[3] = {0, 0, 0};
    const int32_t pieceTriStart[1] = {0};
    const int K = 4;
    // Triangle 1's touch had reference 0.02 > its overlap 0.01 (at rest);
    // triangle 0's touch has no candidate any more (out of reach).
    const int32_t key[K] = {historyKey(1, TriFeature::Face), historyKey(0, TriFeature::Edge1), -1, -1};
    const int32_t kpiece[K] = {0, 0, -1, -1};
    const double ref[K] = {0.02, 0.0, 0.0, 0.0};
    const bool usedOld[K] = {false, false, false, false};
    double handed[2] = {0, 0};
    EXPECT_FALSE(handOver(A, cand, 2, keep, triPiece, pieceTriStart, key, kpiece, ref, usedOld, K, 1e-14,
                          [&](int32_t) { return reach; }, handed));
    EXPECT_EQ(handed[1], 0.0);
}

TEST(TouchHandover, HistoryFollowsATouchAcrossItsTrianglesFeatures) {
    // Two touches of one piece last step (triangles 5 face, 7 face); now the
    // point's closest point on triangle 7 is its edge, and triangle 5's touch
    // ended.  Triangle 7's edge continues triangle 7's slot (1), not the first
    // ended slot (0).
    const Vector3d A(0, 0, 0);
    Candidate cand[1] = {faceCandidate(7, A, Vector3d(0, 0, 1), 0.05)};
    cand[0].cp.feature = TriFeature::Edge0;
    const bool keep[1] = {true};
    const int32_t triPiece[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    const int32_t pieceTriStart[1] = {0};
    const int K = 4;
    const int32_t key[K] = {historyKey(5, TriFeature::Face), historyKey(7, TriFeature::Face), -1, -1};
    const int32_t kpiece[K] = {0, 0, -1, -1};
    const bool usedOld[K] = {false, false, false, false};
    EXPECT_EQ(historySlot(key, kpiece, usedOld, K, historyKey(7, TriFeature::Edge0), 0, cand, keep, 1, triPiece,
                          pieceTriStart),
              1);
    EXPECT_TRUE(touchedPiece(key, kpiece, K, 0));
    EXPECT_FALSE(touchedPiece(key, kpiece, K, 1));
}
