// Piece-piece surface contacts (seed paper §3-4): which pieces can touch,
// registration in cell lists, Verlet lists, and the phase driver.  The two
// contact kinds are in PointPolygon.cpp and EdgeEdge.cpp.  Derivations and
// the rules that keep forces continuous: doc/contacts.md.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../contact/Geometry.hpp"
#include "ContactDetail.hpp"
#include "World.hpp"

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;

void World::updatePieceBounds(bool all) {
    const std::size_t np = pieces.size();
    pc_.pieceLo.resize(3 * np);
    pc_.pieceHi.resize(3 * np);
    for (std::size_t ip = 0; ip < np; ++ip) {
        if (asleep_[ip] && !all) continue;  // has not moved
        const PieceInfo& p = pieces[ip];
        Vector3d lo = Vector3d::Constant(1e300), hi = -lo;
        for (int32_t s = p.surfBegin; s < p.surfEnd; ++s) {
            const Vector3d x = at(pos, surfNodes[s]);
            lo = lo.cwiseMin(x);
            hi = hi.cwiseMax(x);
        }
        const double r = materials[p.material].radius;
        for (int d = 0; d < 3; ++d) {
            pc_.pieceLo[3 * ip + d] = lo[d] - r;
            pc_.pieceHi[3 * ip + d] = hi[d] + r;
        }
    }
}

void World::beginContactForces() {
    if (contactsActive_) return;
    for (std::size_t p = 0; p < pieces.size(); ++p) {
        if (asleep_[p]) continue;  // not integrated: its contact forces are not read
        for (int32_t i = pieces[p].surfBegin; i < pieces[p].surfEnd; ++i)
            for (int d = 0; d < 3; ++d) contactForce_[3 * surfNodes[i] + d] = 0.0;
    }
    contactsActive_ = true;
}

void World::pieceContactPhase(double dt) {
    timings.broadPhase = timings.pointPolygon = timings.edgeEdge = 0;
    contactCounts.pointPolygon = contactCounts.edgeEdge = 0;
    maxPieceOverlap = 0;
    const std::size_t np = pieces.size();
    std::fill(frozen_.begin(), frozen_.end(), 0);
    if (np < 2 || (!settings.pointPolygonOn && !settings.edgeEdgeOn)) return;

    // Which pieces can touch another one at all?  Sweep and prune on x:
    // pieces sorted by the low end of their boxes, each compared only with
    // those starting before its box ends.  O(P log P + touching pairs).
    const double t0 = omp_get_wtime();
    pc_.pieceActive.assign(np, 0);
    pc_.pieceOrder.resize(np);
    for (std::size_t i = 0; i < np; ++i) pc_.pieceOrder[i] = static_cast<int32_t>(i);
    std::sort(pc_.pieceOrder.begin(), pc_.pieceOrder.end(),
              [&](int32_t a, int32_t b) { return pc_.pieceLo[3 * a] < pc_.pieceLo[3 * b]; });
    pc_.pairs.clear();
    for (std::size_t i = 0; i < np; ++i) {
        const int32_t a = pc_.pieceOrder[i];
        for (std::size_t j = i + 1; j < np; ++j) {
            const int32_t b = pc_.pieceOrder[j];
            if (pc_.pieceLo[3 * b] > pc_.pieceHi[3 * a]) break;
            if (pc_.pieceLo[3 * a + 1] <= pc_.pieceHi[3 * b + 1] && pc_.pieceLo[3 * b + 1] <= pc_.pieceHi[3 * a + 1] &&
                pc_.pieceLo[3 * a + 2] <= pc_.pieceHi[3 * b + 2] && pc_.pieceLo[3 * b + 2] <= pc_.pieceHi[3 * a + 2])
                pc_.pairs.insert(pc_.pairs.end(), {a, b, b, a});
        }
    }
    // Neighbour lists (CSR) from the pairs, both directions.
    pc_.nbrStart.assign(np + 1, 0);
    for (std::size_t q = 0; q < pc_.pairs.size(); q += 2) ++pc_.nbrStart[pc_.pairs[q] + 1];
    for (std::size_t i = 0; i < np; ++i) pc_.nbrStart[i + 1] += pc_.nbrStart[i];
    pc_.nbrs.resize(pc_.pairs.size() / 2);
    pc_.nbrFill.assign(pc_.nbrStart.begin(), pc_.nbrStart.end() - 1);
    for (std::size_t q = 0; q < pc_.pairs.size(); q += 2) pc_.nbrs[pc_.nbrFill[pc_.pairs[q]]++] = pc_.pairs[q + 1];
    for (std::size_t i = 0; i < np; ++i) pc_.pieceActive[i] = pc_.nbrStart[i + 1] > pc_.nbrStart[i];
    // A sleeping piece whose neighbours all sleep has nothing moving near it:
    // its contacts are skipped (their history kept).
    if (nAsleep_ > 0)
        for (std::size_t i = 0; i < np; ++i) {
            if (!asleep_[i]) continue;
            bool all = true;
            for (int32_t q = pc_.nbrStart[i]; q < pc_.nbrStart[i + 1] && all; ++q) all = asleep_[pc_.nbrs[q]];
            frozen_[i] = all;
        }
    const bool any = !pc_.pairs.empty();
    if (!any) return;  // nothing touches (history lapses: it is only valid from the previous step)
    // The contact law's material constants of each pair of pieces that can
    // touch (a log and roots each): once per step, not once per contact.
    pc_.nbrLaw.resize(pc_.nbrs.size());
    pc_.pieceRadius.resize(np);
    for (std::size_t i = 0; i < np; ++i) {
        pc_.pieceRadius[i] = materials[pieces[i].material].radius;
        for (int32_t q = pc_.nbrStart[i]; q < pc_.nbrStart[i + 1]; ++q)
            pc_.nbrLaw[q] = pairConst(materials[pieces[i].material], materials[pieces[pc_.nbrs[q]].material]);
    }
    beginContactForces();

    double rMax = 0;
    for (std::size_t ip = 0; ip < np; ++ip)
        if (pc_.pieceActive[ip]) rMax = std::max(rMax, materials[pieces[ip].material].radius);
    if (pc_.surf.sharpAngle != settings.edgeFeatureAngle) pc_.surf.classifyEdges(refPos.data(), settings.edgeFeatureAngle);
    const SurfaceIndex& S = pc_.surf;
    const bool tetItems = settings.broadPhase != BroadPhase::Triangles;

    // Verlet lists (default mode): rebuild only when a surface node has moved
    // more than half the skin, pieces were added, or a piece became active.
    const bool verlet = !tetItems;
    const double skin = settings.verletSkin * rMax;
    bool rebuild = !verlet || !pc_.listValid || pc_.listTris != S.nTris() || pc_.listSkin != skin ||
                   pc_.listActive.size() != np;
    for (std::size_t ip = 0; ip < np && !rebuild; ++ip) rebuild = pc_.pieceActive[ip] && !pc_.listActive[ip];
    if (!rebuild) {
        const bool all = nAsleep_ == 0;  // else only the awake pieces' nodes move
        const auto ns = all ? static_cast<int32_t>(surfNodes.size()) : static_cast<int32_t>(awakeSurf_.size());
        double moved2 = 0;
#pragma omp parallel for schedule(static) reduction(max : moved2)
        for (int32_t j = 0; j < ns; ++j) {
            const int32_t i = all ? j : awakeSurf_[j];
            const int32_t n = surfNodes[i];
            if (!pc_.pieceActive[nodePiece[n]]) continue;
            moved2 = std::max(moved2, (at(pos, n) - Eigen::Map<const Vector3d>(&pc_.listPos[3 * i])).squaredNorm());
        }
        // Sleeping pieces do not move now, but may have moved before they fell asleep.
        for (std::size_t ip = 0; ip < np && nAsleep_ > 0; ++ip)
            if (pc_.pieceActive[ip] && asleep_[ip]) moved2 = std::max(moved2, sleepMoved2_[ip]);
        rebuild = moved2 > 0.25 * skin * skin;
    }
    const double grow = verlet ? skin : 0.0;

    // Register, piece by piece, the surface elements that lie near another
    // piece's box (the others cannot be touched this step), in cells sized by
    // the seed's eq. 6: element bounding radius (eq. 7) plus contact reach.
    if (rebuild) {
        pc_.itemStart.assign(np + 1, 0);
        pc_.items.clear(), pc_.itemPoint.clear(), pc_.itemRadius.clear();
    }
    const bool edgeRebuild = rebuild || !verlet;  // edge lists follow the same rebuilds
    if (edgeRebuild) {
        pc_.edgeStart.assign(np + 1, 0);
        pc_.edgeItems.clear(), pc_.edgeLo.clear(), pc_.edgeHi.clear();
    }
    pc_.triNormal.resize(3 * S.nTris());
    pc_.itemGrid.resize(np), pc_.edgeGrid.resize(np);
    double itemR = 0, edgeR = 0;
    auto addItem = [&](int32_t id, const int32_t* nodes, int n, double r, int32_t piece) {
        Vector3d c = Vector3d::Zero(), lo = Vector3d::Constant(1e300), hi = -lo;
        for (int k = 0; k < n; ++k) {
            const Vector3d x = at(pos, nodes[k]);
            c += x, lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
        }
        c /= n;
        lo.array() -= r + grow, hi.array() += r + grow;
        // Ours filters out elements far from other pieces; the seed's cases
        // A/B/C register everything of their kind, as the paper measured.
        if (!tetItems && !pc_.nearOther(piece, lo.data(), hi.data())) return;
        double R = 0;
        for (int k = 0; k < n; ++k) R = std::max(R, (at(pos, nodes[k]) - c).squaredNorm());
        R = std::sqrt(R);
        itemR = std::max(itemR, R);
        pc_.items.push_back(id);
        pc_.itemPoint.insert(pc_.itemPoint.end(), {c[0], c[1], c[2]});
        pc_.itemRadius.push_back(R);
    };
    for (std::size_t ip = 0; ip < np; ++ip) {
        const PieceInfo& p = pieces[ip];
        const double r = materials[p.material].radius;
        if (pc_.pieceActive[ip] && settings.pointPolygonOn && rebuild) {
            if (!tetItems) {
                for (int32_t t = S.pieceTriStart[ip]; t < S.pieceTriStart[ip + 1]; ++t)
                    addItem(t, &S.tri[3 * t], 3, r, ip);
            } else if (settings.broadPhase == BroadPhase::AllTets) {
                for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) addItem(e, &tetNodes[4 * e], 4, r, ip);
            } else {
                for (int32_t q = S.pieceSurfTetStart[ip]; q < S.pieceSurfTetStart[ip + 1]; ++q)
                    addItem(S.surfTets[q], &tetNodes[4 * S.surfTets[q]], 4, r, ip);
            }
        }
        if (rebuild) pc_.itemStart[ip + 1] = static_cast<int32_t>(pc_.items.size());
        if (pc_.pieceActive[ip] && settings.edgeEdgeOn && edgeRebuild) {
            for (int32_t e = S.pieceEdgeStart[ip]; e < S.pieceEdgeStart[ip + 1]; ++e) {
                if (!S.edgeSharp[e]) continue;
                const Vector3d a = at(pos, S.edge[2 * e]), b = at(pos, S.edge[2 * e + 1]);
                // Box grown by r (+ half the skin): two edges within reach
                // r_a + r_b (+ skin) share a cell.
                const double g = r + 0.5 * grow;
                const Vector3d lo = a.cwiseMin(b).array() - g, hi = a.cwiseMax(b).array() + g;
                if (!pc_.nearOther(ip, lo.data(), hi.data())) continue;
                edgeR = std::max(edgeR, (b - a).norm());
                pc_.edgeItems.push_back(e);
                pc_.edgeLo.insert(pc_.edgeLo.end(), {lo[0], lo[1], lo[2]});
                pc_.edgeHi.insert(pc_.edgeHi.end(), {hi[0], hi[1], hi[2]});
            }
        }
        if (edgeRebuild) pc_.edgeStart[ip + 1] = static_cast<int32_t>(pc_.edgeItems.size());
    }
    if (rebuild) pc_.itemReach = itemR + 2 * rMax + grow;
    for (std::size_t ip = 0; ip < np; ++ip) {
        const int32_t i0 = pc_.itemStart[ip], i1 = pc_.itemStart[ip + 1];
        // Cells twice the reach: a query box of +-reach then spans 2 cells per
        // axis (8 cells) instead of 3 (27), for a few more items per cell.
        if (rebuild) pc_.itemGrid[ip].build(pc_.itemPoint.data() + 3 * i0, i1 - i0, 2 * pc_.itemReach);
        const int32_t e0 = pc_.edgeStart[ip], e1 = pc_.edgeStart[ip + 1];
        if (edgeRebuild)
            pc_.edgeGrid[ip].build(pc_.edgeLo.data() + 3 * e0, pc_.edgeHi.data() + 3 * e0, e1 - e0,
                                   edgeR + 2 * rMax + grow);
    }
    // Unit normals of the surface triangles of active pieces (quick plane
    // test); a sleeping piece's once after it stopped.
#pragma omp parallel
    for (std::size_t ip = 0; ip < np; ++ip) {
        if (!pc_.pieceActive[ip] || normalsFresh_[ip]) continue;
#pragma omp for schedule(static) nowait
        for (int32_t t = S.pieceTriStart[ip]; t < S.pieceTriStart[ip + 1]; ++t) {
            const int32_t* c = &S.tri[3 * t];
            const Vector3d n = (at(pos, c[1]) - at(pos, c[0])).cross(at(pos, c[2]) - at(pos, c[0])).normalized();
            for (int d = 0; d < 3; ++d) pc_.triNormal[3 * t + d] = n[d];
        }
    }
    for (std::size_t ip = 0; ip < np && nAsleep_ > 0; ++ip) normalsFresh_[ip] = asleep_[ip] && pc_.pieceActive[ip];
    if (verlet && rebuild && settings.pointPolygonOn) {
        // Each surface node's candidate triangles: bounding sphere grown by
        // reach + skin holds the node.
        const auto ns = static_cast<int32_t>(surfNodes.size());
        constexpr int KL = PieceContactState::kList;
        pc_.list.resize(KL * static_cast<std::size_t>(ns));
        pc_.listCount.assign(ns, 0);
        pc_.listPos.resize(3 * static_cast<std::size_t>(ns));
#pragma omp parallel for schedule(dynamic, 64)
        for (int32_t i = 0; i < ns; ++i) {
            const int32_t node = surfNodes[i];
            const int32_t pa = nodePiece[node];
            const Vector3d A = at(pos, node);
            for (int d = 0; d < 3; ++d) pc_.listPos[3 * i + d] = A[d];
            if (!pc_.pieceActive[pa]) continue;
            const double ra = materials[pieces[pa].material].radius;
            int count = 0;
            for (int32_t q = pc_.nbrStart[pa]; q < pc_.nbrStart[pa + 1] && count >= 0; ++q) {
                const int32_t pb = pc_.nbrs[q];
                const double reach = ra + materials[pieces[pb].material].radius + skin;
                bool overlap = true;
                for (int d = 0; d < 3 && overlap; ++d)
                    overlap = A[d] - reach <= pc_.pieceHi[3 * pb + d] && pc_.pieceLo[3 * pb + d] <= A[d] + reach;
                if (!overlap) continue;
                const int32_t i0 = pc_.itemStart[pb];
                const Vector3d qlo = A.array() - pc_.itemReach, qhi = A.array() + pc_.itemReach;
                pc_.itemGrid[pb].forRange(qlo.data(), qhi.data(), [&](int32_t local) {
                    const int32_t it = i0 + local;
                    const double R = pc_.itemRadius[it] + reach;
                    if (count < 0 ||
                        (A - Eigen::Map<const Vector3d>(&pc_.itemPoint[3 * it])).squaredNorm() > R * R)
                        return;
                    if (count == KL) {
                        count = -1;  // crowded: this node queries the cells each step
                        return;
                    }
                    pc_.list[static_cast<std::size_t>(KL) * i + count++] = pc_.items[it];
                });
            }
            pc_.listCount[i] = count;
        }
        // Pack the lists (the step streams through them node after node).
        pc_.listStart.resize(static_cast<std::size_t>(ns) + 1);
        pc_.listStart[0] = 0;
        for (int32_t i = 0; i < ns; ++i) pc_.listStart[i + 1] = pc_.listStart[i] + std::max(0, pc_.listCount[i]);
        pc_.listFlat.resize(pc_.listStart[ns]);
#pragma omp parallel for schedule(static)
        for (int32_t i = 0; i < ns; ++i)
            std::copy_n(&pc_.list[static_cast<std::size_t>(KL) * i], std::max(0, pc_.listCount[i]),
                        &pc_.listFlat[pc_.listStart[i]]);
        pc_.listActive.assign(pc_.pieceActive.begin(), pc_.pieceActive.end());
        std::fill(sleepMoved2_.begin(), sleepMoved2_.end(), 0.0);  // lists now from the current positions
        pc_.listSkin = skin;
        pc_.listTris = S.nTris();
        pc_.listValid = true;
        ++pc_.listBuilds;
    }
    if (verlet && edgeRebuild && settings.edgeEdgeOn) {
        // Each registered edge's candidate edges of higher pieces (each pair once).
        const auto ne = static_cast<int32_t>(pc_.edgeItems.size());
        constexpr int KE = PieceContactState::kEdgeList;
        pc_.edgeList.resize(KE * static_cast<std::size_t>(ne));
        pc_.edgeListCount.assign(ne, 0);
#pragma omp parallel for schedule(dynamic, 64)
        for (int32_t ie = 0; ie < ne; ++ie) {
            const int32_t pa = S.edgePiece[pc_.edgeItems[ie]];
            int count = 0;
            for (int32_t q = pc_.nbrStart[pa]; q < pc_.nbrStart[pa + 1] && count >= 0; ++q) {
                const int32_t pb = pc_.nbrs[q];
                if (pb < pa) continue;
                const int32_t j0 = pc_.edgeStart[pb];
                pc_.edgeGrid[pb].forOverlapping(&pc_.edgeLo[3 * ie], &pc_.edgeHi[3 * ie], [&](int32_t local) {
                    if (count < 0) return;
                    if (count == KE) {
                        count = -1;  // crowded: this edge queries the cells each step
                        return;
                    }
                    pc_.edgeList[static_cast<std::size_t>(KE) * ie + count++] = j0 + local;
                });
            }
            pc_.edgeListCount[ie] = count;
        }
    }
    if (!verlet) pc_.listValid = false;

    const int nth = omp_get_max_threads();
    if (static_cast<int>(pc_.threadForce.size()) != nth) pc_.threadForce.assign(nth, {});
    for (auto& b : pc_.threadForce) b.resize(3 * surfNodes.size());
    const double t1 = omp_get_wtime();
    timings.broadPhase = t1 - t0;

    double eDamp = 0, eSlip = 0, maxOv = 0;
    long nPP = 0, nEE = 0;
    const bool fric = settings.frictionOn;
    // Thread buffers: only awake pieces' nodes are read (and so zeroed).
    const bool all = nAsleep_ == 0;
#pragma omp parallel num_threads(nth)
    {
        auto& b = pc_.threadForce[omp_get_thread_num()];
        if (all) std::fill(b.begin(), b.end(), 0.0);
        else
            for (std::size_t ip = 0; ip < np; ++ip)
                if (!asleep_[ip]) std::fill(&b[3 * pieces[ip].surfBegin], &b[3 * pieces[ip].surfEnd], 0.0);
    }
    if (settings.pointPolygonOn) {
        if (fric) pointPolygon<true>(dt, eDamp, eSlip, nPP, maxOv);
        else pointPolygon<false>(dt, eDamp, eSlip, nPP, maxOv);
    }
    const double t2 = omp_get_wtime();
    if (settings.edgeEdgeOn) {
        if (fric) edgeEdge<true>(dt, eDamp, eSlip, nEE, maxOv);
        else edgeEdge<false>(dt, eDamp, eSlip, nEE, maxOv);
    }
    const double tEE = omp_get_wtime();
    // Sum the thread buffers into the node contact forces.
    const auto ns = all ? static_cast<int32_t>(surfNodes.size()) : static_cast<int32_t>(awakeSurf_.size());
#pragma omp parallel for schedule(static) num_threads(nth)
    for (int32_t j = 0; j < ns; ++j) {
        const int32_t s = all ? j : awakeSurf_[j];
        for (int th = 0; th < nth; ++th)
            for (int d = 0; d < 3; ++d) contactForce_[3 * surfNodes[s] + d] += pc_.threadForce[th][3 * s + d];
    }
    const double t3 = omp_get_wtime();
    // The sum of the thread buffers is booked to point-polygon, the main user.
    timings.pointPolygon = (t2 - t1) + (t3 - tEE);
    timings.edgeEdge = tEE - t2;
    contactCounts.pointPolygon = nPP;
    contactCounts.edgeEdge = nEE;
    maxPieceOverlap = maxOv;
    if (settings.trackEnergy) {  // (the elastic energy is summed per piece)
        energy.contactDamping += eDamp;
        energy.friction += eSlip;
    }
}

}  // namespace qdem
