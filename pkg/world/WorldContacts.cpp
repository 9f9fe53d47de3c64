// Piece-piece surface contacts (seed paper §3-4): point-polygon and
// edge-edge, with a cell-list broad phase over surface elements only.
// Derivations and the rules that keep forces continuous: doc/contacts.md.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../contact/Geometry.hpp"
#include "World.hpp"

namespace qdem {

using Eigen::Vector3d;

namespace {

struct PairLaw {
    double kn, cn, kt, ct, mu, reach;
};

// Contact parameters of two particles of radii ra, rb (YADE's FrictPhys rule
// for the stiffness), reduced mass for the dashpots.
inline PairLaw pairLaw(const Material& a, const Material& b, double ma, double mb) {
    PairLaw p;
    const double ea = a.young * a.radius, eb = b.young * b.radius;
    p.kn = 2 * ea * eb / (ea + eb);
    const double nu = 0.5 * (a.poisson + b.poisson);
    p.kt = p.kn * 2 * (1 - nu) / (2 - nu);
    const double m = ma * mb / (ma + mb);
    const double xi = dampingRatioFromRestitution(std::sqrt(a.restitution * b.restitution));
    p.cn = 2 * xi * std::sqrt(p.kn * m);
    p.ct = 2 * xi * std::sqrt(p.kt * m);
    p.mu = std::min(a.frictionPiece, b.frictionPiece);
    p.reach = a.radius + b.radius;
    return p;
}

inline Vector3d at(const Column<double>& c, int32_t i) { return Vector3d(c[3 * i], c[3 * i + 1], c[3 * i + 2]); }

inline void addTo(double* buf, int32_t s, const Vector3d& f) {
    buf[3 * s] += f[0];
    buf[3 * s + 1] += f[1];
    buf[3 * s + 2] += f[2];
}

struct Candidate {
    int32_t tri;
    TriPoint cp;
    double dist;
    bool behind;
};

constexpr int kCandidates = 32;

}  // namespace

void World::updatePieceBounds() {
    const std::size_t np = pieces.size();
    pc_.pieceLo.resize(3 * np);
    pc_.pieceHi.resize(3 * np);
    for (std::size_t ip = 0; ip < np; ++ip) {
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
    const std::size_t ns = surfNodes.size();
    for (std::size_t i = 0; i < ns; ++i)
        for (int d = 0; d < 3; ++d) contactForce_[3 * surfNodes[i] + d] = 0.0;
    contactsActive_ = true;
}

void World::pieceContactPhase(double dt) {
    timings.broadPhase = timings.pointPolygon = timings.edgeEdge = 0;
    contactCounts.pointPolygon = contactCounts.edgeEdge = 0;
    maxPieceOverlap = 0;
    const std::size_t np = pieces.size();
    if (np < 2 || (!pointPolygonOn && !edgeEdgeOn)) return;

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
    const bool any = !pc_.pairs.empty();
    if (!any) return;  // nothing touches (history lapses: it is only valid from the previous step)
    beginContactForces();

    double rMax = 0;
    for (std::size_t ip = 0; ip < np; ++ip)
        if (pc_.pieceActive[ip]) rMax = std::max(rMax, materials[pieces[ip].material].radius);
    if (pc_.surf.sharpAngle != edgeFeatureAngle) pc_.surf.classifyEdges(refPos.data(), edgeFeatureAngle);
    const SurfaceIndex& S = pc_.surf;
    const bool tetItems = broadPhase != BroadPhase::Triangles;

    // Verlet lists (default mode): rebuild only when a surface node has moved
    // more than half the skin, pieces were added, or a piece became active.
    const bool verlet = !tetItems;
    const double skin = verletSkin * rMax;
    bool rebuild = !verlet || !pc_.listValid || pc_.listTris != S.nTris() || pc_.listSkin != skin ||
                   pc_.listActive.size() != np;
    for (std::size_t ip = 0; ip < np && !rebuild; ++ip) rebuild = pc_.pieceActive[ip] && !pc_.listActive[ip];
    if (!rebuild) {
        const auto ns = static_cast<int32_t>(surfNodes.size());
        double moved2 = 0;
#pragma omp parallel for schedule(static) reduction(max : moved2)
        for (int32_t i = 0; i < ns; ++i) {
            const int32_t n = surfNodes[i];
            if (!pc_.pieceActive[nodePiece[n]]) continue;
            moved2 = std::max(moved2, (at(pos, n) - Eigen::Map<const Vector3d>(&pc_.listPos[3 * i])).squaredNorm());
        }
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
    pc_.itemGrid.resize(np);
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
        if (pc_.pieceActive[ip] && pointPolygonOn && rebuild) {
            if (!tetItems) {
                for (int32_t t = S.pieceTriStart[ip]; t < S.pieceTriStart[ip + 1]; ++t)
                    addItem(t, &S.tri[3 * t], 3, r, ip);
            } else if (broadPhase == BroadPhase::AllTets) {
                for (int32_t e = p.tetBegin; e < p.tetEnd; ++e) addItem(e, &tetNodes[4 * e], 4, r, ip);
            } else {
                for (int32_t q = S.pieceSurfTetStart[ip]; q < S.pieceSurfTetStart[ip + 1]; ++q)
                    addItem(S.surfTets[q], &tetNodes[4 * S.surfTets[q]], 4, r, ip);
            }
        }
        if (rebuild) pc_.itemStart[ip + 1] = static_cast<int32_t>(pc_.items.size());
        if (pc_.pieceActive[ip] && edgeEdgeOn && edgeRebuild) {
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
    // Unit normals of the surface triangles of active pieces (quick plane test).
    const auto ntri = static_cast<int32_t>(S.nTris());
#pragma omp parallel for schedule(static)
    for (int32_t t = 0; t < ntri; ++t) {
        if (!pc_.pieceActive[S.triPiece[t]]) continue;
        const int32_t* c = &S.tri[3 * t];
        const Vector3d n = (at(pos, c[1]) - at(pos, c[0])).cross(at(pos, c[2]) - at(pos, c[0])).normalized();
        for (int d = 0; d < 3; ++d) pc_.triNormal[3 * t + d] = n[d];
    }
    if (verlet && rebuild && pointPolygonOn) {
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
        pc_.listActive.assign(pc_.pieceActive.begin(), pc_.pieceActive.end());
        pc_.listSkin = skin;
        pc_.listTris = S.nTris();
        pc_.listValid = true;
        ++pc_.listBuilds;
    }
    if (verlet && edgeRebuild && edgeEdgeOn) {
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

    double eEl = 0, eDamp = 0, eSlip = 0, maxOv = 0;
    long nPP = 0, nEE = 0;
    const bool fric = frictionOn;
#pragma omp parallel num_threads(nth)
    {
        auto& b = pc_.threadForce[omp_get_thread_num()];
        std::fill(b.begin(), b.end(), 0.0);
    }
    if (pointPolygonOn) {
        if (fric) pointPolygon<true>(dt, eEl, eDamp, eSlip, nPP, maxOv);
        else pointPolygon<false>(dt, eEl, eDamp, eSlip, nPP, maxOv);
    }
    const double t2 = omp_get_wtime();
    if (edgeEdgeOn) {
        if (fric) edgeEdge<true>(dt, eEl, eDamp, eSlip, nEE, maxOv);
        else edgeEdge<false>(dt, eEl, eDamp, eSlip, nEE, maxOv);
    }
    const double tEE = omp_get_wtime();
    // Sum the thread buffers into the node contact forces.
    const auto ns = static_cast<int32_t>(surfNodes.size());
#pragma omp parallel for schedule(static) num_threads(nth)
    for (int32_t s = 0; s < ns; ++s)
        for (int th = 0; th < nth; ++th)
            for (int d = 0; d < 3; ++d) contactForce_[3 * surfNodes[s] + d] += pc_.threadForce[th][3 * s + d];
    const double t3 = omp_get_wtime();
    // The sum of the thread buffers is booked to point-polygon, the main user.
    timings.pointPolygon = (t2 - t1) + (t3 - tEE);
    timings.edgeEdge = tEE - t2;
    contactCounts.pointPolygon = nPP;
    contactCounts.edgeEdge = nEE;
    maxPieceOverlap = maxOv;
    if (trackEnergy) {
        energy.contactElastic += eEl;  // reset at the start of each step
        energy.contactDamping += eDamp;
        energy.friction += eSlip;
    }
}

// ---------------------------------------------------------------------------
// Point-polygon: every surface node against the surface triangles of the
// other pieces.  One thread per surface node (seed §4.1).

template <bool Friction>
void World::pointPolygon(double dt, double& eEl, double& eDamp, double& eSlip, long& count, double& maxOv) {
    const SurfaceIndex& S = pc_.surf;
    const auto ns = static_cast<int32_t>(surfNodes.size());
    const bool tets = broadPhase != BroadPhase::Triangles;
    const bool interiorFacesToo = broadPhase == BroadPhase::AllTets || broadPhase == BroadPhase::SurfaceTets;
    constexpr int K = PieceContactState::kPP;
    const long stamp = iter;
    long interiorTests = 0, interiorNear = 0;

#pragma omp parallel reduction(+ : eEl, eDamp, eSlip, count, interiorTests, interiorNear) reduction(max : maxOv)
    {
        double* buf = pc_.threadForce[omp_get_thread_num()].data();
        Candidate cand[kCandidates];
#pragma omp for schedule(dynamic, 64)
        for (int32_t s = 0; s < ns; ++s) {
            const int32_t node = surfNodes[s];
            const int32_t pa = nodePiece[node];
            int32_t* key = &pc_.ppKey[K * s];
            int32_t* kpiece = &pc_.ppPiece[K * s];
            double* shear = &pc_.ppShear[3 * K * s];
            if (pc_.ppStamp[s] != stamp - 1)  // history is only valid from the previous step
                for (int k = 0; k < K; ++k) key[k] = -1;
            pc_.ppStamp[s] = stamp;
            if (!pc_.pieceActive[pa]) {
                for (int k = 0; k < K; ++k) key[k] = -1;
                continue;
            }
            const Material& ma = materials[pieces[pa].material];
            const Vector3d A = at(pos, node);
            int nc = 0;
            bool anyBehind = false;
            // Candidate triangles: bounding sphere grown by the reach holds the
            // node, and the node is within reach in front of its plane (or
            // behind it: possibly inside that piece).
            auto consider = [&](int32_t t, double reach) {
                if (nc == kCandidates) return;
                const int32_t* c = &S.tri[3 * t];
                const Vector3d a = at(pos, c[0]);
                const double h = (A - a).dot(Eigen::Map<const Vector3d>(&pc_.triNormal[3 * t]));
                if (h > reach) return;
                const TriPoint cp = closestOnTriangle(A, a, at(pos, c[1]), at(pos, c[2]));
                const double dist = (A - cp.point).norm();
                // Behind the face (inside the other piece) can only be told for
                // a face-interior closest point; an edge or corner closest point
                // means the node is outside, in that feature's region.
                const bool behind = h < 0 && cp.feature == TriFeature::Face;
                if (!behind && dist >= reach) return;
                anyBehind = anyBehind || behind;
                cand[nc++] = Candidate{t, cp, dist, behind};
            };
            const bool useList = pc_.listValid && pc_.listCount[s] >= 0;
            if (useList) {
                const int32_t* L = &pc_.list[static_cast<std::size_t>(PieceContactState::kList) * s];
                for (int k = 0; k < pc_.listCount[s]; ++k) {
                    const int32_t t = L[k];
                    const int32_t pb = S.triPiece[t];
                    if (pc_.pieceActive[pb]) consider(t, ma.radius + materials[pieces[pb].material].radius);
                }
            }
            for (int32_t q = pc_.nbrStart[pa]; q < pc_.nbrStart[pa + 1] && !useList; ++q) {
                const int32_t pb = pc_.nbrs[q];
                const double reach = ma.radius + materials[pieces[pb].material].radius;
                {
                    const Vector3d lo = A.array() - reach, hi = A.array() + reach;
                    bool overlap = true;
                    for (int d = 0; d < 3 && overlap; ++d)
                        overlap = lo[d] <= pc_.pieceHi[3 * pb + d] && pc_.pieceLo[3 * pb + d] <= hi[d];
                    if (!overlap) continue;
                }
                const int32_t i0 = pc_.itemStart[pb];
                // Items that can reach the node have their reference point within
                // (largest radius + reach) of it: visit the cells of that box only.
                const Vector3d qlo = A.array() - pc_.itemReach, qhi = A.array() + pc_.itemReach;
                pc_.itemGrid[pb].forRange(qlo.data(), qhi.data(), [&](int32_t local) {
                    const int32_t it = i0 + local;
                    // (grown by the skin: the cells may date from the last list rebuild)
                    const double R = pc_.itemRadius[it] + reach + (pc_.listValid ? pc_.listSkin : 0.0);
                    if ((A - Eigen::Map<const Vector3d>(&pc_.itemPoint[3 * it])).squaredNorm() > R * R) return;
                    const int32_t id = pc_.items[it];
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
                                if (j != k) f[n++] = tetNodes[4 * id + j];
                            const TriPoint cp = closestOnTriangle(A, at(pos, f[0]), at(pos, f[1]), at(pos, f[2]));
                            ++interiorTests;
                            if ((A - cp.point).norm() < reach) ++interiorNear;
                        }
                    }
                });
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
                    const int32_t i0 = pc_.itemStart[pb];
                    const Vector3d qlo = A.array() - pc_.itemReach, qhi = A.array() + pc_.itemReach;
                    auto witness = [&](int32_t id) {
                        if (!keep[i]) return;
                        for (int k = 0; k < (tets ? 4 : 1); ++k) {
                            const int32_t t = tets ? S.tetFaceTri[4 * id + k] : id;
                            if (t < 0) continue;
                            const int32_t* c = &S.tri[3 * t];
                            const Vector3d a = at(pos, c[0]);
                            const double h = (A - a).dot(Eigen::Map<const Vector3d>(&pc_.triNormal[3 * t]));
                            if (h >= db) continue;  // cannot be nearer
                            const TriPoint cp = closestOnTriangle(A, a, at(pos, c[1]), at(pos, c[2]));
                            const bool behind = h < 0 && cp.feature == TriFeature::Face;
                            if (!behind && (A - cp.point).norm() < db) keep[i] = false;
                        }
                    };
                    if (useList) {
                        const int32_t* L = &pc_.list[static_cast<std::size_t>(PieceContactState::kList) * s];
                        for (int k = 0; k < pc_.listCount[s]; ++k)
                            if (S.triPiece[L[k]] == pb) witness(L[k]);
                    } else {
                        pc_.itemGrid[pb].forRange(qlo.data(), qhi.data(),
                                                  [&](int32_t local) { witness(pc_.items[i0 + local]); });
                    }
                }

            // Edge and corner closest points are shared by the triangles around
            // them: per other piece keep only the nearest one, and only if no
            // face contact of that piece is nearer (the node is then in that
            // edge's or corner's region of the surface).  Each point of a
            // surface is thus reported once, and a node sliding across edges
            // and corners keeps one continuous contact.
            const double tol = 1e-9;
            const double eps = 1e-12 * ma.radius;
            for (int i = 0; i < nc; ++i) {  // snap rounding-level weights
                TriPoint& cp = cand[i].cp;
                int nz = 0, last = 0;
                for (int k = 0; k < 3; ++k)
                    if (cp.w[k] > tol) ++nz, last = k;
                if (nz == 3) cp.feature = TriFeature::Face;
                else if (nz == 1) cp.feature = static_cast<TriFeature>(4 + last);
                else if (cp.feature == TriFeature::Face) cp.feature = TriFeature::Edge0;  // on an edge: not a face
            }
            for (int i = 0; i < nc; ++i) {
                const Candidate& c = cand[i];
                if (!keep[i] || c.cp.feature == TriFeature::Face) continue;
                const int32_t pb = S.triPiece[c.tri];
                for (int j = 0; j < nc && keep[i]; ++j) {
                    if (j == i || !keep[j] || S.triPiece[cand[j].tri] != pb) continue;
                    const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
                    // A face point at (practically) the same distance is the
                    // same touch seen from the face: the face keeps it.
                    if (cand[j].cp.feature == TriFeature::Face) keep[i] = c.dist < dj - eps;
                    else keep[i] = c.dist < cand[j].dist || (c.dist == cand[j].dist && i < j);
                }
            }

            // Two contacts with the same piece whose normals differ by less
            // than the feature angle are one touch of a nearly flat (possibly
            // slightly folded) surface: keep the nearer.  Without this, a node
            // over a shallow concave fold would feel both faces at full
            // strength, and the count would flicker as the fold flexes.
            // Real corners (a node in a concave corner) keep both contacts.
            const double cosFeature = std::cos(edgeFeatureAngle);
            Vector3d cn[kCandidates];
            for (int i = 0; i < nc; ++i)
                if (keep[i]) cn[i] = (cand[i].behind ? -1.0 : 1.0) * (A - cand[i].cp.point) / std::max(cand[i].dist, eps);
            for (int i = 0; i < nc; ++i) {
                if (!keep[i]) continue;
                for (int j = i + 1; j < nc && keep[i]; ++j) {
                    if (!keep[j] || S.triPiece[cand[j].tri] != S.triPiece[cand[i].tri]) continue;
                    if (cn[i].dot(cn[j]) < cosFeature) continue;
                    const double di = cand[i].behind ? -cand[i].dist : cand[i].dist;
                    const double dj = cand[j].behind ? -cand[j].dist : cand[j].dist;
                    if (dj < di) keep[i] = false;
                    else keep[j] = false;
                }
            }

            int32_t newKey[K], newPiece[K];
            Vector3d newShear[K];
            bool usedOld[K] = {false, false, false, false, false, false};
            int nNew = 0;
            Vector3d fA = Vector3d::Zero();
            for (int i = 0; i < nc; ++i) {
                const Candidate& c = cand[i];
                const int f = static_cast<int>(c.cp.feature);
                if (!keep[i] || nNew == K) continue;

                const int32_t* tn = &S.tri[3 * c.tri];
                const int32_t pb = S.triPiece[c.tri];
                const Material& mb = materials[pieces[pb].material];
                double mT = 0;
                Vector3d vT = Vector3d::Zero();
                for (int k = 0; k < 3; ++k) {
                    mT += c.cp.w[k] * mass[tn[k]];
                    vT += c.cp.w[k] * at(vel, tn[k]);
                }
                const PairLaw law = pairLaw(ma, mb, mass[node], mT);
                const Vector3d nT(pc_.triNormal[3 * c.tri], pc_.triNormal[3 * c.tri + 1], pc_.triNormal[3 * c.tri + 2]);
                Vector3d n;
                double overlap;
                if (c.behind) {
                    n = c.dist > eps ? Vector3d((c.cp.point - A) / c.dist) : nT;
                    overlap = law.reach + c.dist;
                } else {
                    n = c.dist > eps ? Vector3d((A - c.cp.point) / c.dist) : nT;
                    overlap = law.reach - c.dist;
                }
                // Tangential history: same surface feature, else inherited from
                // a contact with the same piece that ended this step (a node
                // sliding onto the next triangle keeps its spring).
                const int32_t kk = 8 * c.tri + f;
                int slot = -1;
                for (int k = 0; k < K; ++k)
                    if (key[k] == kk && !usedOld[k]) slot = k;
                if (slot < 0)
                    for (int k = 0; k < K && slot < 0; ++k)
                        if (key[k] >= 0 && kpiece[k] == pb && !usedOld[k]) {
                            bool matchedLater = false;
                            for (int j = 0; j < nc; ++j)
                                if (keep[j] && 8 * cand[j].tri + static_cast<int>(cand[j].cp.feature) == key[k])
                                    matchedLater = true;
                            if (!matchedLater) slot = k;
                        }
                Vector3d sh = Vector3d::Zero();
                if (slot >= 0) {
                    usedOld[slot] = true;
                    sh = Vector3d(shear[3 * slot], shear[3 * slot + 1], shear[3 * slot + 2]);
                }
                const ContactParams cp{law.kn, law.cn, law.kt, law.ct, law.mu};
                const Vector3d vRel = at(vel, node) - vT;
                const ContactResult r = (Friction && law.mu > 0)
                                            ? contactForce<true>(cp, n, overlap, vRel, dt, sh)
                                            : contactForce<false>(cp, n, overlap, vRel, dt, sh);
                newKey[nNew] = kk;
                newPiece[nNew] = pb;
                newShear[nNew] = sh;
                ++nNew;
                fA += r.force;
                for (int k = 0; k < 3; ++k)
                    if (c.cp.w[k] != 0) addTo(buf, S.surfIndexOfNode[tn[k]], -c.cp.w[k] * r.force);
                eEl += r.elastic;
                eDamp += r.dampPower * dt;
                eSlip += r.slipWork;
                ++count;
                maxOv = std::max(maxOv, overlap);
            }
            addTo(buf, s, fA);
            for (int k = 0; k < K; ++k) {
                key[k] = k < nNew ? newKey[k] : -1;
                kpiece[k] = k < nNew ? newPiece[k] : -1;
                if (k < nNew)
                    for (int d = 0; d < 3; ++d) shear[3 * k + d] = newShear[k][d];
            }
        }
    }
    contactCounts.interiorFaceTests = interiorTests;
    contactCounts.interiorFaceNear = interiorNear;
}

// ---------------------------------------------------------------------------
// Edge-edge: surface edges of different pieces whose closest points are
// inside both edges (ends are point-polygon's business).  One thread per
// edge; each pair is handled by its lower edge id.

template <bool Friction>
void World::edgeEdge(double dt, double& eEl, double& eDamp, double& eSlip, long& count, double& maxOv) {
    const SurfaceIndex& S = pc_.surf;
    const auto ne = static_cast<int32_t>(pc_.edgeItems.size());
    constexpr int K = PieceContactState::kEE;
    const double sinFade2 = std::pow(std::sin(edgeFadeAngle), 2);
    const long stamp = iter;

#pragma omp parallel reduction(+ : eEl, eDamp, eSlip, count) reduction(max : maxOv)
    {
        double* buf = pc_.threadForce[omp_get_thread_num()].data();
#pragma omp for schedule(dynamic, 64)
        for (int32_t ie = 0; ie < ne; ++ie) {
            const int32_t e = pc_.edgeItems[ie];
            const int32_t pa = S.edgePiece[e];
            int32_t* other = &pc_.eeOther[K * e];
            int8_t* side = &pc_.eeSide[K * e];
            double* shear = &pc_.eeShear[3 * K * e];
            if (pc_.eeStamp[e] != stamp - 1)  // history is only valid from the previous step
                for (int k = 0; k < K; ++k) other[k] = -1;
            pc_.eeStamp[e] = stamp;
            const Material& ma = materials[pieces[pa].material];
            const int32_t a0 = S.edge[2 * e], a1 = S.edge[2 * e + 1];
            const Vector3d p1 = at(pos, a0), q1 = at(pos, a1);
            const double len1 = (q1 - p1).norm();
            int32_t newOther[K];
            int8_t newSide[K];
            Vector3d newShear[K];
            int nNew = 0;
            // One pair of edges: je indexes the registered edges.
            auto pair = [&](int32_t je) {
                    if (nNew == K) return;
                    const int32_t e2 = pc_.edgeItems[je];
                    const int32_t pb = S.edgePiece[e2];
                    if (!pc_.pieceActive[pb]) return;
                    const Material& mb = materials[pieces[pb].material];
                    const double reach = ma.radius + mb.radius;
                    const int32_t b0 = S.edge[2 * e2], b1 = S.edge[2 * e2 + 1];
                    const Vector3d p2 = at(pos, b0), q2 = at(pos, b1);
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
                    for (int k = 0; k < K; ++k)
                        if (other[k] == e2) slot = k;
                    // Which side of edge 2 edge 1 is on, along the common normal;
                    // remembered so that edges pushed through each other are
                    // pushed back, not let through.
                    int sNow = d.dot(cross) < 0 ? -1 : 1;
                    if (dist <= 1e-12 * reach && slot < 0) {  // touching at first sight: ask the piece centres
                        const Vector3d ca = 0.5 * (Eigen::Map<const Vector3d>(&pc_.pieceLo[3 * pa]) +
                                                   Eigen::Map<const Vector3d>(&pc_.pieceHi[3 * pa]));
                        const Vector3d cb = 0.5 * (Eigen::Map<const Vector3d>(&pc_.pieceLo[3 * pb]) +
                                                   Eigen::Map<const Vector3d>(&pc_.pieceHi[3 * pb]));
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
                    const double m1 = (1 - sp.s) * mass[a0] + sp.s * mass[a1];
                    const double m2 = (1 - sp.t) * mass[b0] + sp.t * mass[b1];
                    const PairLaw law = pairLaw(ma, mb, m1, m2);
                    const Vector3d vRel = ((1 - sp.s) * at(vel, a0) + sp.s * at(vel, a1)) -
                                          ((1 - sp.t) * at(vel, b0) + sp.t * at(vel, b1));
                    Vector3d sh = Vector3d::Zero();
                    if (slot >= 0) sh = Vector3d(shear[3 * slot], shear[3 * slot + 1], shear[3 * slot + 2]);
                    const ContactParams cp{w * law.kn, w * law.cn, w * law.kt, w * law.ct, law.mu};
                    const ContactResult r = (Friction && law.mu > 0)
                                                ? contactForce<true>(cp, n, overlap, vRel, dt, sh)
                                                : contactForce<false>(cp, n, overlap, vRel, dt, sh);
                    newOther[nNew] = e2;
                    newSide[nNew] = static_cast<int8_t>(sUse);
                    newShear[nNew] = sh;
                    ++nNew;
                    addTo(buf, S.surfIndexOfNode[a0], (1 - sp.s) * r.force);
                    addTo(buf, S.surfIndexOfNode[a1], sp.s * r.force);
                    addTo(buf, S.surfIndexOfNode[b0], -(1 - sp.t) * r.force);
                    addTo(buf, S.surfIndexOfNode[b1], -sp.t * r.force);
                    eEl += r.elastic;
                    eDamp += r.dampPower * dt;
                    eSlip += r.slipWork;
                    ++count;
                    maxOv = std::max(maxOv, overlap);
            };
            // Each pair of pieces once: edges of the lower piece id meet the
            // higher piece's edges, from the list made at the last rebuild or
            // from the cells.
            if (pc_.listValid && pc_.edgeListCount[ie] >= 0) {
                const int32_t* L = &pc_.edgeList[static_cast<std::size_t>(PieceContactState::kEdgeList) * ie];
                for (int k = 0; k < pc_.edgeListCount[ie]; ++k) pair(L[k]);
            } else {
                for (int32_t q = pc_.nbrStart[pa]; q < pc_.nbrStart[pa + 1]; ++q) {
                    const int32_t pb = pc_.nbrs[q];
                    if (pb < pa) continue;
                    const double* lo = &pc_.edgeLo[3 * ie];
                    const double* hi = &pc_.edgeHi[3 * ie];
                    bool overlap = true;  // the edge's box must reach the other piece's box
                    for (int d = 0; d < 3 && overlap; ++d)
                        overlap = lo[d] <= pc_.pieceHi[3 * pb + d] && pc_.pieceLo[3 * pb + d] <= hi[d];
                    if (!overlap) continue;
                    const int32_t j0 = pc_.edgeStart[pb];
                    pc_.edgeGrid[pb].forOverlapping(lo, hi, [&](int32_t local) { pair(j0 + local); });
                }
            }
            for (int k = 0; k < K; ++k) {
                other[k] = k < nNew ? newOther[k] : -1;
                side[k] = k < nNew ? newSide[k] : 0;
                if (k < nNew)
                    for (int d = 0; d < 3; ++d) shear[3 * k + d] = newShear[k][d];
            }
        }
    }
}

}  // namespace qdem
