// Edge-edge contacts between feature edges of different pieces (seed §3.2),
// with the fades and side memory of doc/contacts.md §4.  One thread per
// registered edge; each pair is handled by its lower piece's edge.  A pair in
// two parts: its geometry (closest points, fades, side, overlap), then its
// force with the history.  (The parts are inlined into the sweep: the same
// code, the same bits, as one function.)
#include "EdgeEdgeKind.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactDetail.hpp"
#include "../contact/ContactLaw.hpp"
#include "../contact/ContactLoop.hpp"
#include "../contact/Geometry.hpp"
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

constexpr int K = EdgeEdgeKind::kSlots;

// Gradient of an edge-edge contact's stiffness weight
//   W = fade^2 endS endT aw,  fade = min(1, sin2 / sinFade2),
//   endS = min(1, min(s, 1 - s) len1 / reach), endT alike,
//   aw = aw(s, t) linear (daws, dawt: its slopes in s and t)
// with respect to the ends p1, q1, p2, q2 (out, in that order), for closest
// points inside both segments.  s and t move with the ends as the solution of
// (c1 - c2).e1 = 0, (c1 - c2).e2 = 0 (implicit differentiation).
void weightGradient(const Vector3d& p1, const Vector3d& q1, const Vector3d& p2, const Vector3d& q2,
                           const SegPoints& sp, double reach, double sinFade2, double fade, double endS,
                           double endT, double aw, double daws, double dawt, Vector3d out[4]) {
    const Vector3d e1 = q1 - p1, e2 = q2 - p2, g = sp.c1 - sp.c2;
    const double A = e1.squaredNorm(), B = e1.dot(e2), C = e2.squaredNorm(), D = A * C - B * B;
    const double s = sp.s, t = sp.t, len1 = std::sqrt(A), len2 = std::sqrt(C);
    const Vector3d R1[4] = {(1 - s) * e1 - g, s * e1 + g, -(1 - t) * e1, -t * e1};
    const Vector3d R2[4] = {(1 - s) * e2, s * e2, -(1 - t) * e2 - g, -t * e2 + g};
    // sin2 = D / (A C): its gradient in e1 and e2
    const Vector3d dSinE1 = (-2 * B / (A * C)) * e2 + (2 * B * B / (A * A * C)) * e1;
    const Vector3d dSinE2 = (-2 * B / (A * C)) * e1 + (2 * B * B / (A * C * C)) * e2;
    const bool fading = sp.sin2 < sinFade2, sFading = endS < 1, tFading = endT < 1;
    const double ms = std::min(s, 1 - s), mt = std::min(t, 1 - t);
    const double sgnS = s < 0.5 ? 1.0 : -1.0, sgnT = t < 0.5 ? 1.0 : -1.0;
    for (int k = 0; k < 4; ++k) {
        const Vector3d ds = (-C * R1[k] + B * R2[k]) / D;
        const Vector3d dt = (-B * R1[k] + A * R2[k]) / D;
        const double sgn = (k % 2 == 0) ? -1.0 : 1.0;  // p: -de, q: +de
        const Vector3d dSin = sgn * (k < 2 ? dSinE1 : dSinE2);
        const Vector3d dLen1 = k < 2 ? Vector3d(sgn * e1 / len1) : Vector3d::Zero();
        const Vector3d dLen2 = k >= 2 ? Vector3d(sgn * e2 / len2) : Vector3d::Zero();
        const Vector3d dFade = fading ? Vector3d(dSin / sinFade2) : Vector3d::Zero();
        const Vector3d dEndS = sFading ? Vector3d((sgnS * len1 * ds + ms * dLen1) / reach) : Vector3d::Zero();
        const Vector3d dEndT = tFading ? Vector3d((sgnT * len2 * dt + mt * dLen2) / reach) : Vector3d::Zero();
        const Vector3d dAw = daws * ds + dawt * dt;
        out[k] = (2 * fade * endS * endT * aw) * dFade + (fade * fade * endT * aw) * dEndS +
                 (fade * fade * endS * aw) * dEndT + (fade * fade * endS * endT) * dAw;
    }
}

}  // namespace

// What every edge of one sweep reads.  (Raw pointers in locals: the loop
// stores through int8_t pointers that may alias anything, which would reload
// them through the world's references.)
struct EdgeEdgeKind::Step {
    PieceContactPhase& phase;
    const PieceContactData& w;
    const PieceContactState& L;
    const SurfaceIndex& S;
    double dt, sinFade2;
    int32_t ne;
    long stamp;
    bool regularized, listValid;
    const Domain* dom;
    const double *X, *V, *M;
    const uint8_t* frozen;
    const int32_t *edgeItems, *edgeList, *edgeListCount, *edgeRec;
    int32_t *other, *otherPiece;
    int8_t* side;
    double *shear, *ref;
    long* stamps;
};

// One thread's buffers and tallies.
struct EdgeEdgeKind::Thread {
    EnergyTally energy{};  // damping and slip [J] (the elastic energy goes to the piece's ledger entry)
    double maxOv = 0;
    long count = 0;
    double* buf;
    double* load;
    double* pe;
    PieceContactPhase::DeepContact& deep;
};

// One registered edge: its history slots, and the pairs found this step.
struct EdgeEdgeKind::Edge {
    int32_t ie, e, pa, a0, a1;
    const Material* ma;
    Vector3d p1, q1;
    double len1;
    int32_t* other;       // the other edge: local id in its piece
    int32_t* otherPiece;  // and that piece
    int8_t* side;
    double* shear;
    double* ref;
    bool watched;
    int32_t newOther[K], newOtherPiece[K];
    int8_t newSide[K];
    NewSlots<K> slots;  // the kept pairs' springs and references
};

namespace {

using Step = EdgeEdgeKind::Step;
using Thread = EdgeEdgeKind::Thread;
using Edge = EdgeEdgeKind::Edge;

// The geometry of a pair of edges (the other one, je, registered).
struct PairGeometry {
    int32_t pb, b0, b1, local2;
    const Material* mb;
    double reach, fade, endS, endT, w, cn, dist, overlap;
    Vector3d p2, q2, cross, d, n;
    SegPoints sp;
    int slot, sUse;
};

// Software prefetch, as in point-polygon: the edges ahead are scattered over
// the surface's arrays (history by global edge id, the listed edges' records
// and end positions), and their loads were this loop's stalls.  Far ahead:
// the edge's history and ends, its listed edges' records; nearer: their
// positions.  (Not for a sleeping scene's frozen edges, which are skipped.)
QDEM_INLINE void prefetchAhead(const Step& P, int32_t ie) {
    constexpr int KE = PieceContactState::kEdgeList, kER = PieceContactState::kEdgeRec;
    constexpr int32_t kAheadFar = 4, kAheadNear = 2;
    const SurfaceIndex& S = P.S;
    const int32_t *edgeItems = P.edgeItems, *edgeListCount = P.edgeListCount, *edgeList = P.edgeList,
                  *edgeRec = P.edgeRec;
    const double* X = P.X;
    const int32_t jf = ie + kAheadFar, jn = ie + kAheadNear, ne = P.ne;
    const int32_t ef = jf < ne ? edgeItems[jf] : -1;
    if (ef >= 0 && edgeListCount[jf] > 0 && !P.frozen[S.edgePiece[ef]]) {
        __builtin_prefetch(P.stamps + ef);
        __builtin_prefetch(P.other + K * ef);
        __builtin_prefetch(P.otherPiece + K * ef);
        __builtin_prefetch(&S.edge[2 * ef]);
        const int32_t* L = edgeList + static_cast<std::size_t>(KE) * jf;
        for (int k = 0; k < edgeListCount[jf]; ++k) __builtin_prefetch(edgeRec + kER * L[k]);
    }
    const int32_t en = jn < ne ? edgeItems[jn] : -1;
    if (en >= 0 && edgeListCount[jn] > 0 && !P.frozen[S.edgePiece[en]]) {
        __builtin_prefetch(X + 3 * S.edge[2 * en]);
        __builtin_prefetch(X + 3 * S.edge[2 * en + 1]);
        const int32_t* L = edgeList + static_cast<std::size_t>(KE) * jn;
        for (int k = 0; k < edgeListCount[jn]; ++k) {
            __builtin_prefetch(X + 3 * edgeRec[kER * L[k]]);
            __builtin_prefetch(X + 3 * edgeRec[kER * L[k] + 1]);
        }
    }
}

// The pair's closest points, fades, side and overlap; false: no contact.
QDEM_INLINE bool pairGeometry(const Step& P, const Edge& E, int32_t je, PairGeometry& G) {
    const int32_t* rec = &P.L.edgeRec[PieceContactState::kEdgeRec * je];
    const int32_t pb = rec[2];
    if (!P.L.pieceActive[pb]) return false;
    const Material& mb = P.w.materials[P.w.pieces[pb].material];
    const double reach = E.ma->radius + mb.radius;
    const int32_t b0 = rec[0], b1 = rec[1];
    // Under MPI one rank computes the pair: the owner of the lower
    // node of this edge, the one whose slots keep the pair's history
    // (so a history row has one owner: Domain::rebalance).
    if (P.dom && P.dom->owner(std::min(E.a0, E.a1)) != P.dom->rank()) return false;
    const Vector3d& p1 = E.p1;
    const Vector3d& q1 = E.q1;
    const Vector3d p2 = at(P.X, b0), q2 = at(P.X, b1);
    const SegPoints sp = closestSegmentSegment(p1, q1, p2, q2);
    constexpr double kEnd = 1e-9;
    if (sp.s <= kEnd || sp.s >= 1 - kEnd || sp.t <= kEnd || sp.t >= 1 - kEnd) return false;
    // Fade out towards parallel edges: the seed's formula is
    // singular there; their end nodes' point-polygon contacts
    // take over.  (Also keeps the side test below away from the
    // rounding noise of a near-zero cross product.)  And fade
    // towards the ends of either edge: within one contact reach
    // of an end node, that node's point-polygon contact covers
    // the touch, and the hand-over must be continuous.
    const double fade = std::min(1.0, sp.sin2 / P.sinFade2);
    const double endS = std::min(1.0, std::min(sp.s, 1 - sp.s) * E.len1 / reach);
    const double endT = std::min(1.0, std::min(sp.t, 1 - sp.t) * (q2 - p2).norm() / reach);
    const double w = fade * fade * endS * endT;
    if (w < 1e-6) return false;
    const Vector3d cross = (q1 - p1).cross(q2 - p2);
    const double cn = cross.norm();
    const Vector3d d = sp.c1 - sp.c2;
    const double dist = d.norm();
    int slot = -1;
    const int32_t local2 = rec[3];  // history by stable id (the edge's id in its piece)
    for (int k = 0; k < K; ++k)
        if (E.other[k] == local2 && E.otherPiece[k] == pb) slot = k;
    // Which side of edge 2 edge 1 is on, along the common normal;
    // remembered so that edges pushed through each other are
    // pushed back, not let through.
    int sNow = d.dot(cross) < 0 ? -1 : 1;
    if (dist <= 1e-12 * reach && slot < 0) {  // touching at first sight: ask the piece centres
        const Vector3d ca = 0.5 * (Eigen::Map<const Vector3d>(&P.w.bounds.lo[3 * E.pa]) +
                                   Eigen::Map<const Vector3d>(&P.w.bounds.hi[3 * E.pa]));
        const Vector3d cb = 0.5 * (Eigen::Map<const Vector3d>(&P.w.bounds.lo[3 * pb]) +
                                   Eigen::Map<const Vector3d>(&P.w.bounds.hi[3 * pb]));
        sNow = (ca - cb).dot(cross) < 0 ? -1 : 1;
    }
    const int sUse = slot >= 0 && E.side[slot] != 0 ? E.side[slot] : sNow;
    double overlap;
    Vector3d n;
    if (sUse == sNow && dist > 1e-12 * reach) {
        n = d / dist;
        overlap = reach - dist;
    } else {
        n = double(sUse) * cross / cn;
        overlap = reach + dist;
    }
    if (overlap <= 0) return false;
    G.pb = pb, G.b0 = b0, G.b1 = b1, G.local2 = local2, G.mb = &mb;
    G.reach = reach, G.fade = fade, G.endS = endS, G.endT = endT, G.w = w, G.cn = cn, G.dist = dist;
    G.overlap = overlap, G.p2 = p2, G.q2 = q2, G.cross = cross, G.d = d, G.n = n, G.sp = sp;
    G.slot = slot, G.sUse = sUse;
    return true;
}

// The pair's force with its history: one more of the edge's new slots.
template <bool Friction>
QDEM_INLINE void pairForce(const Step& P, Thread& T, Edge& E, const PairGeometry& G) {
    const SurfaceIndex& S = P.S;
    const double* M = P.M;
    const double* V = P.V;
    const double dt = P.dt;
    const bool regularized = P.regularized;
    const int32_t a0 = E.a0, a1 = E.a1, b0 = G.b0, b1 = G.b1, pa = E.pa, pb = G.pb, slot = G.slot;
    const SegPoints& sp = G.sp;
    const double w = G.w, reach = G.reach, overlap = G.overlap;
    const Vector3d& n = G.n;
    const double m1 = (1 - sp.s) * M[a0] + sp.s * M[a1];
    const double m2 = (1 - sp.t) * M[b0] + sp.t * M[b1];
    const PairConst pc = pairConst(*E.ma, *G.mb);
    ContactGeometry g;
    g.n = n;
    g.overlap = overlap;
    g.vRel = ((1 - sp.s) * at(V, a0) + sp.s * at(V, a1)) - ((1 - sp.t) * at(V, b0) + sp.t * at(V, b1));
    g.mass = g.slipMass = m1 * m2 / (m1 + m2);
    // Area weight (doc/contacts.md, "Area weights"): the mean of
    // the two crossing points' weights, each interpolated along
    // its edge, so it varies continuously as the crossing slides
    // and meets the end node's point-polygon weight at the ends.
    const double* sw = P.w.surfWeight.data();
    const double aw = 0.5 * ((1 - sp.s) * sw[S.surfIndexOfNode[a0]] + sp.s * sw[S.surfIndexOfNode[a1]] +
                             (1 - sp.t) * sw[S.surfIndexOfNode[b0]] + sp.t * sw[S.surfIndexOfNode[b1]]);
    const double saw = std::sqrt(aw);
    g.stiffWeight = w * aw;
    g.dampWeight = w * saw;
    const ContactLoop<Friction> loop(dt, regularized, P.w.settings.frictionRegVelocity);
    // Turned at the mean spin of the two edges at their
    // crossing points, each interpolated along its edge
    // (doc/formulation.md, "Twist").
    if (loop.turns(pc)) {
        const double* om = P.L.surfSpin.data();
        const int32_t* si = S.surfIndexOfNode.data();
        g.spin = 0.5 * ((1 - sp.s) * at(om, si[a0]) + sp.s * at(om, si[a1]) + (1 - sp.t) * at(om, si[b0]) +
                        sp.t * at(om, si[b1]))
                           .dot(n);
    }
    ContactHistory h;
    if (slot >= 0) h.shear = &E.shear[3 * slot], h.ref = &E.ref[slot];
    h.watched = E.watched;
    // Born deep (doc/contacts.md §5), with the edge-edge
    // threshold 0: a crossing is made at the reach, so a new
    // pair deeper than this step's approach did not come by
    // an approach but by its closest points entering both
    // edges' interiors at depth -- typically the crossing
    // jumping from one segment of a bent ridge to the next,
    // where the end fades differ.  Born with its full spring
    // it brought 1/2 kn w aw delta^2 from nowhere (+13 % at
    // 30 degrees, test_crossed_bars_conserve_energy).
    h.threshold = 0.0;
    // Kept as sqrt(w aw) times the elongation: carried to a
    // step where the weight differs, the spring keeps the energy
    // it stored, 1/2 kt w aw |shear|^2, instead of gaining or
    // losing 1/2 kt d(w aw) |shear|^2 unbooked.
    h.shearScale = regularized ? 0.0 : std::sqrt(w * aw);
    ContactParams cp;
    const ContactResult r = loop.touch(pc, g, h, E.slots, T.pe ? &T.pe[3 * pa + 2] : nullptr, &T.energy, &cp);
    const double r0 = E.slots.ref[E.slots.n - 1];
    const Vector3d& vRel = g.vRel;
    // The spring's stiffness w aw kn varies with the geometry
    // (the fades, the area weight), so kn w aw delta n alone is
    // not the gradient of the energy 1/2 kn w aw delta^2 it
    // stores: the crossed bars of test_crossed_bars_conserve_energy
    // gained up to 16 % in a frictionless elastic hit.  The
    // missing part, -1/2 kn delta^2 grad(w aw), on the four
    // ends (doc/contacts.md §4, "Conservative weights").
    Vector3d fw[4];
    {
        const double del = overlap - r0;
        weightGradient(E.p1, E.q1, G.p2, G.q2, sp, reach, P.sinFade2, G.fade, G.endS, G.endT, aw,
                       0.5 * (sw[S.surfIndexOfNode[a1]] - sw[S.surfIndexOfNode[a0]]),
                       0.5 * (sw[S.surfIndexOfNode[b1]] - sw[S.surfIndexOfNode[b0]]), fw);
        const double c = -0.5 * pc.kn * del * del;
        for (auto& f : fw) f *= c;
    }
    const int nNew = E.slots.n - 1;
    E.newOther[nNew] = G.local2;
    E.newOtherPiece[nNew] = pb;
    E.newSide[nNew] = static_cast<int8_t>(G.sUse);
    double* buf = T.buf;
    addTo(buf, S.surfIndexOfNode[a0], (1 - sp.s) * r.force + fw[0]);
    addTo(buf, S.surfIndexOfNode[a1], sp.s * r.force + fw[1]);
    addTo(buf, S.surfIndexOfNode[b0], -(1 - sp.t) * r.force + fw[2]);
    addTo(buf, S.surfIndexOfNode[b1], -sp.t * r.force + fw[3]);
    {
        double* load = T.load;
        const bool tangential = loop.turns(pc);
        const double ra = 0.5 * (m1 + m2) / m2, rb = 0.5 * (m1 + m2) / m1;  // (1 + theta, 1 + 1/theta) / 2
        addContactLoad(load, S.surfIndexOfNode[a0], (1 - sp.s) * ra, cp, tangential);
        addContactLoad(load, S.surfIndexOfNode[a1], sp.s * ra, cp, tangential);
        addContactLoad(load, S.surfIndexOfNode[b0], (1 - sp.t) * rb, cp, tangential);
        addContactLoad(load, S.surfIndexOfNode[b1], sp.t * rb, cp, tangential);
    }
    // Edges crossed (overlap past the reach): how far behind
    // the other edge, against the reach (the per-step check).
    P.phase.noteDepth(T.deep, overlap - reach, reach, vRel.dot(n), a0, pa, pb, true);
    ++T.count;
    T.maxOv = std::max(T.maxOv, overlap);
}

// Registered edge ie: its pairs with the higher pieces' edges, its history.
template <bool Friction>
QDEM_INLINE void edgeContacts(const Step& P, Thread& T, int32_t ie) {
    const SurfaceIndex& S = P.S;
    const PieceContactState& st = P.L;
    const int32_t e = st.edgeItems[ie];
    const int32_t pa = S.edgePiece[e];
    if (P.frozen[pa]) {  // asleep among sleeping pieces: history kept
        P.stamps[e] = P.stamp;
        return;
    }
    if (P.listValid) prefetchAhead(P, ie);
    Edge E;
    E.ie = ie, E.e = e, E.pa = pa;
    E.other = P.other + K * e;
    E.otherPiece = P.otherPiece + K * e;
    E.side = P.side + K * e;
    E.shear = P.shear + 3 * K * e;
    E.ref = P.ref + K * e;
    E.watched = P.stamps[e] == P.stamp - 1;
    if (!E.watched)  // history is only valid from the previous step
        for (int k = 0; k < K; ++k) E.other[k] = -1, E.otherPiece[k] = -1, E.side[k] = 0, E.ref[k] = 0.0;
    P.stamps[e] = P.stamp;
    E.ma = &P.w.materials[P.w.pieces[pa].material];
    E.a0 = S.edge[2 * e], E.a1 = S.edge[2 * e + 1];
    E.p1 = at(P.X, E.a0), E.q1 = at(P.X, E.a1);
    E.len1 = (E.q1 - E.p1).norm();
    // One pair of edges: je indexes the registered edges.
    auto pair = [&](int32_t je) {
        if (E.slots.full()) return;
        PairGeometry G;
        if (pairGeometry(P, E, je, G)) pairForce<Friction>(P, T, E, G);
    };
    // Each pair of pieces once: edges of the lower piece id meet the
    // higher piece's edges, from the list made at the last rebuild or
    // from the cells.
    if (st.listValid && st.edgeListCount[ie] >= 0) {
        const int32_t* L = &st.edgeList[static_cast<std::size_t>(PieceContactState::kEdgeList) * ie];
        for (int k = 0; k < st.edgeListCount[ie]; ++k) pair(L[k]);
    } else {
        for (int32_t q = st.nbrStart[pa]; q < st.nbrStart[pa + 1]; ++q) {
            const int32_t pb = st.nbrs[q];
            if (pb < pa) continue;
            const double* lo = &st.edgeLo[3 * ie];
            const double* hi = &st.edgeHi[3 * ie];
            bool overlap = true;  // the edge's box must reach the other piece's box
            for (int d = 0; d < 3 && overlap; ++d)
                overlap = lo[d] <= P.w.bounds.hi[3 * pb + d] && P.w.bounds.lo[3 * pb + d] <= hi[d];
            if (!overlap) continue;
            const int32_t j0 = st.edgeStart[pb];
            st.edgeGrid[pb].forOverlapping(lo, hi, [&](int32_t local) { pair(j0 + local); });
        }
    }
    const int nNew = E.slots.n;
    if (nNew == 0 && E.other[0] < 0) return;  // no touch, none before (slots fill from 0): nothing to store
    for (int k = 0; k < K; ++k) {
        E.other[k] = k < nNew ? E.newOther[k] : -1;
        E.otherPiece[k] = k < nNew ? E.newOtherPiece[k] : -1;
        E.side[k] = k < nNew ? E.newSide[k] : 0;
    }
    E.slots.store(E.shear, E.ref);
}

}  // namespace

template <bool Friction>
long EdgeEdgeKind::sweep(KindStep& ks) {
    const PieceContactData& w = ks.world;
    const PieceContactState& st = ks.lists;
    const Step P{ks.phase,
                 w,
                 st,
                 w.surface,
                 ks.dt,
                 std::pow(std::sin(w.settings.edgeFadeAngle), 2),
                 st.registeredEdges(),
                 w.iter,
                 w.settings.frictionModel == FrictionModel::Regularized,
                 st.listValid,
                 w.domain.built(),
                 w.pos.data(),
                 w.vel.data(),
                 w.mass.data(),
                 ks.phase.frozenFlags(),
                 st.edgeItems.data(),
                 st.edgeList.data(),
                 st.edgeListCount.data(),
                 st.edgeRec.data(),
                 other_.data(),
                 piece_.data(),
                 side_.data(),
                 shear_.data(),
                 ref_.data(),
                 stamp_.data()};
    long count = 0;
    double maxOv = ks.maxOverlap;
    // The energies are summed per thread and the threads' parts added in
    // thread order, then into the running total (ThreadPartials.hpp): the
    // ledger's last bits do not depend on which thread ends first.
    ThreadPartials<2> energyParts(omp_get_max_threads());
#pragma omp parallel reduction(+ : count) reduction(max : maxOv)
    {
        const int th = omp_get_thread_num();
        Thread T{.buf = ks.threadForce[th].data(),
                 .load = ks.threadLoad[th].data(),
                 .pe = w.settings.trackEnergy ? w.threadPieceEnergy[th].data() : nullptr,
                 .deep = ks.phase.threadDeep(th)};
        // Static chunks: an edge goes to the same thread every run, so a given
        // thread count gives the same bits (its contacts always land in the same
        // thread buffer).  nowait: the region ends with the loop.
#pragma omp for schedule(static, 64) nowait
        for (int32_t ie = 0; ie < P.ne; ++ie) edgeContacts<Friction>(P, T, ie);
        energyParts.set(th, {T.energy.damp, T.energy.slip});
        count += T.count;
        maxOv = std::max(maxOv, T.maxOv);
    }
    const std::array<double, 2> energySum = energyParts.sum();
    ks.eDamp += energySum[0];
    ks.eSlip += energySum[1];
    ks.maxOverlap = maxOv;
    return count;
}

long EdgeEdgeKind::run(KindStep& s) { return s.friction ? sweep<true>(s) : sweep<false>(s); }

void EdgeEdgeKind::piecesAdded(const PieceContactData& w) {
    const std::size_t ne = w.surface.nEdges();
    stamp_.resize(ne, -2);
    other_.resize(K * ne, -1);
    piece_.resize(K * ne, -1);
    side_.resize(K * ne, 0);
    shear_.resize(3 * K * ne, 0.0);
    ref_.resize(K * ne, 0.0);
}

void EdgeEdgeKind::stateColumns(StateColumns& c) {
    c.add("eeOther", other_, Rows::Edge);
    c.add("eeSide", side_, Rows::Edge);
    c.add("eeShear", shear_, Rows::Edge);
    c.add("eeRef", ref_, Rows::Edge);
    c.add("eeStamp", stamp_, Rows::Edge);
    c.add("eePiece", piece_, Rows::Edge, false);  // saved as a field (older files lack it)
}

void EdgeEdgeKind::saveFields(WorldState& s) const { s.put("eePiece", piece_.data(), piece_.size()); }

void EdgeEdgeKind::checkFields(const WorldState& s) const {
    if (s.fields.count("eePiece") > 0) s.check<int32_t>("eePiece", piece_.size());
}

void EdgeEdgeKind::loadFields(const WorldState& s, const PieceContactData& w) {
    const SurfaceIndex& S = w.surface;
    if (s.fields.count("eePiece") > 0) {
        s.get("eePiece", piece_.data(), piece_.size());
        return;
    }
    for (std::size_t k = 0; k < other_.size(); ++k) {
        const int32_t e = other_[k];
        piece_[k] = e >= 0 ? S.edgePiece[e] : -1;
        if (e >= 0) other_[k] = e - S.pieceEdgeStart[S.edgePiece[e]];
    }
}

}  // namespace qdem
