// Point-polygon contacts: every surface node against the surface triangles
// of the other pieces (seed §3.1), with the rules of doc/contacts.md §3.
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>

#include "../contact/ContactLaw.hpp"
#include "../contact/Geometry.hpp"
#include "../core/Errors.hpp"
#include "../core/ThreadPartials.hpp"
#include "../contact/ContactDetail.hpp"
#include "../contact/PointTriangle.hpp"
#include "../contact/TouchSelection.hpp"
#include "../contact/TriLanesFill.hpp"
#include "../parallel/Domain.hpp"
#include "ContactLoad.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;


// ---------------------------------------------------------------------------
// Point-polygon: every surface node against the surface triangles of the
// other pieces.  One thread per surface node (seed §4.1).

template <bool Friction>
void PieceContactPhase::pointPolygon(double dt, double& eDamp, double& eSlip, long& count, double& maxOv) {
    const SurfaceIndex& S = w_.surface;
    const auto ns = static_cast<int32_t>(w_.surfNodes.size());
    const bool tets = w_.settings.broadPhase != BroadPhase::Triangles;
    const bool interiorFacesToo = w_.settings.broadPhase == BroadPhase::AllTets || w_.settings.broadPhase == BroadPhase::SurfaceTets;
    constexpr int K = PieceContactState::kPP;
    const long stamp = w_.iter;
    long interiorTests = 0, interiorNear = 0, listed = 0;
    const bool regions = w_.settings.pointPolygonRegions;
    const bool regularized = w_.settings.frictionModel == FrictionModel::Regularized;
    const double cosFeature = std::cos(w_.settings.edgeFeatureAngle);
    const double* radius = st_.pieceRadius.data();
    const uint8_t* active = st_.pieceActive.data();
    const int32_t* triPiece = S.triPiece.data();
    const int32_t* listStart = st_.listStart.data();
    const int32_t* listFlat = st_.listFlat.data();
    const int32_t* listCount = st_.listCount.data();
    const int32_t* tri = S.tri.data();
    const double* normal = st_.triNormal.data();
    const double* X = w_.pos.data();
    // (locals, not w_'s references: the loop stores through narrow pointers
    // that may alias anything, which would reload them)
    const int32_t* surfNodes = w_.surfNodes.data();
    const int32_t* nodePiece = w_.nodePiece.data();
    const Domain* dom = w_.domain.built();
    const bool listValid = st_.listValid;
    // (nodes ahead; 2/1, 3/1, 4/2 and 6/3 measured alike, within noise)
    constexpr int32_t kAheadFar = 3, kAheadNear = 1;
    const double* V = w_.vel.data();
    const double* M = w_.mass.data();
    struct Tunnel {
        int32_t node = -1, pa = -1, pb = -1;
        double depth = 0, speed = 0, mass = 0, kn = 0;
    } tunnel;

    ThreadPartials<2> energyParts(omp_get_max_threads());  // damping, slip: added in thread order
#pragma omp parallel reduction(+ : count, interiorTests, interiorNear, listed) reduction(max : maxOv)
    {
        double eDampT = 0, eSlipT = 0;
        double* buf = st_.threadForce[omp_get_thread_num()].data();
        double* load = st_.threadLoad[omp_get_thread_num()].data();
        double* pe = w_.settings.trackEnergy ? w_.threadPieceEnergy[omp_get_thread_num()].data() : nullptr;
        DeepContact& deep = threadDeep_[omp_get_thread_num()];
        CandidateList cl;  // the one candidate policy (PointTriangle.hpp)
        Candidate* const cand = cl.c;
        // The pair law last looked up: consecutive nodes mostly touch the
        // same piece from the same piece (8,748 look-ups, ~60 instructions
        // each, in the 27-cube stack).
        int32_t lastPa = -1, lastPb = -1;
        PairConst lastLaw{};
        TriLanes lanes;
        TriLanesOut near;
        for (int l = 0; l < kTriLanes; ++l)  // a unit triangle in every lane until one is loaded
            for (int d = 0; d < 3; ++d)
                lanes.a[d][l] = 0, lanes.b[d][l] = d == 0, lanes.c[d][l] = d == 1, lanes.n[d][l] = d == 2;
        // Static chunks: a node goes to the same thread every run, so a given
        // thread count gives the same bits (its contacts always land in the same
        // thread buffer).  nowait: the region ends with the loop.
#pragma omp for schedule(static, 64) nowait
        for (int32_t s = 0; s < ns; ++s) {
            const int32_t node = surfNodes[s];
            if (dom && !dom->owns(node)) continue;  // under MPI: the point's owner computes the contact
            const int32_t pa = nodePiece[node];
            if (frozen_[pa]) {  // asleep among sleeping pieces: history kept
                st_.ppStamp[s] = stamp;
                continue;
            }
            // Software prefetch for the nodes ahead.  The loop's hottest
            // stalls were loads that miss: a listed triangle's corners,
            // normal and piece (by its id), then the corners' positions
            // (by those), and in the contacts the corners' velocities and
            // masses.  Far ahead, the triangles' own rows; near (those rows
            // now in cache), the corners' rows and the node's history.
            // (Not from or for a sleeping scene's frozen nodes, which are skipped.)
            if (listValid) {
                const int32_t sa = s + kAheadFar, sb = s + kAheadNear;
                if (sa < ns && listCount[sa] > 0 && !frozen_[nodePiece[surfNodes[sa]]]) {
                    const int32_t* L2 = listFlat + listStart[sa];
                    for (int32_t k = 0; k < listCount[sa]; ++k) {
                        __builtin_prefetch(tri + 3 * L2[k]);
                        __builtin_prefetch(normal + 3 * L2[k]);
                        __builtin_prefetch(triPiece + L2[k]);
                    }
                }
                if (sb < ns && listCount[sb] > 0 && !frozen_[nodePiece[surfNodes[sb]]]) {
                    const int32_t* L1 = listFlat + listStart[sb];
                    for (int32_t k = 0; k < listCount[sb]; ++k) {
                        const int32_t* c = tri + 3 * L1[k];
                        for (int j = 0; j < 3; ++j) {
                            __builtin_prefetch(X + 3 * c[j]);
                            __builtin_prefetch(V + 3 * c[j]);
                            __builtin_prefetch(M + c[j]);
                        }
                    }
                    __builtin_prefetch(&st_.ppKey[K * sb]);
                    __builtin_prefetch(&st_.ppPiece[K * sb]);
                    __builtin_prefetch(&st_.ppShear[3 * K * sb]);
                    __builtin_prefetch(&st_.ppRef[K * sb]);
                }
            }
            int32_t* key = &st_.ppKey[K * s];
            int32_t* kpiece = &st_.ppPiece[K * s];
            double* shear = &st_.ppShear[3 * K * s];
            double* ref = &st_.ppRef[K * s];
            const bool watched = st_.ppStamp[s] == stamp - 1;
            if (!watched)  // history is only valid from the previous step
                for (int k = 0; k < K; ++k) key[k] = -1;
            st_.ppStamp[s] = stamp;
            const bool useList = st_.listValid && listCount[s] >= 0;
            if (!active[pa] || (useList && listCount[s] == 0 && key[0] < 0)) {
                // Nothing can touch this node: its slots are empty (slots
                // after the first empty one are empty too).  A node with a
                // contact carried from the last step goes on: it may be deep
                // behind that face, beyond the list's range (side memory below).
                if (key[0] >= 0)
                    for (int k = 0; k < K; ++k) key[k] = -1;
                continue;
            }
            const Material& ma = w_.materials[w_.pieces[pa].material];
            // The law's constants of this node's piece with piece pb.
            auto lawOf = [&](int32_t pb) -> PairConst {
                if (pa == lastPa && pb == lastPb) return lastLaw;
                lastPa = pa, lastPb = pb;
                for (int32_t q = st_.nbrStart[pa]; q < st_.nbrStart[pa + 1]; ++q)
                    if (st_.nbrs[q] == pb) return lastLaw = st_.nbrLaw[q];
                return lastLaw = pairConst(ma, w_.materials[w_.pieces[pb].material]);  // listed before the pieces parted
            };
            const Vector3d A = at(X, node);
            cl.clear();
            int& nc = cl.n;
            bool& anyBehind = cl.anyBehind;
            // Candidate triangles: bounding sphere grown by the reach holds the
            // node, and the node is within reach in front of its plane (or
            // behind it: possibly inside that piece).
            auto consider = [&](int32_t t, double reach) {
                const int32_t* c = &S.tri[3 * t];
                cl.consider(A, t, at(X, c[0]), at(X, c[1]), at(X, c[2]),
                            Eigen::Map<const Vector3d>(&st_.triNormal[3 * t]), reach, regions);
            };
            if (useList) {
                // The same tests as consider(), the closest points of
                // kTriLanes listed triangles at a time (SIMD lane code).
                const int32_t* L = listFlat + listStart[s];
                const int32_t n = listCount[s];
                listed += n;
                for (int32_t k0 = 0; k0 < n; k0 += kTriLanes) {
                    const int cnt = std::min<int32_t>(kTriLanes, n - k0);
                    // Lanes past cnt keep the triangles last loaded (a whole
                    // triangle each, so finite numbers); their results are
                    // not read.  (A quarter of the lanes here.)
                    int l0 = 0;
                    for (; l0 + 4 <= cnt; l0 += 4) fillTriLanes4(X, tri, normal, L + k0 + l0, l0 / 4, lanes);
                    for (int l = l0; l < cnt; ++l) {
                        const int32_t t = L[k0 + l];
                        const int32_t* c = tri + 3 * t;
                        for (int d = 0; d < 3; ++d) {
                            lanes.a[d][l] = X[3 * c[0] + d];
                            lanes.b[d][l] = X[3 * c[1] + d];
                            lanes.c[d][l] = X[3 * c[2] + d];
                            lanes.n[d][l] = normal[3 * t + d];
                        }
                    }
                    closestOnTriangles(A.data(), lanes, near);
                    alignas(64) int32_t snapped[kTriLanes];  // the features as candidates carry them
#pragma omp simd
                    for (int l = 0; l < kTriLanes; ++l)
                        snapped[l] = snappedFeature(near.w[0][l], near.w[1][l], near.w[2][l], near.feature[l]);
                    for (int l = 0; l < cnt; ++l) {
                        const int32_t t = L[k0 + l];
                        const int32_t pb = triPiece[t];
                        if (!active[pb]) continue;
                        const double reach = ma.radius + radius[pb];
                        const double h = near.h[l];
                        if (h > reach) continue;
                        const double dist = std::sqrt(near.dist2[l]);
                        if (!regions && dist - std::abs(h) > 1e-9 * reach) continue;  // seed's inside test
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
            for (int32_t q = st_.nbrStart[pa]; q < st_.nbrStart[pa + 1] && !useList; ++q) {
                const int32_t pb = st_.nbrs[q];
                const double reach = ma.radius + radius[pb];
                {
                    const Vector3d lo = A.array() - reach, hi = A.array() + reach;
                    bool overlap = true;
                    for (int d = 0; d < 3 && overlap; ++d)
                        overlap = lo[d] <= w_.bounds.hi[3 * pb + d] && w_.bounds.lo[3 * pb + d] <= hi[d];
                    if (!overlap) continue;
                }
                const int32_t i0 = st_.itemStart[pb];
                // Items that can reach the node have their reference point within
                // (largest radius + reach) of it: visit the cells of that box only.
                const Vector3d qlo = A.array() - st_.itemReach, qhi = A.array() + st_.itemReach;
                st_.itemGrid[pb].forRange(qlo.data(), qhi.data(), [&](int32_t local) {
                    const int32_t it = i0 + local;
                    // (grown by the skin: the cells may date from the last list rebuild)
                    const double R = st_.itemRadius[it] + reach + (st_.listValid ? st_.listSkin : 0.0);
                    if ((A - Eigen::Map<const Vector3d>(&st_.itemPoint[3 * it])).squaredNorm() > R * R) return;
                    const int32_t id = st_.items[it];
                    if (!tets) {
                        consider(id, reach);
                        return;
                    }
                    for (int k = 0; k < 4; ++k) {
                        const int32_t t = S.tetFaceTri[4 * id + k];
                        if (t >= 0) {
                            consider(t, reach);
                        } else if (interiorFacesToo) {
                            // Cases A and B test interior faces too (and find them
                            // irrelevant): the cost the seed's Figure 6 measures.
                            int32_t f[3], n = 0;
                            for (int j = 0; j < 4; ++j)
                                if (j != k) f[n++] = w_.tetNodes[4 * id + j];
                            const TriPoint cp = closestOnTriangle(A, at(X, f[0]), at(X, f[1]), at(X, f[2]));
                            ++interiorTests;
                            if ((A - cp.point).norm() < reach) ++interiorNear;
                        }
                    }
                });
            }
            // Side memory (issue 12): a contact carried from the last step keeps
            // its triangle while the node stays behind that face, however deep.
            // The search only reaches the triangle's bounding sphere grown by
            // the reach (and skin): a fast impact pushed nodes deeper than that
            // (29 mm for 33 mm triangles), the contact was lost and two cubes
            // at 25 m/s passed through each other (doc/hard_cases.md).
            if (watched)
                for (int k = 0; k < K && key[k] >= 0; ++k) {
                    const int32_t t = S.pieceTriStart[kpiece[k]] + historyTri(key[k]);
                    bool found = false;
                    for (int i = 0; i < nc && !found; ++i) found = cand[i].tri == t;
                    if (found || !active[triPiece[t]]) continue;
                    const int32_t* c = tri + 3 * t;
                    const Vector3d a = at(X, c[0]);
                    if ((A - a).dot(Eigen::Map<const Vector3d>(normal + 3 * t)) >= 0) continue;  // in front: ends as usual
                    const TriPoint cp = closestOnTriangle(A, a, at(X, c[1]), at(X, c[2]));
                    const double dist = (A - cp.point).norm();
                    const double h = (A - a).dot(Eigen::Map<const Vector3d>(normal + 3 * t));
                    // Behind the plane and at most a reach beside the triangle
                    // (its neighbours, folded by the impact, may hold the node's
                    // projection now): still the face it went in through.
                    const double reachT = ma.radius + radius[triPiece[t]];
                    if (dist * dist - h * h > reachT * reachT) continue;
                    cl.add(Candidate{t, cp, dist, true});
                }
            // Inside test for behind candidates (rare: deep penetration): the
            // node is inside a piece only if no front-facing point of that
            // piece's surface is nearer.  An outside point's nearest surface
            // point faces it and is strictly nearer than any point of a face
            // seen from behind.
            bool keep[kCandidates];
            for (int i = 0; i < nc; ++i) keep[i] = true;
            if (anyBehind)
                for (int i = 0; i < nc; ++i) {
                    if (!cand[i].behind) continue;
                    const int32_t pb = S.triPiece[cand[i].tri];
                    const double db = cand[i].dist;
                    const int32_t i0 = st_.itemStart[pb];
                    const Vector3d qlo = A.array() - st_.itemReach, qhi = A.array() + st_.itemReach;
                    int32_t killedBy = -1;  // the front face found nearer
                    auto witness = [&](int32_t id) {
                        if (!keep[i]) return;
                        for (int k = 0; k < (tets ? 4 : 1); ++k) {
                            const int32_t t = tets ? S.tetFaceTri[4 * id + k] : id;
                            if (t < 0) continue;
                            const int32_t* c = &S.tri[3 * t];
                            if (frontFaceNearer(A, at(X, c[0]), at(X, c[1]), at(X, c[2]),
                                                Eigen::Map<const Vector3d>(&st_.triNormal[3 * t]), db)) {
                                keep[i] = false;
                                killedBy = t;
                            }
                        }
                    };
                    if (useList) {
                        const int32_t* L = listFlat + listStart[s];
                        for (int k = 0; k < listCount[s]; ++k)
                            if (triPiece[L[k]] == pb) witness(L[k]);
                    } else {
                        st_.itemGrid[pb].forRange(qlo.data(), qhi.data(),
                                                  [&](int32_t local) { witness(st_.items[i0 + local]); });
                    }
                    // Side memory (issue 12): a contact carried from the last step
                    // whose node is still behind its face came from the front - the
                    // node went in through that face - and keeps pushing it back out,
                    // whatever nearer face the other piece's own deformation (faces
                    // folded by a deep impact) now shows it.  Only the far side of the
                    // piece (a face facing back across it) ends it: the node then
                    // crossed the middle, the law did not stop the impact, and the
                    // run stops (below) rather than push the node on through.
                    if (!keep[i] && watched) {
                        bool carried = false;
                        for (int k = 0; k < K && key[k] >= 0; ++k)
                            carried = carried ||
                                      (kpiece[k] == pb && S.pieceTriStart[pb] + historyTri(key[k]) == cand[i].tri);
                        const bool farSide = killedBy >= 0 && Eigen::Map<const Vector3d>(normal + 3 * killedBy)
                                                                      .dot(Eigen::Map<const Vector3d>(
                                                                          normal + 3 * cand[i].tri)) < -0.5;
                        if (carried && !farSide) {
                            keep[i] = true;
                        } else if (carried && db > ma.radius + radius[pb]) {
                            double mT;
                            Vector3d vT;
                            trianglePointState(cand[i], tri + 3 * cand[i].tri, w_.mass, w_.vel, mT, vT);
                            const double speed = (at(w_.vel, node) - vT).norm();
#pragma omp critical(qdemTunnel)
                            if (tunnel.node < 0) tunnel = Tunnel{node, pa, pb, db, speed, w_.mass[node], lawOf(pb).kn};
                        }
                    }
                }

            if (startPending_)  // set-up check (PieceStartOverlap.cpp): a node centre inside another piece
                for (int i = 0; i < nc; ++i) {
                    if (!keep[i] || !cand[i].behind) continue;
                    const int32_t pb = triPiece[cand[i].tri];
                    if (startChecked_[pa] && startChecked_[pb]) continue;
                    auto& seen = threadStartSeen_[omp_get_thread_num()];
                    const std::pair<int32_t, int32_t> ab{std::min(pa, pb), std::max(pa, pb)};
                    if (seen.empty() || seen.back() != ab) seen.push_back(ab);
                }
            const double eps = 1e-12 * ma.radius;
            const uint32_t touches = selectTouches(A, cand, nc, keep, triPiece, eps, cosFeature);

            int32_t newKey[K], newPiece[K];
            Vector3d newShear[K];
            double newRef[K];
            bool usedOld[K] = {false, false, false, false, false, false};
            // History slots of the touches, in order, then what touches that
            // ended while pressing hand over (TouchSelection.hpp).
            int slotOf[kCandidates];
            int nTouch = 0;
            for (uint32_t m = touches; m && nTouch < K; m &= m - 1, ++nTouch) {
                const int i = std::countr_zero(m);
                const int32_t pb = triPiece[cand[i].tri];
                slotOf[i] = historySlot(key, kpiece, usedOld, K,
                                        historyKey(cand[i].tri - S.pieceTriStart[pb], cand[i].cp.feature), pb, cand,
                                        keep, nc, triPiece, S.pieceTriStart.data());
                if (slotOf[i] >= 0) usedOld[slotOf[i]] = true;
            }
            double handed[kCandidates];
            bool anyHanded = false;
            if (watched && key[0] >= 0) {
                bool ended = false;
                for (int k = 0; k < K; ++k) ended = ended || (key[k] >= 0 && !usedOld[k]);
                if (ended) {
                    for (int i = 0; i < nc; ++i) handed[i] = 0.0;
                    anyHanded = handOver(A, cand, nc, keep, triPiece, S.pieceTriStart.data(), key, kpiece, ref, usedOld,
                                         K, eps, [&](int32_t pb) { return lawOf(pb).reach; }, handed);
                }
            }
            int nNew = 0;
            Vector3d fA = Vector3d::Zero();
            for (uint32_t m = touches; m && nNew < K; m &= m - 1) {  // the kept candidates in order
                const int i = std::countr_zero(m);
                const Candidate& c = cand[i];

                const int32_t* tn = &S.tri[3 * c.tri];
                const int32_t pb = triPiece[c.tri];
                double mT;
                Vector3d vT;
                trianglePointState(c, tn, w_.mass, w_.vel, mT, vT);
                const PairLaw law = pairLaw(lawOf(pb), w_.mass[node], mT);
                const Vector3d nT(st_.triNormal[3 * c.tri], st_.triNormal[3 * c.tri + 1], st_.triNormal[3 * c.tri + 2]);
                Vector3d n;
                double overlap;
                candidateContact(c, A, nT, law.reach, eps, n, overlap);
                // Tangential history: same surface feature, else inherited from
                // a contact with the same piece that ended this step (a node
                // sliding onto the next triangle keeps its spring).
                const int32_t kk = historyKey(c.tri - S.pieceTriStart[pb], c.cp.feature);
                const int slot = slotOf[i];
                Vector3d sh = Vector3d::Zero();
                if (slot >= 0) {
                    sh = Vector3d(shear[3 * slot], shear[3 * slot + 1], shear[3 * slot + 2]);
                }
                const double w = w_.surfWeight[s], sw = std::sqrt(w);  // the query node's area weight
                const ContactParams cp{w * law.kn, sw * law.cn, w * law.kt, sw * law.ct, law.mu, w_.settings.frictionRegVelocity,
                                       w_.mass[node] * mT / (w_.mass[node] + mT)};
                const Vector3d vRel = at(w_.vel, node) - vT;
                // A touch that splits off one with the same piece starts from zero
                // force (threshold 0, TouchSelection.hpp); one missed by the
                // detection from its present overlap (threshold the reach).
                const bool split = slot < 0 && touchedPiece(key, kpiece, K, pb);
                double r0 = bornDeepRef(slot >= 0, slot >= 0 ? ref[slot] : 0.0, watched, overlap,
                                        split ? 0.0 : law.reach, vRel.dot(n), dt);
                if (anyHanded && handed[i] > 0) r0 = handOverRef(overlap, r0, handed[i]);
                // The spring turns with the contact about n at the mean spin
                // of its two sides: the node's own, and the triangle's at the
                // contact point, interpolated from its corners' (surface spins
                // continuous over the surface: SurfaceSpin.hpp, doc/formulation.md
                // "Twist").
                double spin = 0;
                if (Friction && law.mu > 0 && !regularized) {
                    const double* om = st_.surfSpin.data();
                    Vector3d wSum = at(om, s);
                    for (int k = 0; k < 3; ++k) wSum += c.cp.w[k] * at(om, S.surfIndexOfNode[tn[k]]);
                    spin = 0.5 * wSum.dot(n);
                }
                const ContactResult r =
                    lawForce(Friction && law.mu > 0, regularized, cp, n, overlap - r0, vRel, dt, sh, spin);
                // How deep the node is behind pb's surface (overlap - reach:
                // > 0 behind it), against the reach: the per-step check.
                noteDepth(deep, overlap - law.reach, law.reach, vRel.dot(n), node, pa, pb, false);
                if (startPending_ && !(startChecked_[pa] && startChecked_[pb]))
                    notePress(pa, pb, r.elastic, overlap);  // placed pressed in: the start warning's energy
                newKey[nNew] = kk;
                newPiece[nNew] = pb;
                newShear[nNew] = sh;
                newRef[nNew] = r0;
                ++nNew;
                fA += r.force;
                // (the tangential spring and dashpot act with the spring law only)
                const bool tangential = Friction && law.mu > 0 && !regularized;
                // (theta = m_node / m_T: ContactLoad.hpp)
                const double mSum = w_.mass[node] + mT;
                addContactLoad(load, s, 0.5 * mSum / mT, cp, tangential);  // (adds 2 x share)
                for (int k = 0; k < 3; ++k)
                    if (c.cp.w[k] != 0) {
                        addTo(buf, S.surfIndexOfNode[tn[k]], -c.cp.w[k] * r.force);
                        addContactLoad(load, S.surfIndexOfNode[tn[k]], 0.5 * c.cp.w[k] * mSum / w_.mass[node], cp,
                                       tangential);
                    }
                if (pe) pe[3 * pa + 2] += r.elastic;
                eDampT += r.dampPower * dt;
                eSlipT += r.slipWork;
                ++count;
                maxOv = std::max(maxOv, overlap);
            }
            addTo(buf, s, fA);
            for (int k = 0; k < K; ++k) {
                key[k] = k < nNew ? newKey[k] : -1;
                kpiece[k] = k < nNew ? newPiece[k] : -1;
                ref[k] = k < nNew ? newRef[k] : 0.0;
                if (k < nNew)
                    for (int d = 0; d < 3; ++d) shear[3 * k + d] = newShear[k][d];
            }
        }
        energyParts.set(omp_get_thread_num(), {eDampT, eSlipT});
    }
    const std::array<double, 2> energySum = energyParts.sum();
    eDamp += energySum[0];
    eSlip += energySum[1];
    listedTriangles_ = listed;
    interiorFaceTests_ = interiorTests;
    interiorFaceNear_ = interiorNear;
    if (tunnel.node >= 0) {
        // Stopping distance of a node of mass m at speed v on a spring kn:
        // v sqrt(m / kn) (doc/hard_cases.md, "Tunnelling").
        const double stop = tunnel.speed * std::sqrt(tunnel.mass / tunnel.kn);
        std::ostringstream m;
        m.precision(3);
        m << "QDEM: piece " << tunnel.pa << " went through piece " << tunnel.pb << " at step " << w_.iter << ": node "
          << tunnel.node << " is " << tunnel.depth << " m behind a face of piece " << tunnel.pb
          << " and past its middle, at a relative speed of " << tunnel.speed
          << " m/s. The contact is too soft to stop this impact: stopping distance v sqrt(m_node/kn) = " << stop
          << " m (node mass " << tunnel.mass << " kg, kn " << tunnel.kn
          << " N/m) against the piece's half thickness. Make the contact stiffer (kn = E r: a larger QdemMat young "
             "or radius; 4x kn halves the stopping distance), the impact slower or the pieces thicker";
        throw StabilityError(m.str());
    }
}

template void PieceContactPhase::pointPolygon<true>(double, double&, double&, long&, double&);
template void PieceContactPhase::pointPolygon<false>(double, double&, double&, long&, double&);

}  // namespace qdem
