// Point-polygon contacts: every surface node against the surface triangles
// of the other pieces (seed §3.1), with the rules of doc/contacts.md §3.
// One thread per surface node (seed §4.1).  A node's contacts in order: its
// candidates (listed triangles, or the cells; the carried ones), the inside
// test of those behind, the touches with their history slots, the forces.
// (The parts are inlined into the sweep: the same code, the same bits, as
// one function.)
#include "PointPolygonKind.hpp"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "../contact/ContactDetail.hpp"
#include "../contact/ContactLaw.hpp"
#include "../contact/ContactLoop.hpp"
#include "../contact/Geometry.hpp"
#include "../contact/PointTriangle.hpp"
#include "../contact/TouchSelection.hpp"
#include "../contact/TriLanesFill.hpp"
#include "../core/Errors.hpp"
#include "../core/ThreadPartials.hpp"
#include "../parallel/Domain.hpp"
#include "../step/WorldState.hpp"
#include "ContactLoad.hpp"
#include "PieceContactPhase.hpp"

#define QDEM_INLINE [[gnu::always_inline]] inline

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;

namespace {

constexpr int K = PointPolygonKind::kSlots;

// A node found past the middle of the piece it went into (the run stops).
struct Tunnel {
    int32_t node = -1, pa = -1, pb = -1;
    double depth = 0, speed = 0, mass = 0, kn = 0;
};

}  // namespace

// What every node of one sweep reads.  (Raw pointers in locals: the loop
// stores through narrow pointers that may alias anything, which would reload
// them through the world's references.)
struct PointPolygonKind::Step {
    PieceContactPhase& phase;
    const PieceContactData& w;
    const PieceContactState& L;
    const SurfaceIndex& S;
    double dt;
    int32_t ns;
    bool tets, interiorFacesToo, regions, regularized, listValid, startPending;
    long stamp;
    double cosFeature;
    const double* radius;
    const uint8_t* active;
    const uint8_t* frozen;
    const uint8_t* startChecked;
    const int32_t *triPiece, *listStart, *listFlat, *listCount, *tri, *surfNodes, *nodePiece;
    const double *normal, *X, *V, *M;
    const Domain* dom;
    int32_t *key, *kpiece;
    double *shear, *ref;
    long* stamps;
    Tunnel* tunnel;
};

// One thread's buffers and tallies.
struct PointPolygonKind::Thread {
    Thread(double* b, double* l, double* p, PieceContactPhase::DeepContact& d) : buf(b), load(l), pe(p), deep(d) {}
    EnergyTally energy;  // damping and slip [J] (the elastic energy goes to the piece's ledger entry)
    double maxOv = 0;
    long count = 0, interiorTests = 0, interiorNear = 0, listed = 0;
    double* buf;
    double* load;
    double* pe;
    PieceContactPhase::DeepContact& deep;
    CandidateList cl;  // the one candidate policy (PointTriangle.hpp)
    // The pair law last looked up: consecutive nodes mostly touch the
    // same piece from the same piece (8,748 look-ups, ~60 instructions
    // each, in the 27-cube stack).
    int32_t lastPa = -1, lastPb = -1;
    PairConst lastLaw{};
    TriLanes lanes;
    TriLanesOut near;
};

// One surface node's contacts in this step.
struct PointPolygonKind::Node {
    int32_t s, node, pa;
    const Material* ma;
    Vector3d A;
    int32_t* key;
    int32_t* kpiece;
    double* shear;
    double* ref;
    bool watched, useList;
    bool keep[kCandidates];
};

namespace {

using Step = PointPolygonKind::Step;
using Thread = PointPolygonKind::Thread;
using Node = PointPolygonKind::Node;

// The law's constants of the node's piece with piece pb.
QDEM_INLINE PairConst lawOf(const Step& P, Thread& T, const Node& N, int32_t pb) {
    const int32_t pa = N.pa;
    if (pa == T.lastPa && pb == T.lastPb) return T.lastLaw;
    T.lastPa = pa, T.lastPb = pb;
    for (int32_t q = P.L.nbrStart[pa]; q < P.L.nbrStart[pa + 1]; ++q)
        if (P.L.nbrs[q] == pb) return T.lastLaw = P.L.nbrLaw[q];
    return T.lastLaw = pairConst(*N.ma, P.w.materials[P.w.pieces[pb].material]);  // listed before the pieces parted
}

// Software prefetch for the nodes ahead.  The loop's hottest stalls were
// loads that miss: a listed triangle's corners, normal and piece (by its
// id), then the corners' positions (by those), and in the contacts the
// corners' velocities and masses.  Far ahead, the triangles' own rows; near
// (those rows now in cache), the corners' rows and the node's history.
// (Not from or for a sleeping scene's frozen nodes, which are skipped.)
// (nodes ahead; 2/1, 3/1, 4/2 and 6/3 measured alike, within noise)
QDEM_INLINE void prefetchAhead(const Step& P, int32_t s) {
    constexpr int32_t kAheadFar = 3, kAheadNear = 1;
    const int32_t sa = s + kAheadFar, sb = s + kAheadNear, ns = P.ns;
    const int32_t *listCount = P.listCount, *listFlat = P.listFlat, *listStart = P.listStart;
    if (sa < ns && listCount[sa] > 0 && !P.frozen[P.nodePiece[P.surfNodes[sa]]]) {
        const int32_t* L2 = listFlat + listStart[sa];
        for (int32_t k = 0; k < listCount[sa]; ++k) {
            __builtin_prefetch(P.tri + 3 * L2[k]);
            __builtin_prefetch(P.normal + 3 * L2[k]);
            __builtin_prefetch(P.triPiece + L2[k]);
        }
    }
    if (sb < ns && listCount[sb] > 0 && !P.frozen[P.nodePiece[P.surfNodes[sb]]]) {
        const int32_t* L1 = listFlat + listStart[sb];
        for (int32_t k = 0; k < listCount[sb]; ++k) {
            const int32_t* c = P.tri + 3 * L1[k];
            for (int j = 0; j < 3; ++j) {
                __builtin_prefetch(P.X + 3 * c[j]);
                __builtin_prefetch(P.V + 3 * c[j]);
                __builtin_prefetch(P.M + c[j]);
            }
        }
        __builtin_prefetch(P.key + K * sb);
        __builtin_prefetch(P.kpiece + K * sb);
        __builtin_prefetch(P.shear + 3 * K * sb);
        __builtin_prefetch(P.ref + K * sb);
    }
}

// Candidate triangles from the node's Verlet list: the same tests as
// consider(), the closest points of kTriLanes listed triangles at a time
// (SIMD lane code).
QDEM_INLINE void listedCandidates(const Step& P, Thread& T, const Node& N) {
    CandidateList& cl = T.cl;
    TriLanes& lanes = T.lanes;
    TriLanesOut& near = T.near;
    const Vector3d& A = N.A;
    const int32_t* L = P.listFlat + P.listStart[N.s];
    const int32_t n = P.listCount[N.s];
    T.listed += n;
    for (int32_t k0 = 0; k0 < n; k0 += kTriLanes) {
        const int cnt = std::min<int32_t>(kTriLanes, n - k0);
        // Lanes past cnt keep the triangles last loaded (a whole
        // triangle each, so finite numbers); their results are
        // not read.  (A quarter of the lanes here.)
        int l0 = 0;
        for (; l0 + 4 <= cnt; l0 += 4) fillTriLanes4(P.X, P.tri, P.normal, L + k0 + l0, l0 / 4, lanes);
        for (int l = l0; l < cnt; ++l) {
            const int32_t t = L[k0 + l];
            const int32_t* c = P.tri + 3 * t;
            for (int d = 0; d < 3; ++d) {
                lanes.a[d][l] = P.X[3 * c[0] + d];
                lanes.b[d][l] = P.X[3 * c[1] + d];
                lanes.c[d][l] = P.X[3 * c[2] + d];
                lanes.n[d][l] = P.normal[3 * t + d];
            }
        }
        closestOnTriangles(A.data(), lanes, near);
        alignas(64) int32_t snapped[kTriLanes];  // the features as candidates carry them
#pragma omp simd
        for (int l = 0; l < kTriLanes; ++l)
            snapped[l] = snappedFeature(near.w[0][l], near.w[1][l], near.w[2][l], near.feature[l]);
        for (int l = 0; l < cnt; ++l) {
            const int32_t t = L[k0 + l];
            const int32_t pb = P.triPiece[t];
            if (!P.active[pb]) continue;
            const double reach = N.ma->radius + P.radius[pb];
            const double h = near.h[l];
            if (h > reach) continue;
            const double dist = std::sqrt(near.dist2[l]);
            if (!P.regions && dist - std::abs(h) > 1e-9 * reach) continue;  // seed's inside test
            const bool behind =
                h < 0 && straightBehind(near.feature[l] == static_cast<int32_t>(TriFeature::Face), dist, h);
            if (!behind && dist >= reach) continue;
            Candidate* cd = cl.slotFor(dist);
            if (!cd) continue;
            cd->tri = t;
            cd->cp.point = Vector3d(near.point[0][l], near.point[1][l], near.point[2][l]);
            for (int k = 0; k < 3; ++k) cd->cp.w[k] = near.w[k][l];
            cd->cp.feature = static_cast<TriFeature>(snapped[l]);
            cd->dist = dist;
            cd->behind = behind;
            cl.noteBehind(behind);
        }
    }
}

// Candidate triangles from the cells (no list, or a crowded node): bounding
// sphere grown by the reach holds the node, and the node is within reach in
// front of its plane (or behind it: possibly inside that piece).
QDEM_INLINE void cellCandidates(const Step& P, Thread& T, const Node& N) {
    const SurfaceIndex& S = P.S;
    const PieceContactState& st = P.L;
    const Vector3d& A = N.A;
    auto consider = [&](int32_t t, double reach) {
        const int32_t* c = &S.tri[3 * t];
        T.cl.consider(A, t, at(P.X, c[0]), at(P.X, c[1]), at(P.X, c[2]),
                      Eigen::Map<const Vector3d>(&st.triNormal[3 * t]), reach, P.regions);
    };
    for (int32_t q = st.nbrStart[N.pa]; q < st.nbrStart[N.pa + 1]; ++q) {
        const int32_t pb = st.nbrs[q];
        const double reach = N.ma->radius + P.radius[pb];
        {
            const Vector3d lo = A.array() - reach, hi = A.array() + reach;
            bool overlap = true;
            for (int d = 0; d < 3 && overlap; ++d)
                overlap = lo[d] <= P.w.bounds.hi[3 * pb + d] && P.w.bounds.lo[3 * pb + d] <= hi[d];
            if (!overlap) continue;
        }
        const int32_t i0 = st.itemStart[pb];
        // Items that can reach the node have their reference point within
        // (largest radius + reach) of it: visit the cells of that box only.
        const Vector3d qlo = A.array() - st.itemReach, qhi = A.array() + st.itemReach;
        st.itemGrid[pb].forRange(qlo.data(), qhi.data(), [&](int32_t local) {
            const int32_t it = i0 + local;
            // (grown by the skin: the cells may date from the last list rebuild)
            const double R = st.itemRadius[it] + reach + (st.listValid ? st.listSkin : 0.0);
            if ((A - Eigen::Map<const Vector3d>(&st.itemPoint[3 * it])).squaredNorm() > R * R) return;
            const int32_t id = st.items[it];
            if (!P.tets) {
                consider(id, reach);
                return;
            }
            for (int k = 0; k < 4; ++k) {
                const int32_t t = S.tetFaceTri[4 * id + k];
                if (t >= 0) {
                    consider(t, reach);
                } else if (P.interiorFacesToo) {
                    // Cases A and B test interior faces too (and find them
                    // irrelevant): the cost the seed's Figure 6 measures.
                    int32_t f[3], n = 0;
                    for (int j = 0; j < 4; ++j)
                        if (j != k) f[n++] = P.w.tetNodes[4 * id + j];
                    const TriPoint cp = closestOnTriangle(A, at(P.X, f[0]), at(P.X, f[1]), at(P.X, f[2]));
                    ++T.interiorTests;
                    if ((A - cp.point).norm() < reach) ++T.interiorNear;
                }
            }
        });
    }
}

// Side memory (issue 12): a contact carried from the last step keeps its
// triangle while the node stays behind that face, however deep.  The search
// only reaches the triangle's bounding sphere grown by the reach (and skin):
// a fast impact pushed nodes deeper than that (29 mm for 33 mm triangles),
// the contact was lost and two cubes at 25 m/s passed through each other
// (doc/hard_cases.md).
QDEM_INLINE void carriedCandidates(const Step& P, Thread& T, const Node& N) {
    const SurfaceIndex& S = P.S;
    const Vector3d& A = N.A;
    for (int k = 0; k < K && N.key[k] >= 0; ++k) {
        const int32_t t = S.pieceTriStart[N.kpiece[k]] + historyTri(N.key[k]);
        bool found = false;
        for (int i = 0; i < T.cl.n && !found; ++i) found = T.cl.c[i].tri == t;
        if (found || !P.active[P.triPiece[t]]) continue;
        const int32_t* c = P.tri + 3 * t;
        const Vector3d a = at(P.X, c[0]);
        if ((A - a).dot(Eigen::Map<const Vector3d>(P.normal + 3 * t)) >= 0) continue;  // in front: ends as usual
        const TriPoint cp = closestOnTriangle(A, a, at(P.X, c[1]), at(P.X, c[2]));
        const double dist = (A - cp.point).norm();
        const double h = (A - a).dot(Eigen::Map<const Vector3d>(P.normal + 3 * t));
        // Behind the plane and at most a reach beside the triangle
        // (its neighbours, folded by the impact, may hold the node's
        // projection now): still the face it went in through.
        const double reachT = N.ma->radius + P.radius[P.triPiece[t]];
        if (dist * dist - h * h > reachT * reachT) continue;
        T.cl.add(Candidate{t, cp, dist, true});
    }
}

// Inside test for behind candidate i (rare: deep penetration): the node is
// inside a piece only if no front-facing point of that piece's surface is
// nearer.  An outside point's nearest surface point faces it and is strictly
// nearer than any point of a face seen from behind.
QDEM_INLINE void insideTest(const Step& P, Thread& T, Node& N, int i) {
    const SurfaceIndex& S = P.S;
    const PieceContactState& st = P.L;
    const Vector3d& A = N.A;
    const Candidate* cand = T.cl.c;
    bool* keep = N.keep;
    const int32_t pb = S.triPiece[cand[i].tri];
    const double db = cand[i].dist;
    const int32_t i0 = st.itemStart[pb];
    const Vector3d qlo = A.array() - st.itemReach, qhi = A.array() + st.itemReach;
    int32_t killedBy = -1;  // the front face found nearer
    auto witness = [&](int32_t id) {
        if (!keep[i]) return;
        for (int k = 0; k < (P.tets ? 4 : 1); ++k) {
            const int32_t t = P.tets ? S.tetFaceTri[4 * id + k] : id;
            if (t < 0) continue;
            const int32_t* c = &S.tri[3 * t];
            if (frontFaceNearer(A, at(P.X, c[0]), at(P.X, c[1]), at(P.X, c[2]),
                                Eigen::Map<const Vector3d>(&st.triNormal[3 * t]), db)) {
                keep[i] = false;
                killedBy = t;
            }
        }
    };
    if (N.useList) {
        const int32_t* L = P.listFlat + P.listStart[N.s];
        for (int k = 0; k < P.listCount[N.s]; ++k)
            if (P.triPiece[L[k]] == pb) witness(L[k]);
    } else {
        st.itemGrid[pb].forRange(qlo.data(), qhi.data(), [&](int32_t local) { witness(st.items[i0 + local]); });
    }
    // Side memory (issue 12): a contact carried from the last step
    // whose node is still behind its face came from the front - the
    // node went in through that face - and keeps pushing it back out,
    // whatever nearer face the other piece's own deformation (faces
    // folded by a deep impact) now shows it.  Only the far side of the
    // piece (a face facing back across it) ends it: the node then
    // crossed the middle, the law did not stop the impact, and the
    // run stops (below) rather than push the node on through.
    if (!keep[i] && N.watched) {
        bool carried = false;
        for (int k = 0; k < K && N.key[k] >= 0; ++k)
            carried = carried ||
                      (N.kpiece[k] == pb && S.pieceTriStart[pb] + historyTri(N.key[k]) == cand[i].tri);
        const bool farSide = killedBy >= 0 && Eigen::Map<const Vector3d>(P.normal + 3 * killedBy)
                                                      .dot(Eigen::Map<const Vector3d>(P.normal + 3 * cand[i].tri)) <
                                                  -0.5;
        if (carried && !farSide) {
            keep[i] = true;
        } else if (carried && db > N.ma->radius + P.radius[pb]) {
            double mT;
            Vector3d vT;
            trianglePointState(cand[i], P.tri + 3 * cand[i].tri, P.w.mass, P.w.vel, mT, vT);
            const double speed = (at(P.w.vel, N.node) - vT).norm();
            Tunnel& tunnel = *P.tunnel;
#pragma omp critical(qdemTunnel)
            if (tunnel.node < 0)
                tunnel = Tunnel{N.node, N.pa, pb, db, speed, P.w.mass[N.node], lawOf(P, T, N, pb).kn};
        }
    }
}

// The kept candidates' contact forces, their history written back.
template <bool Friction>
QDEM_INLINE void applyTouches(const Step& P, Thread& T, Node& N, uint32_t touches, double eps) {
    const SurfaceIndex& S = P.S;
    const PieceContactData& w = P.w;
    const Candidate* cand = T.cl.c;
    const int nc = T.cl.n;
    const int32_t s = N.s, node = N.node, pa = N.pa;
    int32_t* key = N.key;
    int32_t* kpiece = N.kpiece;
    double* ref = N.ref;
    const double dt = P.dt;
    int32_t newKey[K], newPiece[K];
    NewSlots<K> slots;  // the kept contacts' springs and references
    const ContactLoop<Friction> loop(dt, P.regularized, w.settings.frictionRegVelocity);
    bool usedOld[K] = {false, false, false, false, false, false};
    // History slots of the touches, in order, then what touches that
    // ended while pressing hand over (TouchSelection.hpp).
    int slotOf[kCandidates];
    int nTouch = 0;
    for (uint32_t m = touches; m && nTouch < K; m &= m - 1, ++nTouch) {
        const int i = std::countr_zero(m);
        const int32_t pb = P.triPiece[cand[i].tri];
        slotOf[i] = historySlot(key, kpiece, usedOld, K, historyKey(cand[i].tri - S.pieceTriStart[pb], cand[i].cp.feature),
                                pb, cand, N.keep, nc, P.triPiece, S.pieceTriStart.data());
        if (slotOf[i] >= 0) usedOld[slotOf[i]] = true;
    }
    double handed[kCandidates];
    bool anyHanded = false;
    if (N.watched && key[0] >= 0) {
        bool ended = false;
        for (int k = 0; k < K; ++k) ended = ended || (key[k] >= 0 && !usedOld[k]);
        if (ended) {
            for (int i = 0; i < nc; ++i) handed[i] = 0.0;
            anyHanded = handOver(N.A, cand, nc, N.keep, P.triPiece, S.pieceTriStart.data(), key, kpiece, ref, usedOld, K,
                                 eps, [&](int32_t pb) { return lawOf(P, T, N, pb).reach; }, handed);
        }
    }
    Vector3d fA = Vector3d::Zero();
    for (uint32_t m = touches; m && !slots.full(); m &= m - 1) {  // the kept candidates in order
        const int i = std::countr_zero(m);
        const Candidate& c = cand[i];
        const int32_t* tn = &S.tri[3 * c.tri];
        const int32_t pb = P.triPiece[c.tri];
        double mT;
        Vector3d vT;
        trianglePointState(c, tn, w.mass, w.vel, mT, vT);
        const PairConst pc = lawOf(P, T, N, pb);
        const double reach = pc.reach;
        const Vector3d nT(P.L.triNormal[3 * c.tri], P.L.triNormal[3 * c.tri + 1], P.L.triNormal[3 * c.tri + 2]);
        ContactGeometry g;
        candidateContact(c, N.A, nT, reach, eps, g.n, g.overlap);
        // Tangential history: same surface feature, else inherited from
        // a contact with the same piece that ended this step (a node
        // sliding onto the next triangle keeps its spring).
        const int slot = slotOf[i];
        g.vRel = at(w.vel, node) - vT;
        g.mass = g.slipMass = w.mass[node] * mT / (w.mass[node] + mT);
        g.stiffWeight = w.surfWeight[s];  // the query node's area weight
        g.dampWeight = std::sqrt(g.stiffWeight);
        // The spring turns with the contact about n at the mean spin
        // of its two sides: the node's own, and the triangle's at the
        // contact point, interpolated from its corners' (surface spins
        // continuous over the surface: SurfaceSpin.hpp, doc/formulation.md
        // "Twist").
        if (loop.turns(pc)) {
            const double* om = P.L.surfSpin.data();
            Vector3d wSum = at(om, s);
            for (int k = 0; k < 3; ++k) wSum += c.cp.w[k] * at(om, S.surfIndexOfNode[tn[k]]);
            g.spin = 0.5 * wSum.dot(g.n);
        }
        // A touch that splits off one with the same piece starts from zero
        // force (threshold 0, TouchSelection.hpp); one missed by the
        // detection from its present overlap (threshold the reach).
        ContactHistory h;
        if (slot >= 0) h.shear = &N.shear[3 * slot], h.ref = &ref[slot];
        h.watched = N.watched;
        h.threshold = slot < 0 && touchedPiece(key, kpiece, K, pb) ? 0.0 : reach;
        h.handed = anyHanded ? handed[i] : 0.0;
        ContactParams cp;
        const ContactResult r = loop.touch(pc, g, h, slots, T.pe ? &T.pe[3 * pa + 2] : nullptr, &T.energy, &cp);
        // How deep the node is behind pb's surface (overlap - reach:
        // > 0 behind it), against the reach: the per-step check.
        P.phase.noteDepth(T.deep, g.overlap - reach, reach, g.vRel.dot(g.n), node, pa, pb, false);
        if (P.startPending && !(P.startChecked[pa] && P.startChecked[pb]))
            P.phase.notePress(pa, pb, r.elastic, g.overlap);  // placed pressed in: the start warning's energy
        newKey[slots.n - 1] = historyKey(c.tri - S.pieceTriStart[pb], c.cp.feature);
        newPiece[slots.n - 1] = pb;
        fA += r.force;
        // (the tangential spring and dashpot act with the spring law only)
        const bool tangential = loop.turns(pc);
        // (theta = m_node / m_T: ContactLoad.hpp)
        const double mSum = w.mass[node] + mT;
        addContactLoad(T.load, s, 0.5 * mSum / mT, cp, tangential);  // (adds 2 x share)
        for (int k = 0; k < 3; ++k)
            if (c.cp.w[k] != 0) {
                addTo(T.buf, S.surfIndexOfNode[tn[k]], -c.cp.w[k] * r.force);
                addContactLoad(T.load, S.surfIndexOfNode[tn[k]], 0.5 * c.cp.w[k] * mSum / w.mass[node], cp, tangential);
            }
        ++T.count;
        T.maxOv = std::max(T.maxOv, g.overlap);
    }
    addTo(T.buf, s, fA);
    for (int k = 0; k < K; ++k) {
        key[k] = k < slots.n ? newKey[k] : -1;
        kpiece[k] = k < slots.n ? newPiece[k] : -1;
    }
    slots.store(N.shear, ref);
}

// Surface node s: its candidates, the inside test, its touches.
template <bool Friction>
QDEM_INLINE void nodeContacts(const Step& P, Thread& T, int32_t s) {
    const int32_t node = P.surfNodes[s];
    if (P.dom && !P.dom->owns(node)) return;  // under MPI: the point's owner computes the contact
    const int32_t pa = P.nodePiece[node];
    if (P.frozen[pa]) {  // asleep among sleeping pieces: history kept
        P.stamps[s] = P.stamp;
        return;
    }
    if (P.listValid) prefetchAhead(P, s);
    Node N;
    N.s = s, N.node = node, N.pa = pa;
    N.key = P.key + K * s;
    N.kpiece = P.kpiece + K * s;
    N.shear = P.shear + 3 * K * s;
    N.ref = P.ref + K * s;
    N.watched = P.stamps[s] == P.stamp - 1;
    if (!N.watched)  // history is only valid from the previous step
        for (int k = 0; k < K; ++k) N.key[k] = -1;
    P.stamps[s] = P.stamp;
    N.useList = P.L.listValid && P.listCount[s] >= 0;
    if (!P.active[pa] || (N.useList && P.listCount[s] == 0 && N.key[0] < 0)) {
        // Nothing can touch this node: its slots are empty (slots
        // after the first empty one are empty too).  A node with a
        // contact carried from the last step goes on: it may be deep
        // behind that face, beyond the list's range (side memory).
        if (N.key[0] >= 0)
            for (int k = 0; k < K; ++k) N.key[k] = -1;
        return;
    }
    N.ma = &P.w.materials[P.w.pieces[pa].material];
    N.A = at(P.X, node);
    T.cl.clear();
    if (N.useList) listedCandidates(P, T, N);
    else cellCandidates(P, T, N);
    if (N.watched) carriedCandidates(P, T, N);
    const int nc = T.cl.n;
    Candidate* const cand = T.cl.c;
    for (int i = 0; i < nc; ++i) N.keep[i] = true;
    if (T.cl.anyBehind)
        for (int i = 0; i < nc; ++i)
            if (cand[i].behind) insideTest(P, T, N, i);
    if (P.startPending)  // set-up check (PieceStartOverlap.cpp): a node centre inside another piece
        for (int i = 0; i < nc; ++i) {
            if (!N.keep[i] || !cand[i].behind) continue;
            const int32_t pb = P.triPiece[cand[i].tri];
            if (P.startChecked[pa] && P.startChecked[pb]) continue;
            P.phase.noteStartSeen(pa, pb);
        }
    const double eps = 1e-12 * N.ma->radius;
    const uint32_t touches = selectTouches(N.A, cand, nc, N.keep, P.triPiece, eps, P.cosFeature);
    applyTouches<Friction>(P, T, N, touches, eps);
}

[[noreturn]] void throwTunnel(const Tunnel& tunnel, long iter) {
    // Stopping distance of a node of mass m at speed v on a spring kn:
    // v sqrt(m / kn) (doc/hard_cases.md, "Tunnelling").
    const double stop = tunnel.speed * std::sqrt(tunnel.mass / tunnel.kn);
    std::ostringstream m;
    m.precision(3);
    m << "QDEM: piece " << tunnel.pa << " went through piece " << tunnel.pb << " at step " << iter << ": node "
      << tunnel.node << " is " << tunnel.depth << " m behind a face of piece " << tunnel.pb
      << " and past its middle, at a relative speed of " << tunnel.speed
      << " m/s. The contact is too soft to stop this impact: stopping distance v sqrt(m_node/kn) = " << stop
      << " m (node mass " << tunnel.mass << " kg, kn " << tunnel.kn
      << " N/m) against the piece's half thickness. Make the contact stiffer (kn = E r: a larger QdemMat young "
         "or radius; 4x kn halves the stopping distance), the impact slower or the pieces thicker";
    throw StabilityError(m.str());
}

}  // namespace

template <bool Friction>
long PointPolygonKind::sweep(KindStep& ks) {
    const PieceContactData& w = ks.world;
    const PieceContactState& st = ks.lists;
    Tunnel tunnel;
    const Step P{ks.phase,
                 w,
                 st,
                 w.surface,
                 ks.dt,
                 static_cast<int32_t>(w.surfNodes.size()),
                 w.settings.broadPhase != BroadPhase::Triangles,
                 w.settings.broadPhase == BroadPhase::AllTets || w.settings.broadPhase == BroadPhase::SurfaceTets,
                 w.settings.pointPolygonRegions,
                 w.settings.frictionModel == FrictionModel::Regularized,
                 st.listValid,
                 ks.phase.startPending(),
                 w.iter,
                 std::cos(w.settings.edgeFeatureAngle),
                 st.pieceRadius.data(),
                 st.pieceActive.data(),
                 ks.phase.frozenFlags(),
                 ks.phase.startCheckedFlags(),
                 w.surface.triPiece.data(),
                 st.listStart.data(),
                 st.listFlat.data(),
                 st.listCount.data(),
                 w.surface.tri.data(),
                 w.surfNodes.data(),
                 w.nodePiece.data(),
                 st.triNormal.data(),
                 w.pos.data(),
                 w.vel.data(),
                 w.mass.data(),
                 w.domain.built(),
                 key_.data(),
                 piece_.data(),
                 shear_.data(),
                 ref_.data(),
                 stamp_.data(),
                 &tunnel};
    long count = 0, interiorTests = 0, interiorNear = 0, listed = 0;
    double maxOv = ks.maxOverlap;
    ThreadPartials<2> energyParts(omp_get_max_threads());  // damping, slip: added in thread order
#pragma omp parallel reduction(+ : count, interiorTests, interiorNear, listed) reduction(max : maxOv)
    {
        const int th = omp_get_thread_num();
        Thread T(ks.threadForce[th].data(), ks.threadLoad[th].data(),
                 w.settings.trackEnergy ? w.threadPieceEnergy[th].data() : nullptr, ks.phase.threadDeep(th));
        for (int l = 0; l < kTriLanes; ++l)  // a unit triangle in every lane until one is loaded
            for (int d = 0; d < 3; ++d)
                T.lanes.a[d][l] = 0, T.lanes.b[d][l] = d == 0, T.lanes.c[d][l] = d == 1, T.lanes.n[d][l] = d == 2;
        // Static chunks: a node goes to the same thread every run, so a given
        // thread count gives the same bits (its contacts always land in the same
        // thread buffer).  nowait: the region ends with the loop.
#pragma omp for schedule(static, 64) nowait
        for (int32_t s = 0; s < P.ns; ++s) nodeContacts<Friction>(P, T, s);
        energyParts.set(th, {T.energy.damp, T.energy.slip});
        count += T.count, interiorTests += T.interiorTests, interiorNear += T.interiorNear, listed += T.listed;
        maxOv = std::max(maxOv, T.maxOv);
    }
    const std::array<double, 2> energySum = energyParts.sum();
    ks.eDamp += energySum[0];
    ks.eSlip += energySum[1];
    ks.maxOverlap = maxOv;
    listed_ = listed;
    interiorTests_ = interiorTests;
    interiorNear_ = interiorNear;
    if (tunnel.node >= 0) throwTunnel(tunnel, w.iter);
    return count;
}

long PointPolygonKind::run(KindStep& s) { return s.friction ? sweep<true>(s) : sweep<false>(s); }

void PointPolygonKind::piecesAdded(const PieceContactData& w) {
    const std::size_t ns = w.surfNodes.size();
    stamp_.resize(ns, -2);
    key_.resize(K * ns, -1);
    piece_.resize(K * ns, -1);
    shear_.resize(3 * K * ns, 0.0);
    ref_.resize(K * ns, 0.0);
}

void PointPolygonKind::stateColumns(StateColumns& c) {
    c.add("ppKey", key_, Rows::SurfaceNode);
    c.add("ppPiece", piece_, Rows::SurfaceNode);
    c.add("ppShear", shear_, Rows::SurfaceNode);
    c.add("ppRef", ref_, Rows::SurfaceNode);
    c.add("ppStamp", stamp_, Rows::SurfaceNode);
}

void PointPolygonKind::loadFields(const WorldState& s, const PieceContactData& w) {
    if (s.fields.count("eePiece") > 0) return;
    for (std::size_t k = 0; k < key_.size(); ++k)
        if (key_[k] >= 0) key_[k] -= 8 * w.surface.pieceTriStart[piece_[k]];
}

void PointPolygonKind::report(PhaseReport& r) const {
    r.counts.push_back({"interiorFaceTests", interiorTests_});
    r.counts.push_back({"interiorFaceNear", interiorNear_});
    r.counts.push_back({"listedTriangles", listed_});
}

void PointPolygonKind::addLoadWeights(const PieceContactData& w, double* perNode, double work) const {
    const std::size_t ns = w.surfNodes.size();
    if (ns == 0) return;
    const std::size_t k = key_.size() / ns;
    for (std::size_t i = 0; i < ns; ++i)
        for (std::size_t j = 0; j < k; ++j)
            if (key_[i * k + j] >= 0) perNode[w.surfNodes[i]] += work;
}

}  // namespace qdem
