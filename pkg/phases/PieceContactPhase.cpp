// Piece-piece surface contacts (seed paper §3-4): which pieces can touch,
// registration in cell lists, Verlet lists, and the phase driver.  The two
// contact kinds are in PointPolygon.cpp and EdgeEdge.cpp.  Derivations and
// the rules that keep forces continuous: doc/contacts.md.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "../contact/ContactLaw.hpp"
#include "../contact/Geometry.hpp"
#include "../contact/ListKernels.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../contact/ContactDetail.hpp"
#include "../parallel/Domain.hpp"
#include "../step/WorldState.hpp"
#include "PieceContactPhase.hpp"
#include "../contact/SurfaceSpin.hpp"

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;

PieceContactPhase::PieceContactPhase(const Data& data) : w_(data) {
    for (const ContactKindRow& row : contactKinds()) kinds_.push_back({&row, row.make()});
}

bool PieceContactPhase::kindOn(const Kind& k) const { return !k.row->on || w_.settings.*(k.row->on); }

bool PieceContactPhase::anyKindOn() const {
    for (const Kind& k : kinds_)
        if (kindOn(k)) return true;
    return false;
}

unsigned PieceContactPhase::listsWanted() const {
    unsigned lists = RegisterNothing;
    for (const Kind& k : kinds_)
        if (kindOn(k)) lists |= k.row->lists;
    return lists;
}

// The spin of the surface at every surface node of a piece that may touch
// another with friction (SurfaceSpin.hpp): what the springs between pieces turn by.  With
// the spring law only (the regularised one has no spring, frictionless
// contacts none either).  Each node from its own ring: any thread count
// gives the same bits; under MPI only the current nodes, whose rings the
// contact halo holds whole where a contact reads them.
void PieceContactPhase::surfaceSpins() {
    spinSeconds_ = 0, spinNodes_ = 0;
    if (!w_.settings.frictionOn || w_.settings.frictionModel == FrictionModel::Regularized) return;
    const double t0 = omp_get_wtime();
    const auto ns = static_cast<int32_t>(w_.surfNodes.size());
    st_.surfSpin.resize(3 * static_cast<std::size_t>(ns));
    const Domain* dom = w_.domain.built();
    const uint8_t* cur = dom ? dom->currentMask().data() : nullptr;
    const int32_t* surfNodes = w_.surfNodes.data();
    const int32_t* nodePiece = w_.nodePiece.data();
    // Only pieces with a friction partner near (the pair law's mu > 0).
    const std::size_t np = w_.pieces.size();
    st_.spinPiece.assign(np, 0);
    bool any = false;
    for (std::size_t p = 0; p < np; ++p) {
        for (int32_t q = st_.nbrStart[p]; q < st_.nbrStart[p + 1] && !st_.spinPiece[p]; ++q)
            st_.spinPiece[p] = st_.nbrLaw[q].mu > 0;
        any = any || st_.spinPiece[p];
    }
    if (!any) return;
    const uint8_t* active = st_.spinPiece.data();
    const double* X = w_.pos.data();
    const double* V = w_.vel.data();
    double* spin = st_.surfSpin.data();
    long done = 0;
#pragma omp parallel for schedule(static) reduction(+ : done)
    for (int32_t s = 0; s < ns; ++s) {
        const int32_t node = surfNodes[s];
        const int32_t p = nodePiece[node];
        // (a frozen piece's too: an awake piece's node may touch its triangles)
        if (!active[p] || (cur && !cur[node])) continue;
        surfaceNodeSpin(w_.surface, s, node, X, V, cur, spin + 3 * s);
        ++done;
    }
    spinNodes_ = done;
    spinSeconds_ = omp_get_wtime() - t0;
}

void PieceContactPhase::report(PhaseReport& r) const {
    // The sum of the thread buffers is booked to the first kind (point-polygon, the main user).
    r.seconds.push_back({"broadPhase", broadSeconds_});
    r.seconds.push_back({"surfaceSpin", spinSeconds_});
    r.counts.push_back({"surfaceSpinNodes", spinNodes_});
    for (std::size_t i = 0; i < kinds_.size(); ++i) {
        r.seconds.push_back({kinds_[i].row->name, kinds_[i].seconds + (i == 0 ? sumSeconds_ : 0.0)});
        r.counts.push_back({kinds_[i].row->name, kinds_[i].contacts});
        kinds_[i].kernel->report(r);
    }
    // Cases A/B: interior faces tested for nothing, and of them those within reach.
    r.counts.push_back({"interiorFaceTests", interiorFaceTests_});
    r.counts.push_back({"interiorFaceNear", interiorFaceNear_});
    r.counts.push_back({"listedTriangles", listedTriangles_});
}

void PieceContactPhase::run(double dt) {
    broadSeconds_ = sumSeconds_ = 0;
    for (Kind& k : kinds_) k.seconds = 0, k.contacts = 0;
    maxOverlap_ = maxDepthRatio_ = 0;
    stepLimit_ = ContactStepLimit{};
    interiorFaceTests_ = interiorFaceNear_ = 0;  // (a step with no pieces near tests none)
    listedTriangles_ = 0;
    const std::size_t np = w_.pieces.size();
    noteSleepChanges();
    std::fill(frozen_.begin(), frozen_.end(), 0);
    if (np < 2 || !anyKindOn()) {  // no contacts: no overlap to refuse either
        startChecked_.assign(np, 1);
        return;
    }
    // The lists the switched-on kinds declare (their rows' Registration bits).
    const unsigned lists = listsWanted();
    const bool triLists = lists & RegisterSurfaceTriangles, edgeLists = lists & RegisterFeatureEdges;

    // Which pieces can touch another one at all?  Sweep and prune on x:
    // pieces sorted by the low end of their boxes, each compared only with
    // those starting before its box ends.  O(P log P + touching pairs).
    const double t0 = omp_get_wtime();
    const double* X = w_.pos.data();  // (a local: the list loops store through narrow pointers)
    st_.pieceActive.assign(np, 0);
    st_.pieceOrder.resize(np);
    for (std::size_t i = 0; i < np; ++i) st_.pieceOrder[i] = static_cast<int32_t>(i);
    std::sort(st_.pieceOrder.begin(), st_.pieceOrder.end(),
              [&](int32_t a, int32_t b) { return w_.bounds.lo[3 * a] < w_.bounds.lo[3 * b]; });
    st_.pairs.clear();
    for (std::size_t i = 0; i < np; ++i) {
        const int32_t a = st_.pieceOrder[i];
        for (std::size_t j = i + 1; j < np; ++j) {
            const int32_t b = st_.pieceOrder[j];
            if (w_.bounds.lo[3 * b] > w_.bounds.hi[3 * a]) break;
            if (w_.bounds.lo[3 * a + 1] <= w_.bounds.hi[3 * b + 1] && w_.bounds.lo[3 * b + 1] <= w_.bounds.hi[3 * a + 1] &&
                w_.bounds.lo[3 * a + 2] <= w_.bounds.hi[3 * b + 2] && w_.bounds.lo[3 * b + 2] <= w_.bounds.hi[3 * a + 2])
                st_.pairs.insert(st_.pairs.end(), {a, b, b, a});
        }
    }
    // Neighbour lists (CSR) from the pairs, both directions.
    st_.nbrStart.assign(np + 1, 0);
    for (std::size_t q = 0; q < st_.pairs.size(); q += 2) ++st_.nbrStart[st_.pairs[q] + 1];
    for (std::size_t i = 0; i < np; ++i) st_.nbrStart[i + 1] += st_.nbrStart[i];
    st_.nbrs.resize(st_.pairs.size() / 2);
    st_.nbrFill.assign(st_.nbrStart.begin(), st_.nbrStart.end() - 1);
    for (std::size_t q = 0; q < st_.pairs.size(); q += 2) st_.nbrs[st_.nbrFill[st_.pairs[q]]++] = st_.pairs[q + 1];
    for (std::size_t i = 0; i < np; ++i) st_.pieceActive[i] = st_.nbrStart[i + 1] > st_.nbrStart[i];
    // A sleeping piece whose neighbours all sleep has nothing moving near it:
    // its contacts are skipped (their history kept).
    if (w_.sleeping.nAsleep() > 0)
        for (std::size_t i = 0; i < np; ++i) {
            if (!w_.sleeping.asleep(i)) continue;
            bool all = true;
            for (int32_t q = st_.nbrStart[i]; q < st_.nbrStart[i + 1] && all; ++q) all = w_.sleeping.asleep(st_.nbrs[q]);
            frozen_[i] = all;
        }
    const bool any = !st_.pairs.empty();
    if (!any) {  // nothing touches (history lapses: it is only valid from the previous step)
        startChecked_.assign(np, 1);  // (nor overlaps)
        return;
    }
    // The contact law's material constants of each pair of pieces that can
    // touch (a log and roots each): once per step, not once per contact,
    // and once per pair of materials, which pieces share (a table when it
    // is small; filled afresh each step, as materials may have changed).
    st_.nbrLaw.resize(st_.nbrs.size());
    st_.pieceRadius.resize(np);
    const std::size_t nm = w_.materials.size();
    const bool table = nm * nm <= 4 * st_.nbrs.size() + 64;
    if (table) matPairDone_.assign(nm * nm, 0), matPairLaw_.resize(nm * nm);
    for (std::size_t i = 0; i < np; ++i) {
        const int ma = w_.pieces[i].material;
        st_.pieceRadius[i] = w_.materials[ma].radius;
        for (int32_t q = st_.nbrStart[i]; q < st_.nbrStart[i + 1]; ++q) {
            const int mb = w_.pieces[st_.nbrs[q]].material;
            if (!table) {
                st_.nbrLaw[q] = pairConst(w_.materials[ma], w_.materials[mb]);
                continue;
            }
            const std::size_t k = static_cast<std::size_t>(ma) * nm + mb;
            if (!matPairDone_[k]) matPairLaw_[k] = pairConst(w_.materials[ma], w_.materials[mb]), matPairDone_[k] = 1;
            st_.nbrLaw[q] = matPairLaw_[k];
        }
    }
    w_.contacts.begin();

    double rMax = 0;
    for (std::size_t ip = 0; ip < np; ++ip)
        if (st_.pieceActive[ip]) rMax = std::max(rMax, w_.materials[w_.pieces[ip].material].radius);
    if (w_.surface.sharpAngle != w_.settings.edgeFeatureAngle) w_.surface.classifyEdges(w_.refPos.data(), w_.settings.edgeFeatureAngle);
    const SurfaceIndex& S = w_.surface;
    const bool tetItems = w_.settings.broadPhase != BroadPhase::Triangles;

    // Verlet lists (default mode): rebuild only when a surface node has moved
    // more than half the skin, pieces were added, or a piece became active.
    const bool verlet = !tetItems;
    const double skin = w_.settings.verletSkin * rMax;
    // Under MPI (Domain.hpp) only owned and ghost nodes are current: what is
    // registered must be current, and lists are rebuilt when the set changes.
    const Domain* dom = w_.domain.built();
    const uint8_t* cur = dom ? dom->currentMask().data() : nullptr;
    bool rebuild = !verlet || !st_.listValid || st_.listTris != S.nTris() || st_.listSkin != skin ||
                   st_.listActive.size() != np || st_.listKinds != lists ||
                   (dom && listDomainVersion_ != dom->currentVersion());
    for (std::size_t ip = 0; ip < np && !rebuild; ++ip) rebuild = st_.pieceActive[ip] && !st_.listActive[ip];
    bool outran = false;          // motion outran an open window: all at once
    // A rebuild spread over steps (PieceContactState.hpp): not under MPI
    // (ranks rebuild as their halos change), nor without node lists.
    const int spread = dom || !verlet || !triLists ? 1 : w_.settings.verletRebuildSteps;
    bool finishWindow = false;  // build every chunk still to do, this step
    bool spreadNow = false;     // a rebuild due now is spread over steps
    if (st_.windowNext >= 0 && spread == 1) rebuild = true;  // (spreading switched off: all at once)
    const bool forced = rebuild;  // by a change, not by motion: all at once
    if (rebuild) st_.windowNext = -1;  // (an open window's lists are given up)
    double movedNow = 0;               // the largest move from listPos
    if (!rebuild) {
        // Only the awake pieces' nodes move; under MPI the current ones (the
        // owned and the ghosts: a ghost face moving in counts as much).
        const bool all = w_.sleeping.everything();
        const std::vector<int32_t>& moving = dom ? dom->currentSurf() : w_.sleeping.awakeSurf();
        const auto ns = all ? static_cast<int32_t>(w_.surfNodes.size()) : static_cast<int32_t>(moving.size());
        const bool window = st_.windowNext >= 0;
        double moved2 = 0, movedOld2 = 0;
#pragma omp parallel for schedule(static) reduction(max : moved2)
        for (int32_t j = 0; j < ns; ++j) {
            const int32_t i = all ? j : moving[j];
            const int32_t n = w_.surfNodes[i];
            if (!st_.pieceActive[w_.nodePiece[n]]) continue;
            moved2 = std::max(moved2, (at(X, n) - Eigen::Map<const Vector3d>(&st_.listPos[3 * i])).squaredNorm());
        }
        // Sleeping pieces do not move now, but may have moved before they fell asleep.
        for (std::size_t ip = 0; ip < np && w_.sleeping.nAsleep() > 0; ++ip)
            if (st_.pieceActive[ip] && w_.sleeping.asleep(ip))
                moved2 = std::max(moved2, listsSinceSleep_[ip] ? 0.0 : w_.sleeping.moved2(ip));
        if (window) {
            // The former lists, still read by the nodes not yet done: every
            // surface node (a sleeping one too: it may have moved since then).
            const auto nsAll = static_cast<int32_t>(w_.surfNodes.size());
#pragma omp parallel for schedule(static) reduction(max : movedOld2)
            for (int32_t i = 0; i < nsAll; ++i) {
                const int32_t n = w_.surfNodes[i];
                movedOld2 = std::max(movedOld2,
                                     (at(X, n) - Eigen::Map<const Vector3d>(&st_.listPosOld[3 * i])).squaredNorm());
            }
        }
        const double moved = std::sqrt(moved2), half = 0.5 * skin;
        if (spread == 1) {
            rebuild = moved2 > 0.25 * skin * skin;  // (the rule of a rebuild in one step, exactly)
        } else if (window) {
            // The new lists: built up to now, each valid while no node moves
            // more than half the skin less the move at its build.
            if (moved > half - std::max(st_.listSlack, moved)) rebuild = outran = true;
            else finishWindow = std::sqrt(movedOld2) > half - st_.listSlackOld;
        } else {
            // Start early enough for the window to end before the lists in
            // use expire: the largest move grows by about `growth` a step,
            // and the window's last chunks come spread - 1 steps after its
            // start (with half as much again to spare; if motion speeds up,
            // finishWindow builds the rest at once).  Lists that live only a
            // few tens of steps are not worth spreading (the margin and the
            // slack would make rebuilds more frequent): all in one step then,
            // by the one-step rule.
            const double growth = st_.lastMoved >= 0 ? std::max(0.0, moved - st_.lastMoved) : 0.0;
            const double margin = 1.5 * (spread - 1) * growth, room = half - st_.listSlack;
            spreadNow = room > 10 * margin;
            rebuild = spreadNow ? moved + margin > room
                                : (st_.listSlack > 0 ? moved > room : moved2 > 0.25 * skin * skin);
        }
        st_.lastMoved = movedNow = moved;
    }
    // This step: the whole rebuild (one step, or one forced by a change), the
    // first step of a window, or some of an open window's chunks.
    const bool windowStart = rebuild && spreadNow && !forced && !outran;
    const double grow = verlet ? skin : 0.0;

    // Register, piece by piece, the surface elements that lie near another
    // piece's box (the others cannot be touched this step), in cells sized by
    // the seed's eq. 6: element bounding radius (eq. 7) plus contact reach.
    // The pieces are registered in parallel, each into its own stretch of
    // the arrays (its triangles, tets or edges' id range), then the
    // stretches are packed in piece order: the same items, in the same
    // order, as one pass piece after piece.
    // Edge lists follow the same rebuilds; a spread rebuild registers the
    // edges and builds their lists on its second step (the former ones,
    // registered with the former lists, serve until then).
    const bool edgesNow = st_.windowEdgesPending && !rebuild;
    const bool edgeRebuild = (rebuild && !windowStart) || edgesNow || !verlet;
    st_.windowEdgesPending = windowStart;
    const bool registerNow = rebuild || edgeRebuild;
    const bool allTets = w_.settings.broadPhase == BroadPhase::AllTets;
    // Piece ip's candidate items: a range of ids (its triangles; its tets or
    // surface tets in the seed's cases A/B/C); the ones registered are
    // written from the start of that range, then packed.
    auto itemRange = [&](std::size_t ip) -> std::pair<int32_t, int32_t> {
        if (!tetItems) return {S.pieceTriStart[ip], S.pieceTriStart[ip + 1]};
        if (allTets) return {w_.pieces[ip].tetBegin, w_.pieces[ip].tetEnd};
        return {S.pieceSurfTetStart[ip], S.pieceSurfTetStart[ip + 1]};
    };
    const std::size_t itemCap = !tetItems ? S.nTris() : allTets ? static_cast<std::size_t>(w_.tetNodes.size() / 4)
                                                                 : S.surfTets.size();
    // (The arrays keep the capacity of every candidate: itemStart[np] and
    // edgeStart[np] say how many are registered.  Shrinking them to that
    // count made the next rebuild zero-fill them again: serial stores of
    // the size of the surface.)
    if (rebuild) {
        st_.items.resize(itemCap), st_.itemPoint.resize(3 * itemCap), st_.itemRadius.resize(itemCap);
        st_.itemStart.assign(np + 1, 0);
    }
    if (edgeRebuild) {
        st_.edgeItems.resize(S.nEdges()), st_.edgeLo.resize(3 * S.nEdges()), st_.edgeHi.resize(3 * S.nEdges());
        st_.edgeRec.resize(PieceContactState::kEdgeRec * S.nEdges());
        st_.edgeStart.assign(np + 1, 0);
    }
    st_.triNormal.resize(3 * S.nTris());
    st_.itemGrid.resize(np), st_.edgeGrid.resize(np);
    double itemR = 0, edgeR = 0;
    // Registers item id (its n nodes) of piece `piece` at slot k if it is
    // near another piece; returns whether it did.
    auto addItem = [&](int32_t id, const int32_t* nodes, int n, double r, int32_t piece, std::size_t k,
                       double& rLargest, int32_t& hint) {
        if (cur)
            for (int j = 0; j < n; ++j)
                if (!cur[nodes[j]]) return false;
        Vector3d c = Vector3d::Zero(), lo = Vector3d::Constant(1e300), hi = -lo;
        for (int j = 0; j < n; ++j) {
            const Vector3d x = at(X, nodes[j]);
            c += x, lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
        }
        c /= n;
        lo.array() -= r + grow, hi.array() += r + grow;
        // Ours filters out elements far from other pieces; the seed's cases
        // A/B/C register everything of their kind, as the paper measured.
        if (!tetItems && !st_.nearOther(piece, lo.data(), hi.data(), w_.bounds.lo.data(), w_.bounds.hi.data(), hint))
            return false;
        double R = 0;
        for (int j = 0; j < n; ++j) R = std::max(R, (at(X, nodes[j]) - c).squaredNorm());
        R = std::sqrt(R);
        rLargest = std::max(rLargest, R);
        st_.items[k] = id;
        for (int d = 0; d < 3; ++d) st_.itemPoint[3 * k + d] = c[d];
        st_.itemRadius[k] = R;
        return true;
    };
    const auto npi = static_cast<int32_t>(np);
#pragma omp parallel for schedule(dynamic, 1) reduction(max : itemR, edgeR) if (registerNow)
    for (int32_t ip = 0; ip < (registerNow ? npi : 0); ++ip) {
        const PieceInfo& p = w_.pieces[ip];
        const double r = w_.materials[p.material].radius;
        if (st_.pieceActive[ip] && triLists && rebuild) {
            const auto [b, e] = itemRange(ip);
            const std::size_t k0 = !tetItems ? S.pieceTriStart[ip] : allTets ? p.tetBegin : S.pieceSurfTetStart[ip];
            std::size_t k = k0;
            int32_t hint = -1;
            for (int32_t q = b; q < e; ++q) {
                if (!tetItems) k += addItem(q, &S.tri[3 * q], 3, r, ip, k, itemR, hint);
                else if (allTets) k += addItem(q, &w_.tetNodes[4 * q], 4, r, ip, k, itemR, hint);
                else k += addItem(S.surfTets[q], &w_.tetNodes[4 * S.surfTets[q]], 4, r, ip, k, itemR, hint);
            }
            st_.itemStart[ip + 1] = static_cast<int32_t>(k - k0);  // (a count until packed)
        }
        if (st_.pieceActive[ip] && edgeLists && edgeRebuild) {
            std::size_t k = S.pieceEdgeStart[ip];
            int32_t hint = -1;
            for (int32_t e = S.pieceEdgeStart[ip]; e < S.pieceEdgeStart[ip + 1]; ++e) {
                if (!S.edgeSharp[e]) continue;
                if (cur && (!cur[S.edge[2 * e]] || !cur[S.edge[2 * e + 1]])) continue;
                const Vector3d a = at(X, S.edge[2 * e]), b = at(X, S.edge[2 * e + 1]);
                // Box grown by r (+ half the skin): two edges within reach
                // r_a + r_b (+ skin) share a cell.
                const double g = r + 0.5 * grow;
                const Vector3d lo = a.cwiseMin(b).array() - g, hi = a.cwiseMax(b).array() + g;
                if (!st_.nearOther(ip, lo.data(), hi.data(), w_.bounds.lo.data(), w_.bounds.hi.data(), hint)) continue;
                edgeR = std::max(edgeR, (b - a).norm());
                st_.edgeItems[k] = e;
                for (int d = 0; d < 3; ++d) st_.edgeLo[3 * k + d] = lo[d], st_.edgeHi[3 * k + d] = hi[d];
                int32_t* rec = &st_.edgeRec[PieceContactState::kEdgeRec * k];
                rec[0] = S.edge[2 * e], rec[1] = S.edge[2 * e + 1], rec[2] = ip, rec[3] = e - S.pieceEdgeStart[ip];
                ++k;
            }
            st_.edgeStart[ip + 1] = static_cast<int32_t>(k - S.pieceEdgeStart[ip]);
        }
    }
    // Pack the pieces' stretches (each moves down or stays: order kept).
    if (rebuild) {
        for (std::size_t ip = 0; ip < np; ++ip) {
            const std::size_t from = !tetItems ? S.pieceTriStart[ip] : allTets ? w_.pieces[ip].tetBegin
                                                                              : S.pieceSurfTetStart[ip];
            const int32_t n = st_.itemStart[ip + 1], to = st_.itemStart[ip];
            std::copy_n(&st_.items[from], n, &st_.items[to]);
            std::copy_n(&st_.itemPoint[3 * from], 3 * n, &st_.itemPoint[3 * to]);
            std::copy_n(&st_.itemRadius[from], n, &st_.itemRadius[to]);
            st_.itemStart[ip + 1] = to + n;
        }
    }
    if (edgeRebuild) {
        for (std::size_t ip = 0; ip < np; ++ip) {
            const std::size_t from = S.pieceEdgeStart[ip];
            const int32_t n = st_.edgeStart[ip + 1], to = st_.edgeStart[ip];
            std::copy_n(&st_.edgeItems[from], n, &st_.edgeItems[to]);
            std::copy_n(&st_.edgeLo[3 * from], 3 * n, &st_.edgeLo[3 * to]);
            std::copy_n(&st_.edgeHi[3 * from], 3 * n, &st_.edgeHi[3 * to]);
            constexpr int R = PieceContactState::kEdgeRec;
            std::copy_n(&st_.edgeRec[R * from], R * n, &st_.edgeRec[R * to]);
            st_.edgeStart[ip + 1] = to + n;
        }
    }
    if (rebuild) st_.itemReach = itemR + 2 * rMax + grow, st_.listKinds = lists;
    // (each piece's grids are its own: built in parallel)
#pragma omp parallel for schedule(dynamic, 1) if (registerNow)
    for (int32_t ip = 0; ip < (registerNow ? npi : 0); ++ip) {
        const int32_t i0 = st_.itemStart[ip], i1 = st_.itemStart[ip + 1];
        // Cells twice the reach: a query box of +-reach then spans 2 cells per
        // axis (8 cells) instead of 3 (27), for a few more items per cell.
        if (rebuild)
            st_.itemGrid[ip].build(st_.itemPoint.data() + 3 * i0, i1 - i0, 2 * st_.itemReach,
                                   st_.itemRadius.data() + i0);  // (the radii ride along: the list build reads them)
        const int32_t e0 = st_.edgeStart[ip], e1 = st_.edgeStart[ip + 1];
        if (edgeRebuild)
            st_.edgeGrid[ip].build(st_.edgeLo.data() + 3 * e0, st_.edgeHi.data() + 3 * e0, e1 - e0,
                                   edgeR + 2 * rMax + grow);
    }
    // Thread force buffers, one per thread, 3 per surface node.
    const int nth = omp_get_max_threads();
    if (static_cast<int>(st_.threadForce.size()) != nth) st_.threadForce.assign(nth, {});
    for (auto& b : st_.threadForce) b.resize(3 * w_.surfNodes.size());
    st_.threadForceData.resize(nth);
    for (int th = 0; th < nth; ++th) st_.threadForceData[th] = st_.threadForce[th].data();
    if (static_cast<int>(st_.threadLoad.size()) != nth) st_.threadLoad.assign(nth, {});
    for (auto& b : st_.threadLoad) b.resize(2 * w_.surfNodes.size());
    st_.threadLoadData.resize(nth);
    for (int th = 0; th < nth; ++th) st_.threadLoadData[th] = st_.threadLoad[th].data();
    const bool all = w_.sleeping.everything();
    const bool windowOpen = windowStart || st_.windowNext >= 0;  // some nodes read their former lists
    // Unit normals of the surface triangles of active pieces (quick plane test);
    // a sleeping piece's once after it stopped (and again after a rebuild,
    // which may register others of its triangles).  The same region zeroes the
    // thread buffers (only awake pieces' nodes are read, and so zeroed): one
    // fork and join less.
#pragma omp parallel num_threads(nth)
    {
        for (int th = omp_get_thread_num(); th < nth; th += omp_get_num_threads()) {
            std::vector<double>& b = st_.threadForce[th];
            std::vector<double>& l = st_.threadLoad[th];
            if (all) std::fill(b.begin(), b.end(), 0.0), std::fill(l.begin(), l.end(), 0.0);
            else
                for (std::size_t ip = 0; ip < np; ++ip)
                    if (!w_.sleeping.asleep(ip)) {
                        std::fill(&b[3 * w_.pieces[ip].surfBegin], &b[3 * w_.pieces[ip].surfEnd], 0.0);
                        std::fill(&l[2 * w_.pieces[ip].surfBegin], &l[2 * w_.pieces[ip].surfEnd], 0.0);
                    }
        }
        auto normal = [&](int32_t t) {
            const int32_t* c = &S.tri[3 * t];
            const Vector3d n = (at(X, c[1]) - at(X, c[0])).cross(at(X, c[2]) - at(X, c[0])).normalized();
            for (int d = 0; d < 3; ++d) st_.triNormal[3 * t + d] = n[d];
        };
        for (std::size_t ip = 0; ip < np; ++ip) {
            if (!st_.pieceActive[ip] || (normalsFresh_[ip] && !rebuild && !windowOpen)) continue;
            // (the seed's cases: every tet face may be read; during a spread
            // rebuild, the former lists may hold triangles no longer registered)
            if (tetItems || windowOpen) {
#pragma omp for schedule(static) nowait
                for (int32_t t = S.pieceTriStart[ip]; t < S.pieceTriStart[ip + 1]; ++t) normal(t);
            } else {
                // Only the registered triangles are read (listed, or met in
                // the cells): a third of the stack's surface faces out, and
                // most of a sparse scene's is far from any other piece.
#pragma omp for schedule(static) nowait
                for (int32_t k = st_.itemStart[ip]; k < st_.itemStart[ip + 1]; ++k) normal(st_.items[k]);
            }
        }
    }
    for (std::size_t ip = 0; ip < np && w_.sleeping.nAsleep() > 0; ++ip) normalsFresh_[ip] = w_.sleeping.asleep(ip) && st_.pieceActive[ip];
    if (verlet && triLists && (rebuild || st_.windowNext >= 0)) {
        // Each surface node's candidate triangles: bounding sphere grown by
        // reach + skin holds the node.
        const auto ns = static_cast<int32_t>(w_.surfNodes.size());
        constexpr int KL = PieceContactState::kList;
        // The nodes go in chunks of kListChunk, one chunk per task; a chunk's
        // lists are written one after the other into its own stretch of
        // listFlat (room for kList each), so they come out packed chunk by
        // chunk with no second pass to pack them.
        constexpr int32_t CH = PieceContactState::kListChunk;
        const int32_t nChunks = (ns + CH - 1) / CH;
        // Two halves: a spread rebuild writes the new lists into the one
        // the nodes not yet done do not read.
        const std::size_t halfSize = static_cast<std::size_t>(KL) * CH * nChunks;
        if (rebuild) {
            st_.listFlat.resize(2 * halfSize);  // (same size each rebuild: no fill)
            st_.listCount.resize(ns);
            st_.listStart.resize(ns);
            // The lists' reference positions: every surface node's, now.
            if (windowStart) std::swap(st_.listPos, st_.listPosOld), st_.listSlackOld = st_.listSlack;
            st_.listPos.resize(3 * static_cast<std::size_t>(ns));
            const auto* surf = w_.surfNodes.data();
            double* ref = st_.listPos.data();
#pragma omp parallel for schedule(static)
            for (int32_t i = 0; i < ns; ++i)
                for (int d = 0; d < 3; ++d) ref[3 * i + d] = X[3 * surf[i] + d];
            st_.listSlack = 0, st_.lastMoved = 0;
            st_.listHalf = windowStart ? 1 - st_.listHalf : 0;
        }
        // The chunks this step builds: all of them (a rebuild in one step, or
        // what is left of a window when the former lists expire), none on a
        // window's first step, or the next part of an open window.
        int32_t chunk0 = 0, chunk1 = nChunks;
        if (windowStart) {
            st_.windowNext = 0;
            st_.windowChunksPerStep = (nChunks + spread - 2) / (spread - 1);
            chunk1 = 0;
        } else if (!rebuild) {
            chunk0 = st_.windowNext;
            chunk1 = finishWindow ? nChunks : std::min(nChunks, chunk0 + st_.windowChunksPerStep);
            st_.listSlack = std::max(st_.listSlack, movedNow);  // these lists are built that far from listPos
            st_.windowNext = chunk1 < nChunks ? chunk1 : -1;
            ++st_.windowSteps;
        }
        const std::size_t base = static_cast<std::size_t>(st_.listHalf) * halfSize;
        // Per neighbour entry: the reach (ra + rb + skin, summed in that
        // order) and the neighbour's box, as 7 arrays over the entries.
        const std::size_t nq = st_.nbrs.size();
        st_.nbrBox.resize(7 * nq);
        for (std::size_t pa = 0; pa < np; ++pa)
            for (int32_t q = st_.nbrStart[pa]; q < st_.nbrStart[pa + 1]; ++q) {
                const int32_t pb = st_.nbrs[q];
                st_.nbrBox[q] = st_.pieceRadius[pa] + st_.pieceRadius[pb] + skin;
                for (int d = 0; d < 3; ++d)
                    st_.nbrBox[(1 + d) * nq + q] = w_.bounds.lo[3 * pb + d], st_.nbrBox[(4 + d) * nq + q] = w_.bounds.hi[3 * pb + d];
            }
        const double* nbrReach = st_.nbrBox.data();
        const double* nbrLo[3] = {nbrReach + nq, nbrReach + 2 * nq, nbrReach + 3 * nq};
        const double* nbrHi[3] = {nbrReach + 4 * nq, nbrReach + 5 * nq, nbrReach + 6 * nq};
        // Node i's list into buf (KL + 8 entries): its count, -1 when more
        // than KL pass (crowded: the node queries the cells each step).
        auto nodeList = [&](int32_t i, int32_t* buf) -> int {
            const int32_t node = w_.surfNodes[i];
            const int32_t pa = w_.nodePiece[node];
            const Vector3d A = at(X, node);
            if (!st_.pieceActive[pa] || (dom && !dom->owns(node))) return 0;  // (another rank's query point)
            // Branch-free tests (ListKernels.hpp): about one visited item in
            // five passes, unpredictably; more than KL pass: crowded, this
            // node queries the cells each step.  The grid's slots are visited
            // as before (cells in x-y-z order, descending items within a cell).
            int count = 0;
            // The neighbour pieces whose box, grown by the reach, holds the
            // node: flagged 64 at a time (most neighbours touch the piece
            // elsewhere, unpredictably for a branch), then visited in order.
            const int32_t q0 = st_.nbrStart[pa], q1 = st_.nbrStart[pa + 1];
            for (int32_t qb = q0; qb < q1 && count <= KL; qb += 64) {
                const int m = static_cast<int>(std::min<int32_t>(64, q1 - qb));
                const double Ad[3] = {A[0], A[1], A[2]};
                for (uint64_t near = boxesNear(Ad, nbrReach, nbrLo, nbrHi, qb, m); near && count <= KL;
                     near &= near - 1) {
                    const int32_t q = qb + std::countr_zero(near);
                    const int32_t pb = st_.nbrs[q];
                    const double reach = nbrReach[q];
                    const Vector3d qlo = A.array() - st_.itemReach, qhi = A.array() + st_.itemReach;
                    const CellGrid& g = st_.itemGrid[pb];
                    const int32_t* item = g.item();
                    const double *gx = g.x(), *gy = g.y(), *gz = g.z(), *gr = g.r();
                    const int c0 = count;
                    g.forRuns(qlo.data(), qhi.data(), [&](int32_t b, int32_t e) {
                        count = spheresWithin(Ad, reach, gx, gy, gz, gr, item, b, e, buf, count, KL);
                    });
                    const int32_t i0 = st_.itemStart[pb];
                    for (int k = c0; k < std::min(count, KL); ++k) buf[k] = st_.items[i0 + buf[k]];
                }
            }
            return count > KL ? -1 : count;
        };
#pragma omp parallel for schedule(dynamic, 1)
        for (int32_t chunk = chunk0; chunk < chunk1; ++chunk) {
            auto fill = static_cast<int32_t>(base + static_cast<std::size_t>(KL) * CH * chunk);
            for (int32_t i = CH * chunk; i < std::min(ns, CH * (chunk + 1)); ++i) {
                int32_t buf[KL + 8];
                const int count = nodeList(i, buf);
                std::copy_n(buf, std::max(0, count), &st_.listFlat[fill]);
                st_.listStart[i] = fill, st_.listCount[i] = count;
                fill += std::max(0, count);
            }
        }
        if (rebuild) {
            st_.listActive.assign(st_.pieceActive.begin(), st_.pieceActive.end());
            // lists now from the current positions (AwakeSet::moved2 no longer counts)
            std::fill(listsSinceSleep_.begin(), listsSinceSleep_.end(), 1);
            st_.listSkin = skin;
            st_.listTris = S.nTris();
            st_.listValid = true;
            ++st_.listBuilds;
            if (dom) listDomainVersion_ = dom->currentVersion();
        }
    }
    if (verlet && edgeRebuild && edgeLists) {
        // Each registered edge's candidate edges of higher pieces (each pair once).
        const int32_t ne = st_.registeredEdges();
        constexpr int KE = PieceContactState::kEdgeList;
        st_.edgeList.resize(KE * static_cast<std::size_t>(ne));
        st_.edgeListCount.assign(ne, 0);
#pragma omp parallel for schedule(dynamic, 64)
        for (int32_t ie = 0; ie < ne; ++ie) {
            const int32_t pa = S.edgePiece[st_.edgeItems[ie]];
            int count = 0;
            for (int32_t q = st_.nbrStart[pa]; q < st_.nbrStart[pa + 1] && count >= 0; ++q) {
                const int32_t pb = st_.nbrs[q];
                if (pb < pa) continue;
                // pb's registered edge boxes lie within its box (its surface
                // nodes +- r) grown by half the skin: a piece whose box, grown
                // by r + skin to spare rounding, misses this edge's box has
                // none that overlaps it (most of the neighbours touch a piece
                // elsewhere).
                const double m = st_.pieceRadius[pb] + grow;
                const double* lo = &st_.edgeLo[3 * ie];
                const double* hi = &st_.edgeHi[3 * ie];
                bool overlap = true;
                for (int d = 0; d < 3 && overlap; ++d)
                    overlap = lo[d] <= w_.bounds.hi[3 * pb + d] + m && w_.bounds.lo[3 * pb + d] - m <= hi[d];
                if (!overlap) continue;
                const int32_t j0 = st_.edgeStart[pb];
                st_.edgeGrid[pb].forOverlapping(&st_.edgeLo[3 * ie], &st_.edgeHi[3 * ie], [&](int32_t local) {
                    if (count < 0) return;
                    if (count == KE) {
                        count = -1;  // crowded: this edge queries the cells each step
                        return;
                    }
                    st_.edgeList[static_cast<std::size_t>(KE) * ie + count++] = j0 + local;
                });
            }
            st_.edgeListCount[ie] = count;
        }
    }
    if (!verlet) st_.listValid = false;

    broadSeconds_ = omp_get_wtime() - t0;
    surfaceSpins();

    beginStartCheck();
    threadDeep_.assign(omp_get_max_threads(), DeepContact{});  // (same size each step: no allocation)
    // The kinds of the table, in order (ContactKind.hpp).
    KindStep ks{dt, w_.settings.frictionOn, w_, *this, st_, st_.threadForce};
    for (Kind& k : kinds_) {
        if (!kindOn(k)) continue;
        const double tk = omp_get_wtime();
        k.contacts = k.kernel->run(ks);
        k.seconds = omp_get_wtime() - tk;
    }
    finishStartCheck();
    for (const DeepContact& d : threadDeep_) maxDepthRatio_ = std::max(maxDepthRatio_, d.ratio);
    if (maxDepthRatio_ > 1) checkContactDepth(dt);
    const double tSum = omp_get_wtime();
    // Sum the thread buffers into the node contact forces.
    // (Under MPI the ghosts' too: their owners get them back, Domain.hpp.)
    const std::vector<int32_t>& summed = dom ? dom->currentSurf() : w_.sleeping.awakeSurf();
    const auto ns = all ? static_cast<int32_t>(w_.surfNodes.size()) : static_cast<int32_t>(summed.size());
    // (Raw pointers in locals: through w_'s columns and the vector of
    // vectors, every store to a double reloaded them.)
    double* Fc = w_.contacts.force.data();
    const int32_t* surfNodes = w_.surfNodes.data();
    const int32_t* summedIds = summed.data();
    const double* const* tf = st_.threadForceData.data();
    // With the forces, each node's contact load (ContactLoad.hpp), added to
    // the obstacles' on it; its stable step is taken once the spheres' are
    // in too (contactStepLimit; under MPI by the owners, ownedStepLimit).
    const double* const* tl = st_.threadLoadData.data();
    const int32_t* nodePiece = w_.nodePiece.data();
    double* const L = w_.contacts.beginLoad();
#pragma omp parallel for schedule(static) num_threads(nth)
    for (int32_t j = 0; j < ns; ++j) {
        const int32_t s = all ? j : summedIds[j];
        const int32_t node = surfNodes[s];
        double* f = Fc + 3 * node;
        double k = 0, c = 0;
        for (int th = 0; th < nth; ++th) {
            for (int d = 0; d < 3; ++d) f[d] += tf[th][3 * s + d];
            k += tl[th][2 * s], c += tl[th][2 * s + 1];
        }
        // (A sleeping piece's rows are neither zeroed nor moved: serially
        // only awake nodes are summed, so only theirs count under MPI too.)
        if (all || !w_.sleeping.asleep(static_cast<std::size_t>(nodePiece[node]))) L[2 * s] += k, L[2 * s + 1] += c;
    }
    sumSeconds_ = omp_get_wtime() - tSum;
    maxOverlap_ = ks.maxOverlap;
    const double eDamp = ks.eDamp, eSlip = ks.eSlip;
    if (w_.settings.trackEnergy) {  // (the elastic energy is summed per piece)
        w_.energy.contactDamping += eDamp;
        w_.energy.friction += eSlip;
    }
}

}  // namespace qdem

namespace qdem {

void PieceContactPhase::stateColumns(StateColumns& c) {
    c.add("ppKey", st_.ppKey, Rows::SurfaceNode);
    c.add("ppPiece", st_.ppPiece, Rows::SurfaceNode);
    c.add("ppShear", st_.ppShear, Rows::SurfaceNode);
    c.add("ppRef", st_.ppRef, Rows::SurfaceNode);
    c.add("ppStamp", st_.ppStamp, Rows::SurfaceNode);
    c.add("eeOther", st_.eeOther, Rows::Edge);
    c.add("eeSide", st_.eeSide, Rows::Edge);
    c.add("eeShear", st_.eeShear, Rows::Edge);
    c.add("eeRef", st_.eeRef, Rows::Edge);
    c.add("eeStamp", st_.eeStamp, Rows::Edge);
    c.add("eePiece", st_.eePiece, Rows::Edge, false);  // saved as a field (older files lack it)
    for (Kind& k : kinds_) k.kernel->stateColumns(c);
}

double PieceContactPhase::nodeStepLimit(int32_t node, double k, double c) const {
    const std::size_t p = static_cast<std::size_t>(w_.nodePiece[node]);
    if (w_.pieceElementW2.size() != w_.pieces.size() || w_.pieceElementRate.size() != w_.pieces.size())
        return std::numeric_limits<double>::infinity();
    const double w2 = w_.pieceElementW2[p] + k / w_.mass[node], w = std::sqrt(w2);
    return leapfrogLimit(w, (w_.pieceElementRate[p] + c / w_.mass[node]) / (2 * w));
}

void PieceContactPhase::ownedStepLimit() {
    stepLimit_ = ContactStepLimit{};
    const Domain* dom = w_.domain.built();
    if (!w_.contacts.loadActive || !dom) return;
    ContactStepLimit& best = stepLimit_;
    for (const int32_t s : dom->currentSurf()) {
        const int32_t node = w_.surfNodes[s];
        const double k = w_.contacts.load[2 * s], c = w_.contacts.load[2 * s + 1];
        if (!(k > 0) || !dom->owns(node) || w_.sleeping.asleep(static_cast<std::size_t>(w_.nodePiece[node]))) continue;
        const double limit = nodeStepLimit(node, k, c);
        if (limit < best.limit || (limit == best.limit && node < best.node))
            best = ContactStepLimit{limit, node, w_.nodePiece[node], k, c, w_.iter};
    }
}

void PieceContactPhase::packStepLimit(double* v, int rank) const {
    const ContactStepLimit& l = stepLimit_;
    double* r = v + static_cast<std::ptrdiff_t>(kLimitValues) * rank;
    r[0] = l.limit, r[1] = l.node, r[2] = l.piece, r[3] = l.stiffness, r[4] = l.dashpot;
    r[5] = static_cast<double>(l.step);
}

void PieceContactPhase::unpackStepLimit(const double* v, int nRanks) {
    // (Each rank wrote its own slots, the others zeros: the sums are the values.)
    ContactStepLimit best;
    for (int q = 0; q < nRanks; ++q) {
        const double* r = v + static_cast<std::ptrdiff_t>(kLimitValues) * q;
        const auto node = static_cast<int32_t>(r[1]);
        if (node < 0 || !(r[0] <= best.limit)) continue;
        if (r[0] < best.limit || node < best.node)
            best = ContactStepLimit{r[0], node, static_cast<int32_t>(r[2]), r[3], r[4], static_cast<long>(r[5])};
    }
    stepLimit_ = best;
}

void PieceContactPhase::checkStepLimit(double dt) const {
    const ContactStepLimit& l = stepLimit_;
    const double m = w_.mass[l.node];
    throw StabilityError(cat(
        "QDEM: during step ", l.step + 1, " the contacts on node ", l.node - w_.pieces[l.piece].nodeBegin,
        " of piece ", l.piece, " make its stable time step ", l.limit, " s, below O.dt = ", dt, " s by a factor ",
        dt / l.limit, ": the springs on it, as a node pressed on another piece, a wall, box or facet, and as a "
        "corner of the faces other pieces' nodes and YADE spheres press on, load it with ", l.stiffness,
        " N/m on its ", m, " kg (with its elements' ", std::sqrt(w_.pieceElementW2[l.piece]),
        " rad/s). The stable step before the run counts one contact per node (doc/formulation.md, \"Stable time "
        "step\"). Lower O.dt below ", l.limit, " s, or make the contact softer (a smaller QdemMat young or radius)."));
}

void PieceContactPhase::piecesAdded() {
    stepLimit_ = ContactStepLimit{};
    st_.resizeHistory(w_.surfNodes.size(), w_.surface.nEdges());
    for (Kind& k : kinds_) k.kernel->piecesAdded(w_);
    frozen_.resize(w_.pieces.size(), 0);
    normalsFresh_.resize(w_.pieces.size(), 0);
    sleepSeen_.resize(w_.pieces.size(), 0);
    listsSinceSleep_.resize(w_.pieces.size(), 0);
    startChecked_.resize(w_.pieces.size(), 0);
}

void PieceContactPhase::noteSleepChanges() {
    for (std::size_t p = 0; p < sleepSeen_.size(); ++p) {
        const uint32_t c = w_.sleeping.changes(p);
        if (c == sleepSeen_[p]) continue;
        sleepSeen_[p] = c;
        frozen_[p] = normalsFresh_[p] = listsSinceSleep_[p] = 0;
    }
}

// The edge-edge partners' pieces, and the format of the history keys: states
// saved before the keys were stable ids (no "eePiece") held global triangle
// and edge ids, converted here.
void PieceContactPhase::saveFields(WorldState& s) const { s.put("eePiece", st_.eePiece.data(), st_.eePiece.size()); }

void PieceContactPhase::checkFields(const WorldState& s) const {
    if (s.fields.count("eePiece") > 0) s.check<int32_t>("eePiece", st_.eePiece.size());
}

void PieceContactPhase::loadFields(const WorldState& s) {
    const SurfaceIndex& S = w_.surface;
    if (s.fields.count("eePiece") > 0) {
        s.get("eePiece", st_.eePiece.data(), st_.eePiece.size());
        return;
    }
    for (std::size_t k = 0; k < st_.ppKey.size(); ++k)
        if (st_.ppKey[k] >= 0) st_.ppKey[k] -= 8 * S.pieceTriStart[st_.ppPiece[k]];
    for (std::size_t k = 0; k < st_.eeOther.size(); ++k) {
        const int32_t e = st_.eeOther[k];
        st_.eePiece[k] = e >= 0 ? S.edgePiece[e] : -1;
        if (e >= 0) st_.eeOther[k] = e - S.pieceEdgeStart[S.edgePiece[e]];
    }
}

void PieceContactPhase::stateLoaded() {
    stepLimit_ = ContactStepLimit{};
    std::fill(frozen_.begin(), frozen_.end(), 0);
    std::fill(normalsFresh_.begin(), normalsFresh_.end(), 0);
    st_.listValid = false;  // Verlet lists: rebuilt from the loaded positions
    startChecked_.assign(w_.pieces.size(), 1);  // a restart, not a set-up: contacts go on as saved
}

}  // namespace qdem
