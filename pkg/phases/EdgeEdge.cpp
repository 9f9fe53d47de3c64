// Edge-edge contacts between feature edges of different pieces (seed §3.2),
// with the fades and side memory of doc/contacts.md §4.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../contact/Geometry.hpp"
#include "../contact/ContactDetail.hpp"
#include "../core/ThreadPartials.hpp"
#include "../parallel/Domain.hpp"
#include "ContactLoad.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;
// Gradient of an edge-edge contact's stiffness weight
//   W = fade^2 endS endT aw,  fade = min(1, sin2 / sinFade2),
//   endS = min(1, min(s, 1 - s) len1 / reach), endT alike,
//   aw = aw(s, t) linear (daws, dawt: its slopes in s and t)
// with respect to the ends p1, q1, p2, q2 (out, in that order), for closest
// points inside both segments.  s and t move with the ends as the solution of
// (c1 - c2).e1 = 0, (c1 - c2).e2 = 0 (implicit differentiation).
static void weightGradient(const Vector3d& p1, const Vector3d& q1, const Vector3d& p2, const Vector3d& q2,
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

// ---------------------------------------------------------------------------
// Edge-edge: surface edges of different pieces whose closest points are
// inside both edges (ends are point-polygon's business).  One thread per
// edge; each pair is handled by its lower edge id.

template <bool Friction>
void PieceContactPhase::edgeEdge(double dt, double& eDamp, double& eSlip, long& count, double& maxOv) {
    const SurfaceIndex& S = w_.surface;
    const int32_t ne = st_.registeredEdges();
    constexpr int K = PieceContactState::kEE;
    const double sinFade2 = std::pow(std::sin(w_.settings.edgeFadeAngle), 2);
    const long stamp = w_.iter;
    const bool regularized = w_.settings.frictionModel == FrictionModel::Regularized;
    const Domain* dom = w_.domain.built();
    // (locals, not w_'s references: the loop stores through int8_t pointers
    // that may alias anything, which would reload them)
    const double* X = w_.pos.data();
    const double* V = w_.vel.data();
    const double* M = w_.mass.data();
    const bool listValid = st_.listValid;
    const int32_t* edgeItems = st_.edgeItems.data();
    const int32_t* edgeList = st_.edgeList.data();
    const int32_t* edgeListCount = st_.edgeListCount.data();
    const int32_t* edgeRec = st_.edgeRec.data();
    constexpr int KE = PieceContactState::kEdgeList, kER = PieceContactState::kEdgeRec;
    constexpr int32_t kAheadFar = 4, kAheadNear = 2;

    // The energies are summed per thread and the threads' parts added in
    // thread order, then into the running total (ThreadPartials.hpp): the
    // ledger's last bits do not depend on which thread ends first.
    ThreadPartials<2> energyParts(omp_get_max_threads());
#pragma omp parallel reduction(+ : count) reduction(max : maxOv)
    {
        double dampHere = 0, slipHere = 0;
        double* buf = st_.threadForce[omp_get_thread_num()].data();
        double* load = st_.threadLoad[omp_get_thread_num()].data();
        double* pe = w_.settings.trackEnergy ? w_.threadPieceEnergy[omp_get_thread_num()].data() : nullptr;
        DeepContact& deep = threadDeep_[omp_get_thread_num()];
        // Static chunks: a node goes to the same thread every run, so a given
        // thread count gives the same bits (its contacts always land in the same
        // thread buffer).  nowait: the region ends with the loop.
#pragma omp for schedule(static, 64) nowait
        for (int32_t ie = 0; ie < ne; ++ie) {
            const int32_t e = st_.edgeItems[ie];
            const int32_t pa = S.edgePiece[e];
            if (frozen_[pa]) {  // asleep among sleeping pieces: history kept
                st_.eeStamp[e] = stamp;
                continue;
            }
            // Software prefetch, as in point-polygon: the edges ahead are
            // scattered over the surface's arrays (history by global edge
            // id, the listed edges' records and end positions), and their
            // loads were this loop's stalls.  Far ahead: the edge's history
            // and ends, its listed edges' records; nearer: their positions.
            if (listValid) {
                // (not for a sleeping scene's frozen edges, which are skipped)
                const int32_t jf = ie + kAheadFar, jn = ie + kAheadNear;
                const int32_t ef = jf < ne ? edgeItems[jf] : -1;
                if (ef >= 0 && edgeListCount[jf] > 0 && !frozen_[S.edgePiece[ef]]) {
                    __builtin_prefetch(&st_.eeStamp[ef]);
                    __builtin_prefetch(&st_.eeOther[K * ef]);
                    __builtin_prefetch(&st_.eePiece[K * ef]);
                    __builtin_prefetch(&S.edge[2 * ef]);
                    const int32_t* L = edgeList + static_cast<std::size_t>(KE) * jf;
                    for (int k = 0; k < edgeListCount[jf]; ++k) __builtin_prefetch(edgeRec + kER * L[k]);
                }
                const int32_t en = jn < ne ? edgeItems[jn] : -1;
                if (en >= 0 && edgeListCount[jn] > 0 && !frozen_[S.edgePiece[en]]) {
                    __builtin_prefetch(X + 3 * S.edge[2 * en]);
                    __builtin_prefetch(X + 3 * S.edge[2 * en + 1]);
                    const int32_t* L = edgeList + static_cast<std::size_t>(KE) * jn;
                    for (int k = 0; k < edgeListCount[jn]; ++k) {
                        __builtin_prefetch(X + 3 * edgeRec[kER * L[k]]);
                        __builtin_prefetch(X + 3 * edgeRec[kER * L[k] + 1]);
                    }
                }
            }
            int32_t* other = &st_.eeOther[K * e];        // the other edge: local id in its piece
            int32_t* otherPiece = &st_.eePiece[K * e];   // and that piece
            int8_t* side = &st_.eeSide[K * e];
            double* shear = &st_.eeShear[3 * K * e];
            double* ref = &st_.eeRef[K * e];
            const bool watched = st_.eeStamp[e] == stamp - 1;
            if (!watched)  // history is only valid from the previous step
                for (int k = 0; k < K; ++k) other[k] = -1, otherPiece[k] = -1, side[k] = 0, ref[k] = 0.0;
            st_.eeStamp[e] = stamp;
            const Material& ma = w_.materials[w_.pieces[pa].material];
            const int32_t a0 = S.edge[2 * e], a1 = S.edge[2 * e + 1];
            const Vector3d p1 = at(X, a0), q1 = at(X, a1);
            const double len1 = (q1 - p1).norm();
            int32_t newOther[K], newOtherPiece[K];
            int8_t newSide[K];
            Vector3d newShear[K];
            double newRef[K];
            int nNew = 0;
            // One pair of edges: je indexes the registered edges.
            auto pair = [&](int32_t je) {
                    if (nNew == K) return;
                    const int32_t* rec = &st_.edgeRec[PieceContactState::kEdgeRec * je];
                    const int32_t pb = rec[2];
                    if (!st_.pieceActive[pb]) return;
                    const Material& mb = w_.materials[w_.pieces[pb].material];
                    const double reach = ma.radius + mb.radius;
                    const int32_t b0 = rec[0], b1 = rec[1];
                    // Under MPI one rank computes the pair: the owner of the lower
                    // node of this edge, the one whose slots keep the pair's history
                    // (so a history row has one owner: Domain::rebalance).
                    if (dom && dom->owner(std::min(a0, a1)) != dom->rank()) return;
                    const Vector3d p2 = at(X, b0), q2 = at(X, b1);
                    const SegPoints sp = closestSegmentSegment(p1, q1, p2, q2);
                    constexpr double kEnd = 1e-9;
                    if (sp.s <= kEnd || sp.s >= 1 - kEnd || sp.t <= kEnd || sp.t >= 1 - kEnd) return;
                    // Fade out towards parallel edges: the seed's formula is
                    // singular there; their end nodes' point-polygon contacts
                    // take over.  (Also keeps the side test below away from the
                    // rounding noise of a near-zero cross product.)  And fade
                    // towards the ends of either edge: within one contact reach
                    // of an end node, that node's point-polygon contact covers
                    // the touch, and the hand-over must be continuous.
                    const double fade = std::min(1.0, sp.sin2 / sinFade2);
                    const double endS = std::min(1.0, std::min(sp.s, 1 - sp.s) * len1 / reach);
                    const double endT = std::min(1.0, std::min(sp.t, 1 - sp.t) * (q2 - p2).norm() / reach);
                    const double w = fade * fade * endS * endT;
                    if (w < 1e-6) return;
                    const Vector3d cross = (q1 - p1).cross(q2 - p2);
                    const double cn = cross.norm();
                    const Vector3d d = sp.c1 - sp.c2;
                    const double dist = d.norm();
                    int slot = -1;
                    const int32_t local2 = rec[3];  // history by stable id (the edge's id in its piece)
                    for (int k = 0; k < K; ++k)
                        if (other[k] == local2 && otherPiece[k] == pb) slot = k;
                    // Which side of edge 2 edge 1 is on, along the common normal;
                    // remembered so that edges pushed through each other are
                    // pushed back, not let through.
                    int sNow = d.dot(cross) < 0 ? -1 : 1;
                    if (dist <= 1e-12 * reach && slot < 0) {  // touching at first sight: ask the piece centres
                        const Vector3d ca = 0.5 * (Eigen::Map<const Vector3d>(&w_.bounds.lo[3 * pa]) +
                                                   Eigen::Map<const Vector3d>(&w_.bounds.hi[3 * pa]));
                        const Vector3d cb = 0.5 * (Eigen::Map<const Vector3d>(&w_.bounds.lo[3 * pb]) +
                                                   Eigen::Map<const Vector3d>(&w_.bounds.hi[3 * pb]));
                        sNow = (ca - cb).dot(cross) < 0 ? -1 : 1;
                    }
                    const int sUse = slot >= 0 && side[slot] != 0 ? side[slot] : sNow;
                    double overlap;
                    Vector3d n;
                    if (sUse == sNow && dist > 1e-12 * reach) {
                        n = d / dist;
                        overlap = reach - dist;
                    } else {
                        n = double(sUse) * cross / cn;
                        overlap = reach + dist;
                    }
                    if (overlap <= 0) return;
                    const double m1 = (1 - sp.s) * M[a0] + sp.s * M[a1];
                    const double m2 = (1 - sp.t) * M[b0] + sp.t * M[b1];
                    const PairLaw law = pairLaw(ma, mb, m1, m2);
                    const Vector3d vRel = ((1 - sp.s) * at(V, a0) + sp.s * at(V, a1)) -
                                          ((1 - sp.t) * at(V, b0) + sp.t * at(V, b1));
                    Vector3d sh = Vector3d::Zero();
                    // Area weight (doc/contacts.md, "Area weights"): the mean of
                    // the two crossing points' weights, each interpolated along
                    // its edge, so it varies continuously as the crossing slides
                    // and meets the end node's point-polygon weight at the ends.
                    const double* sw = w_.surfWeight.data();
                    const double aw = 0.5 * ((1 - sp.s) * sw[S.surfIndexOfNode[a0]] + sp.s * sw[S.surfIndexOfNode[a1]] +
                                             (1 - sp.t) * sw[S.surfIndexOfNode[b0]] + sp.t * sw[S.surfIndexOfNode[b1]]);
                    const double saw = std::sqrt(aw);
                    if (slot >= 0) {
                        sh = Vector3d(shear[3 * slot], shear[3 * slot + 1], shear[3 * slot + 2]);
                        if (!regularized) sh /= std::sqrt(w * aw);  // (stored times sqrt(w aw), below)
                    }
                    const ContactParams cp{w * aw * law.kn, w * saw * law.cn, w * aw * law.kt, w * saw * law.ct, law.mu,
                                           w_.settings.frictionRegVelocity, m1 * m2 / (m1 + m2)};
                    // Born deep (doc/contacts.md §5), with the edge-edge
                    // threshold: a crossing is made at the reach, so a new
                    // pair deeper than this step's approach did not come by
                    // an approach but by its closest points entering both
                    // edges' interiors at depth -- typically the crossing
                    // jumping from one segment of a bent ridge to the next,
                    // where the end fades differ.  Born with its full spring
                    // it brought 1/2 kn w aw delta^2 from nowhere (+13 % at
                    // 30 degrees, test_crossed_bars_conserve_energy).
                    const double r0 = bornDeepRef(slot >= 0, slot >= 0 ? ref[slot] : 0.0, watched, overlap, 0.0,
                                                  vRel.dot(n), dt);
                    // Turned at the mean spin of the two edges at their
                    // crossing points, each interpolated along its edge
                    // (doc/formulation.md, "Twist").
                    double spin = 0;
                    if (Friction && law.mu > 0 && !regularized) {
                        const double* om = st_.surfSpin.data();
                        const int32_t* si = S.surfIndexOfNode.data();
                        spin = 0.5 * ((1 - sp.s) * at(om, si[a0]) + sp.s * at(om, si[a1]) + (1 - sp.t) * at(om, si[b0]) +
                                      sp.t * at(om, si[b1]))
                                         .dot(n);
                    }
                    const ContactResult r =
                        lawForce(Friction && law.mu > 0, regularized, cp, n, overlap - r0, vRel, dt, sh, spin);
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
                        weightGradient(p1, q1, p2, q2, sp, reach, sinFade2, fade, endS, endT, aw,
                                       0.5 * (sw[S.surfIndexOfNode[a1]] - sw[S.surfIndexOfNode[a0]]),
                                       0.5 * (sw[S.surfIndexOfNode[b1]] - sw[S.surfIndexOfNode[b0]]), fw);
                        const double c = -0.5 * law.kn * del * del;
                        for (auto& f : fw) f *= c;
                    }
                    newOther[nNew] = local2;
                    newOtherPiece[nNew] = pb;
                    newSide[nNew] = static_cast<int8_t>(sUse);
                    // Kept as sqrt(w aw) times the elongation: carried to a
                    // step where the weight differs, the spring keeps the energy
                    // it stored, 1/2 kt w aw |shear|^2, instead of gaining or
                    // losing 1/2 kt d(w aw) |shear|^2 unbooked.
                    newShear[nNew] = regularized ? sh : Vector3d(sh * std::sqrt(w * aw));
                    newRef[nNew] = r0;
                    ++nNew;
                    addTo(buf, S.surfIndexOfNode[a0], (1 - sp.s) * r.force + fw[0]);
                    addTo(buf, S.surfIndexOfNode[a1], sp.s * r.force + fw[1]);
                    addTo(buf, S.surfIndexOfNode[b0], -(1 - sp.t) * r.force + fw[2]);
                    addTo(buf, S.surfIndexOfNode[b1], -sp.t * r.force + fw[3]);
                    {
                        const bool tangential = Friction && law.mu > 0 && !regularized;
                        const double ra = 0.5 * (m1 + m2) / m2, rb = 0.5 * (m1 + m2) / m1;  // (1 + theta, 1 + 1/theta) / 2
                        addContactLoad(load, S.surfIndexOfNode[a0], (1 - sp.s) * ra, cp, tangential);
                        addContactLoad(load, S.surfIndexOfNode[a1], sp.s * ra, cp, tangential);
                        addContactLoad(load, S.surfIndexOfNode[b0], (1 - sp.t) * rb, cp, tangential);
                        addContactLoad(load, S.surfIndexOfNode[b1], sp.t * rb, cp, tangential);
                    }
                    if (pe) pe[3 * pa + 2] += r.elastic;
                    // Edges crossed (overlap past the reach): how far behind
                    // the other edge, against the reach (the per-step check).
                    noteDepth(deep, overlap - reach, reach, vRel.dot(n), a0, pa, pb, true);
                    dampHere += r.dampPower * dt;
                    slipHere += r.slipWork;
                    ++count;
                    maxOv = std::max(maxOv, overlap);
            };
            // Each pair of pieces once: edges of the lower piece id meet the
            // higher piece's edges, from the list made at the last rebuild or
            // from the cells.
            if (st_.listValid && st_.edgeListCount[ie] >= 0) {
                const int32_t* L = &st_.edgeList[static_cast<std::size_t>(PieceContactState::kEdgeList) * ie];
                for (int k = 0; k < st_.edgeListCount[ie]; ++k) pair(L[k]);
            } else {
                for (int32_t q = st_.nbrStart[pa]; q < st_.nbrStart[pa + 1]; ++q) {
                    const int32_t pb = st_.nbrs[q];
                    if (pb < pa) continue;
                    const double* lo = &st_.edgeLo[3 * ie];
                    const double* hi = &st_.edgeHi[3 * ie];
                    bool overlap = true;  // the edge's box must reach the other piece's box
                    for (int d = 0; d < 3 && overlap; ++d)
                        overlap = lo[d] <= w_.bounds.hi[3 * pb + d] && w_.bounds.lo[3 * pb + d] <= hi[d];
                    if (!overlap) continue;
                    const int32_t j0 = st_.edgeStart[pb];
                    st_.edgeGrid[pb].forOverlapping(lo, hi, [&](int32_t local) { pair(j0 + local); });
                }
            }
            if (nNew == 0 && other[0] < 0) continue;  // no touch, none before (slots fill from 0): nothing to store
            for (int k = 0; k < K; ++k) {
                other[k] = k < nNew ? newOther[k] : -1;
                otherPiece[k] = k < nNew ? newOtherPiece[k] : -1;
                side[k] = k < nNew ? newSide[k] : 0;
                ref[k] = k < nNew ? newRef[k] : 0.0;
                if (k < nNew)
                    for (int d = 0; d < 3; ++d) shear[3 * k + d] = newShear[k][d];
            }
        }
        energyParts.set(omp_get_thread_num(), {dampHere, slipHere});
    }
    const std::array<double, 2> energySum = energyParts.sum();
    eDamp += energySum[0];
    eSlip += energySum[1];
}

template void PieceContactPhase::edgeEdge<true>(double, double&, double&, long&, double&);
template void PieceContactPhase::edgeEdge<false>(double, double&, double&, long&, double&);

}  // namespace qdem
