// The touch rules (contact/TouchSelection.hpp, doc/contacts.md §3): the
// one-pass selectTouches, with the features snapped beforehand by
// snappedFeature as the candidate lists do, against the pairwise form with
// its own snapping that it replaced (kept here as the reference, verbatim),
// candidate for candidate and feature for feature, on random candidate sets
// built to hit every branch: several pieces, edge/corner candidates at equal
// distances (the tie-break by index), faces at the same distance as an edge
// up to eps, faces behind (negative signed distance), candidates already
// dropped by the inside test, weights at rounding level (the snapping), and
// normals within and beyond the feature angle.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "contact/PointTriangle.hpp"
#include "contact/TouchSelection.hpp"

using namespace qdem;
using namespace qdem::contact_detail;

namespace {

// The pairwise rules as they were (main 3d8cf35).
void selectTouchesPairwise(const Vector3d& A, Candidate* cand, int nc, bool* keep, const int32_t* triPiece,
                           double eps, double cosFeature) {
    const double tol = 1e-9;
    int32_t piece[kCandidates];
    for (int i = 0; i < nc; ++i) piece[i] = triPiece[cand[i].tri];
    for (int i = 0; i < nc; ++i) {
        TriPoint& cp = cand[i].cp;
        int nz = 0, last = 0;
        for (int k = 0; k < 3; ++k)
            if (cp.w[k] > tol) ++nz, last = k;
        if (nz == 3) cp.feature = TriFeature::Face;
        else if (nz == 1) cp.feature = static_cast<TriFeature>(4 + last);
        else if (cp.feature == TriFeature::Face) cp.feature = TriFeature::Edge0;
    }
    for (int i = 0; i < nc; ++i) {
        const Candidate& c = cand[i];
        if (!keep[i] || c.cp.feature == TriFeature::Face) continue;
        const int32_t pb = piece[i];
        for (int j = 0; j < nc && keep[i]; ++j) {
            if (j == i || !keep[j] || piece[j] != pb) continue;
            const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
            if (cand[j].cp.feature == TriFeature::Face) keep[i] = c.dist < dj - eps;
            else keep[i] = c.dist < cand[j].dist || (c.dist == cand[j].dist && i < j);
        }
    }
    Vector3d cn[kCandidates];
    for (int i = 0; i < nc; ++i)
        if (keep[i]) cn[i] = (cand[i].behind ? -1.0 : 1.0) * (A - cand[i].cp.point) / std::max(cand[i].dist, eps);
    for (int i = 0; i < nc; ++i) {
        if (!keep[i]) continue;
        for (int j = i + 1; j < nc && keep[i]; ++j) {
            if (!keep[j] || piece[j] != piece[i]) continue;
            if (cn[i].dot(cn[j]) < cosFeature) continue;
            const double di = cand[i].behind ? -cand[i].dist : cand[i].dist;
            const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
            if (dj < di) keep[i] = false;
            else keep[j] = false;
        }
    }
}

}  // namespace

TEST(TouchSelection, OnePassEqualsPairwise) {
    std::mt19937 rng(16);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double eps = 1e-12, cosFeature = std::cos(0.5235987755982988);
    const int nTri = 64;
    int32_t triPiece[nTri];
    int stats[6] = {0, 0, 0, 0, 0, 0};  // kept edge/corner, dropped by a face, by a tie, by the angle, behind faces, snapped
    for (int trial = 0; trial < 200000; ++trial) {
        const int nPieces = 1 + trial % 3;
        for (int t = 0; t < nTri; ++t) triPiece[t] = static_cast<int32_t>((t * 7 + trial) % nPieces);
        const int nc = 1 + static_cast<int>(u(rng) * (trial % 4 == 0 ? kCandidates : 9));
        const Vector3d A(u(rng), u(rng), u(rng));
        // Ties, near-ties, and a face exactly eps farther than an edge (the
        // strict test dist < d - eps decides).
        const double dists[5] = {0.01, 0.02, 0.02 + 0.5 * eps, 0.03, 0.03 + eps};
        Candidate a[kCandidates], b[kCandidates];
        bool ka[kCandidates], kb[kCandidates];
        for (int i = 0; i < nc; ++i) {
            Candidate& c = a[i];
            c.tri = static_cast<int32_t>(u(rng) * nTri);
            c.dist = u(rng) < 0.7 ? dists[static_cast<int>(u(rng) * 5)] : 0.04 * u(rng);
            c.behind = u(rng) < 0.15;
            // Weights: a face, an edge or a corner, some with a rounding-level
            // weight that the snapping turns into the lower feature.
            const int kind = static_cast<int>(u(rng) * 3);
            const double tiny = u(rng) < 0.2 ? 1e-12 : 0.0;
            const double s = 0.2 + 0.6 * u(rng);
            if (kind == 0) c.cp.w[0] = s * 0.5, c.cp.w[1] = s * 0.5, c.cp.w[2] = 1 - s, c.cp.feature = TriFeature::Face;
            else if (kind == 1) c.cp.w[0] = s, c.cp.w[1] = 1 - s, c.cp.w[2] = tiny, c.cp.feature = tiny > 0 ? TriFeature::Face : TriFeature::Edge0;
            else c.cp.w[0] = tiny, c.cp.w[1] = 1, c.cp.w[2] = tiny, c.cp.feature = tiny > 0 ? TriFeature::Edge2 : TriFeature::Vert1;
            stats[5] += tiny > 0;
            // Normals mostly within the feature angle of +z, some beyond.
            const double tilt = u(rng) < 0.7 ? 0.2 * u(rng) : 1.5 * u(rng);
            const double phi = 6.283185307179586 * u(rng);
            const Vector3d dir(std::sin(tilt) * std::cos(phi), std::sin(tilt) * std::sin(phi), std::cos(tilt));
            c.cp.point = A - (c.behind ? -1.0 : 1.0) * c.dist * dir;
            ka[i] = u(rng) > 0.1;
            b[i] = c;
            kb[i] = ka[i];
        }
        selectTouchesPairwise(A, a, nc, ka, triPiece, eps, cosFeature);
        for (int i = 0; i < nc; ++i)  // snapped as CandidateList makes them
            b[i].cp.feature = static_cast<TriFeature>(
                snappedFeature(b[i].cp.w[0], b[i].cp.w[1], b[i].cp.w[2], static_cast<int32_t>(b[i].cp.feature)));
        const uint32_t touches = selectTouches(A, b, nc, kb, triPiece, eps, cosFeature);
        for (int i = 0; i < nc; ++i) {
            ASSERT_EQ(ka[i], kb[i]) << "trial " << trial << " candidate " << i << " of " << nc;
            ASSERT_EQ(kb[i], ((touches >> i) & 1u) != 0) << "trial " << trial << " candidate " << i;
            ASSERT_EQ(a[i].cp.feature, b[i].cp.feature) << "trial " << trial << " candidate " << i;
        }
        // What the sets exercised (so a generator that stops reaching a rule shows).
        int keptEdges = 0;
        for (int i = 0; i < nc; ++i) keptEdges += ka[i] && a[i].cp.feature != TriFeature::Face;
        stats[0] += keptEdges;
        for (int i = 0; i < nc; ++i) stats[4] += a[i].behind && a[i].cp.feature == TriFeature::Face;
    }
    EXPECT_GT(stats[0], 10000);
    EXPECT_GT(stats[4], 10000);
    EXPECT_GT(stats[5], 10000);
}

// The rules themselves, on a hand-made case: a node over a corner shared by
// six triangles of one piece (six corner candidates at the same distance),
// one edge candidate of another piece and a face of it eps nearer.
TEST(TouchSelection, CornerSharedBySixTrianglesIsOneTouch) {
    int32_t triPiece[8] = {0, 0, 0, 0, 0, 0, 1, 1};
    const Vector3d A(0, 0, 0.01);
    Candidate c[8];
    bool keep[8];
    for (int i = 0; i < 8; ++i) {
        c[i].tri = i;
        c[i].behind = false;
        c[i].dist = 0.01;
        c[i].cp.point = Vector3d(0, 0, 0);
        c[i].cp.w[0] = 1, c[i].cp.w[1] = 0, c[i].cp.w[2] = 0;
        c[i].cp.feature = TriFeature::Vert0;
        keep[i] = true;
    }
    c[6].cp.w[0] = 0.5, c[6].cp.w[1] = 0.5, c[6].cp.feature = TriFeature::Edge0;  // piece 1: an edge
    c[7].cp.w[0] = 0.3, c[7].cp.w[1] = 0.3, c[7].cp.w[2] = 0.4, c[7].cp.feature = TriFeature::Face;
    c[7].dist = 0.01 - 0.5e-12;  // a face of piece 1 at the same distance to within eps
    selectTouches(A, c, 8, keep, triPiece, 1e-12, std::cos(0.5235987755982988));
    const bool expected[8] = {true, false, false, false, false, false, false, true};
    for (int i = 0; i < 8; ++i) EXPECT_EQ(keep[i], expected[i]) << "candidate " << i;
}
