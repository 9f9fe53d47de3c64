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

// cand[0..nc) are the candidate closest points of one query point A; keep[i]
// starts true (false for candidates already rejected, e.g. by the inside test).
// triPiece maps a triangle to its piece: duplicates are only resolved within
// one piece.  eps: a length at rounding level; cosFeature: cosine of the
// feature angle below which two contacts with one piece are one touch.
inline void selectTouches(const Vector3d& A, Candidate* cand, int nc, bool* keep, const int32_t* triPiece,
                          double eps, double cosFeature) {
    const double tol = 1e-9;
    int32_t piece[kCandidates];  // each candidate's piece, looked up once
    for (int i = 0; i < nc; ++i) piece[i] = triPiece[cand[i].tri];
    for (int i = 0; i < nc; ++i) {  // snap rounding-level weights
        TriPoint& cp = cand[i].cp;
        int nz = 0, last = 0;
        for (int k = 0; k < 3; ++k)
            if (cp.w[k] > tol) ++nz, last = k;
        if (nz == 3) cp.feature = TriFeature::Face;
        else if (nz == 1) cp.feature = static_cast<TriFeature>(4 + last);
        else if (cp.feature == TriFeature::Face) cp.feature = TriFeature::Edge0;  // on an edge: not a face
    }
    // Edge and corner closest points are shared by the triangles around
    // them: per piece keep only the nearest one, and only if no face contact
    // of that piece is nearer (the point is then in that edge's or corner's
    // region of the surface).  Each point of a surface is thus reported once,
    // and a point sliding across edges and corners keeps one continuous contact.
    for (int i = 0; i < nc; ++i) {
        const Candidate& c = cand[i];
        if (!keep[i] || c.cp.feature == TriFeature::Face) continue;
        const int32_t pb = piece[i];
        for (int j = 0; j < nc && keep[i]; ++j) {
            if (j == i || !keep[j] || piece[j] != pb) continue;
            const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
            // A face point at (practically) the same distance is the same
            // touch seen from the face: the face keeps it.
            if (cand[j].cp.feature == TriFeature::Face) keep[i] = c.dist < dj - eps;
            else keep[i] = c.dist < cand[j].dist || (c.dist == cand[j].dist && i < j);
        }
    }
    // Two contacts with the same piece whose normals differ by less than the
    // feature angle are one touch of a nearly flat (possibly slightly folded)
    // surface: keep the nearer.  Without this, a point over a shallow concave
    // fold would feel both faces at full strength, and the count would
    // flicker as the fold flexes.  Real corners (a point in a concave corner)
    // keep both contacts.
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

}  // namespace qdem::contact_detail
