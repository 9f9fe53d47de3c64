// One contact per touch: the rules shared by node-triangle (point-polygon) and
// sphere-triangle contacts that turn the candidate triangles near a point into
// the contacts it feels (doc/contacts.md §3).
#pragma once
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "ContactDetail.hpp"

namespace qdem::contact_detail {

// cand[0..nc) are the candidate closest points of one query point A, their
// features snapped (snappedFeature, PointTriangle.hpp: CandidateList does it); keep[i]
// starts true (false for candidates already rejected, e.g. by the inside test).
// triPiece maps a triangle to its piece: duplicates are only resolved within
// one piece.  eps: a length at rounding level; cosFeature: cosine of the
// feature angle below which two contacts with one piece are one touch.
//
// The rules below were first written as pairwise loops over the candidates
// (O(nc^2), ~800 instructions per node of the 27-cube stack, a sixth of
// point-polygon); they are evaluated here in one pass per rule with the same
// result, bit for bit, for any distances that are not NaN (the argument at
// each rule; tests/cpp/test_touch_selection.cpp checks it against the
// pairwise form on random and tied candidate sets).
//
// Returns the candidates kept as bits (bit i: keep[i]), for the callers'
// loops over the touches (one in six candidates in the 27-cube stack).
static_assert(kCandidates <= 32, "selectTouches returns the kept candidates as 32 bits");
inline uint32_t selectTouches(const Vector3d& A, Candidate* cand, int nc, bool* keep, const int32_t* triPiece,
                              double eps, double cosFeature) {
    // Edge and corner closest points are shared by the triangles around
    // them: per piece keep only the nearest one, and only if no face contact
    // of that piece is nearer (the point is then in that edge's or corner's
    // region of the surface).  Each point of a surface is thus reported once,
    // and a point sliding across edges and corners keeps one continuous contact.
    //
    // As a pairwise rule (visiting i in order, j over the candidates still
    // kept): an edge or corner candidate i stays while dist_i < d_j - eps for
    // every face j of its piece (d_j signed: negative behind) and (dist_i,
    // i) < (dist_j, j) for every other edge or corner j.  Faces never drop
    // here, so the face test is dist_i < min_j d_j - eps (rounding of x - eps
    // is monotone in x).  Among edges and corners only the least M by (dist,
    // index) can stay: any other i meets M (still kept when M comes later;
    // when M came earlier, either it stayed, or a face dropped it and then
    // drops i too, dist_i >= dist_M).  M itself stays iff it passes the
    // faces.  So one pass: per piece the least edge or corner and the
    // nearest face.
    int32_t piece[kCandidates];  // each kept candidate's piece, looked up once
    int32_t gPiece[kCandidates];
    int gBest[kCandidates];     // least edge or corner candidate of the piece (-1: none)
    double gFace[kCandidates];  // least signed distance of its faces (when gKept > 0)
    int gKept[kCandidates];     // its faces kept, then its candidates kept
    int ng = 0;
    uint32_t mask = 0;
    for (int i = 0; i < nc; ++i) {
        const Candidate& c = cand[i];
        if (!keep[i]) continue;
        const int32_t pb = piece[i] = triPiece[c.tri];
        int g = 0;
        while (g < ng && gPiece[g] != pb) ++g;
        if (g == ng) gPiece[ng] = pb, gBest[ng] = -1, gFace[ng] = INFINITY, gKept[ng] = 0, ++ng;
        if (c.cp.feature == TriFeature::Face) {
            gFace[g] = std::min(gFace[g], c.behind ? -c.dist : c.dist);
            ++gKept[g];
            mask |= 1u << i;
        } else {
            keep[i] = false;  // back below if it is its piece's touch
            if (gBest[g] < 0 || c.dist < cand[gBest[g]].dist) gBest[g] = i;
        }
    }
    bool twoOnAPiece = false;
    for (int g = 0; g < ng; ++g) {
        const int b = gBest[g];
        if (b >= 0 && (gKept[g] == 0 || cand[b].dist < gFace[g] - eps))  // (no face: kept)
            keep[b] = true, ++gKept[g], mask |= 1u << b;
        twoOnAPiece = twoOnAPiece || gKept[g] > 1;
    }
    if (!twoOnAPiece) return mask;  // the rule below compares contacts with one piece
    // Two contacts with the same piece whose normals differ by less than the
    // feature angle are one touch of a nearly flat (possibly slightly folded)
    // surface: keep the nearer.  Without this, a point over a shallow concave
    // fold would feel both faces at full strength, and the count would
    // flicker as the fold flexes.  Real corners (a point in a concave corner)
    // keep both contacts.  (Pairwise over the candidates still kept, in
    // order: the same visits as over all of them, skipping the dropped ones.)
    int kept[kCandidates];
    int nk = 0;
    for (int i = 0; i < nc; ++i)
        if (keep[i]) kept[nk++] = i;
    Vector3d cn[kCandidates];
    for (int a = 0; a < nk; ++a) {
        const int i = kept[a];
        cn[i] = (cand[i].behind ? -1.0 : 1.0) * (A - cand[i].cp.point) / std::max(cand[i].dist, eps);
    }
    for (int a = 0; a < nk; ++a) {
        const int i = kept[a];
        if (!keep[i]) continue;
        for (int b = a + 1; b < nk && keep[i]; ++b) {
            const int j = kept[b];
            if (!keep[j] || piece[j] != piece[i]) continue;
            if (cn[i].dot(cn[j]) < cosFeature) continue;
            const double di = cand[i].behind ? -cand[i].dist : cand[i].dist;
            const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
            if (dj < di) keep[i] = false;
            else keep[j] = false;
        }
    }
    mask = 0;
    for (int a = 0; a < nk; ++a)
        if (keep[kept[a]]) mask |= 1u << kept[a];
    return mask;
}

// Tangential history slot for the contact keyed kk = 8 * triangle + feature
// with piece pb: the slot of the same surface feature, else one inherited from
// a contact with the same piece that ended this step (a point sliding onto the
// next triangle keeps its spring); -1 = a new contact.  key/kpiece hold the K
// slots of the previous step; usedOld marks slots already taken.
inline int historySlot(const int32_t* key, const int32_t* kpiece, const bool* usedOld, int K, int32_t kk, int32_t pb,
                       const Candidate* cand, const bool* keep, int nc, const int32_t* triPiece,
                       const int32_t* pieceTriStart) {
    int slot = -1;
    for (int k = 0; k < K; ++k)
        if (key[k] == kk && kpiece[k] == pb && !usedOld[k]) slot = k;
    // Then the touch on the same triangle at another feature (its closest
    // point moved from the face onto an edge or a corner, or back): the
    // same touch, whichever other touches of the piece ended.
    for (int k = 0; k < K && slot < 0; ++k)
        if (key[k] >= 0 && kpiece[k] == pb && !usedOld[k] && historyTri(key[k]) == historyTri(kk)) slot = k;
    if (slot < 0)
        for (int k = 0; k < K && slot < 0; ++k)
            if (key[k] >= 0 && kpiece[k] == pb && !usedOld[k]) {
                bool matchedLater = false;
                for (int j = 0; j < nc; ++j)
                    if (keep[j] && triPiece[cand[j].tri] == pb &&
                        historyKey(cand[j].tri - pieceTriStart[pb], cand[j].cp.feature) == key[k])
                        matchedLater = true;
                if (!matchedLater) slot = k;
            }
    return slot;
}

// The set of touches of a point changes only without creating or destroying
// stored energy (doc/contacts.md §3, "Touches that split and merge").  A touch
// that splits off (more touches with a piece than on the previous step) is
// born at zero force: bornDeepRef with threshold 0 (touchedPiece says the
// point touched the piece before).  A touch that ends while still pressing
// (two touches merging: the feature-angle rule, or its closest point moving
// onto an edge or corner that a face of another touch beats) hands its
// stored depth to the surviving touch of that piece whose normal is nearest
// its own, handed[j] += (overlap - reference)^2 (candidate j's index): the
// survivor lowers its reference so that its ½ kn δ² holds both (the
// caller's handOverRef).  Both touches have the same kn (one point, one
// piece), so the energy is handed over exactly.
inline bool touchedPiece(const int32_t* key, const int32_t* kpiece, int K, int32_t pb) {
    for (int k = 0; k < K; ++k)
        if (key[k] >= 0 && kpiece[k] == pb) return true;
    return false;
}

// usedOld: the old slots continued by this step's touches (historySlot for
// every kept touch, in order); reachOf(pb): the contact reach with piece pb.
// Returns whether anything was handed (handed[] zeroed by the caller).
template <class ReachOf>
inline bool handOver(const Vector3d& A, const Candidate* cand, int nc, const bool* keep, const int32_t* triPiece,
                     const int32_t* pieceTriStart, const int32_t* key, const int32_t* kpiece, const double* ref,
                     const bool* usedOld, int K, double eps, ReachOf&& reachOf, double* handed) {
    bool any = false;
    for (int k = 0; k < K; ++k) {
        if (key[k] < 0 || usedOld[k]) continue;
        const int32_t pb = kpiece[k];
        const int32_t t = pieceTriStart[pb] + historyTri(key[k]);
        int g = 0;
        while (g < nc && cand[g].tri != t) ++g;
        if (g == nc) continue;  // out of reach: it ended at zero force
        const Candidate& cg = cand[g];
        const double reach = reachOf(pb);
        const double depth = (cg.behind ? reach + cg.dist : reach - cg.dist) - ref[k];
        if (depth <= 0) continue;
        const Vector3d ng = (cg.behind ? -1.0 : 1.0) * (A - cg.cp.point) / std::max(cg.dist, eps);
        int best = -1;
        double bestDot = -INFINITY;
        for (int j = 0; j < nc; ++j) {
            if (!keep[j] || triPiece[cand[j].tri] != pb) continue;
            const double d = ng.dot((cand[j].behind ? -1.0 : 1.0) * (A - cand[j].cp.point) / std::max(cand[j].dist, eps));
            if (d > bestDot) bestDot = d, best = j;
        }
        if (best < 0) continue;  // no touch with the piece left
        handed[best] += depth * depth;
        any = true;
    }
    return any;
}

// The reference of a survivor at overlap ov (reference r0) that takes the
// squared depths handed to it: its depth becomes sqrt(δ² + handed), the
// reference never below zero (a contact never pulls).
inline double handOverRef(double ov, double r0, double handed) {
    const double d = std::max(ov - r0, 0.0);
    return std::max(0.0, ov - std::sqrt(d * d + handed));
}

}  // namespace qdem::contact_detail
