// A piece started inside another piece so deep that no contact sees it is
// refused, as one started inside a wall, box or facet is
// (ObstacleStartOverlap.cpp).  Pieces that start interpenetrated where the
// contact search reaches them separate, without gaining energy
// (doc/contacts.md §5, test_hard_cases.py): a packing generated with
// overlaps relaxes, as YADE users expect.  But two 0.4 m cubes of 0.1 m
// cells placed 10 or 30 cm into each other stayed interpenetrated for good:
// their faces meet along planes of nodes, no node centre lies behind a face
// within reach of it, and the contacts found later count as born deep.  A
// piece wholly inside another is the same case.  Nothing was said.
//
// Checked once per piece, the first step after it is added.  Per pair of
// neighbouring pieces with a new one: the surface nodes of each that lie
// deepest inside the other's box (by more than the contact reach, so
// touching pieces have none), at most kSamples, are tested by winding
// number; nodes inside, in a pair where point-polygon found no node centre
// inside the other piece this step, are refused.  A loaded state is a
// restart, not a set-up: never refused.
//
// Deep overlap during a run (checked every QdemEngine.checkPeriod steps,
// World::checkDeepOverlap, by the same scan): contacts too soft for their
// load (kn ~ E r per node) let a node sink deeper into the other piece than
// the contact's reach r_a + r_b.  No contact sees it any more and the pieces
// interpenetrate for good - a very soft cube sank through a stiff one and
// below the floor with no error.  A surface node inside the other piece's
// closed surface (winding number) and farther than the reach from it stops
// the run (StabilityError naming both pieces, the node, its depth against
// the reach and the fixes).  Cheap: per neighbour pair only the nodes deeper
// than the reach inside the other's box are candidates (none for pieces
// resting on each other), at most 16 of them tested, each against the other
// piece's triangles: 0.05 % of the 100 steps between checks on the 27-cube
// stack, 0.5 % with 27 randomly rotated cubes whose boxes overlap.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>

#include <Eigen/Geometry>

#include "../contact/Geometry.hpp"
#include "../contact/WindingNumber.hpp"
#include "../core/Errors.hpp"
#include "../parallel/Domain.hpp"
#include "PieceContactPhase.hpp"

namespace qdem {

namespace {


}  // namespace

void PieceContactPhase::beginStartCheck() {
    startChecked_.resize(w_.pieces.size(), 0);
    startPending_ = false;
    for (std::size_t i = 0; i < w_.pieces.size(); ++i) startPending_ = startPending_ || !startChecked_[i];
    threadStartSeen_.resize(startPending_ ? omp_get_max_threads() : 0);
    for (auto& v : threadStartSeen_) v.clear();
    threadStartPress_.resize(startPending_ ? omp_get_max_threads() : 0);
    for (auto& v : threadStartPress_) v.clear();
}

double PieceContactPhase::meanSurfaceEdge(int32_t piece) const {
    const SurfaceIndex& S = w_.surface;
    const double* X = w_.pos.data();
    double sum = 0;
    const int32_t e0 = S.pieceEdgeStart[piece], e1 = S.pieceEdgeStart[piece + 1];
    for (int32_t e = e0; e < e1; ++e) {
        const int32_t a = S.edge[2 * e], b = S.edge[2 * e + 1];
        sum += std::sqrt(std::pow(X[3 * a] - X[3 * b], 2) + std::pow(X[3 * a + 1] - X[3 * b + 1], 2) +
                         std::pow(X[3 * a + 2] - X[3 * b + 2], 2));
    }
    return e1 > e0 ? sum / (e1 - e0) : 0.0;
}

void PieceContactPhase::warnStartPress() {
    // The pairs of pieces that can touch, each once, lower id first; the
    // springs' energy summed over the threads.
    std::vector<std::pair<int32_t, int32_t>> pairs;
    for (std::size_t q = 0; q + 1 < st_.pairs.size(); q += 2)
        if (st_.pairs[q] < st_.pairs[q + 1]) pairs.emplace_back(st_.pairs[q], st_.pairs[q + 1]);
    std::sort(pairs.begin(), pairs.end());
    const auto nq = static_cast<int>(pairs.size());
    std::vector<double> energy(nq, 0.0), overlap(nq, 0.0);
    for (const auto& v : threadStartPress_)
        for (const StartPress& p : v) {
            const auto it = std::lower_bound(pairs.begin(), pairs.end(), std::make_pair(p.a, p.b));
            if (it == pairs.end() || *it != std::make_pair(p.a, p.b)) continue;
            energy[it - pairs.begin()] += p.energy;
            overlap[it - pairs.begin()] = std::max(overlap[it - pairs.begin()], p.overlap);
        }
    // Under MPI each rank sums its own nodes' springs and says so: no
    // collective here (a rank whose start check or obstacle check refused
    // the set-up is not in this call, and would leave the others waiting).
    const Domain* dom = w_.domain.built();
    for (int q = 0; q < nq; ++q) {
        const int32_t a = pairs[q].first, b = pairs[q].second;
        if (startChecked_[a] && startChecked_[b]) continue;
        const double ra = w_.materials[w_.pieces[a].material].radius;
        const double rb = w_.materials[w_.pieces[b].material].radius;
        // Pieces resting on each other press their springs by m g / (n kn),
        // a small part of the reach; a quarter of it is a set-up (walls: the same).
        if (!(overlap[q] > 0.25 * (ra + rb))) continue;
        // Released, the springs throw the pieces apart at up to
        // sqrt(2 E / mu), mu the pieces' reduced mass (energy into relative motion).
        const double ma = w_.pieces[a].mass, mb = w_.pieces[b].mass;
        const double speed = std::sqrt(2 * energy[q] * (ma + mb) / (ma * mb));
        std::ostringstream m;
        m.precision(3);
        m << "qdem: pieces " << a << " and " << b << " start pressed into each other (contact overlap up to "
          << overlap[q] << " m against their reach r_a + r_b = " << ra + rb << " m";
        if (overlap[q] > ra + rb) m << ": node centres " << overlap[q] - (ra + rb) << " m inside";
        m << "): their contact springs hold " << energy[q] << " J, enough to throw them apart at up to " << speed
          << " m/s relative speed";
        if (dom) m << " (the springs of this rank's nodes, rank " << dom->rank() << " of " << dom->size() << ")";
        m << ". Pieces placed overlapping are pushed apart by that stored energy, not "
             "relaxed gently. A piece's surface is its nodes' spheres, r outside the mesh: to start them at rest, "
             "place their meshes at least r_a + r_b = "
          << ra + rb << " m apart (a packing: generate it without overlaps, or let it settle under damping).";
        startWarnings_.push_back(m.str());
    }
}

PieceContactPhase::DeepNode PieceContactPhase::deepestInside(
    bool periodic, const std::vector<std::pair<int32_t, int32_t>>& pushed,
    std::vector<std::pair<int32_t, int32_t>>* stillDeep) const {
    constexpr int kSamples = 16;
    const auto isPushed = [&](int32_t a, int32_t b) {
        return std::binary_search(pushed.begin(), pushed.end(), std::make_pair(std::min(a, b), std::max(a, b)));
    };
    // Which of two finds is reported: the start check the deepest node, the
    // periodic one the node deepest beyond its pair's reach (then the lower node).
    const auto better = [&](const DeepNode& f, double key, int32_t n) {
        const double fKey = periodic ? f.depth - f.reach : f.depth;
        return f.node < 0 || key > fKey || (key == fKey && n < f.node);
    };
    const SurfaceIndex& S = w_.surface;
    const double* X = w_.pos.data();
    // The start check runs inside the step: each rank its own nodes.  The
    // periodic one after gatherAll: every rank every node, the same answer.
    const Domain* dom = periodic ? nullptr : w_.domain.built();
    const auto nq = static_cast<int32_t>(st_.pairs.size() / 2);
    std::vector<DeepNode> deep(omp_get_max_threads());
    std::vector<std::vector<std::pair<int32_t, int32_t>>> threadDeep(periodic ? omp_get_max_threads() : 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (int32_t q = 0; q < nq; ++q) {
        const int32_t a = st_.pairs[2 * q], b = st_.pairs[2 * q + 1];
        if (!periodic && ((startChecked_[a] && startChecked_[b]) || isPushed(a, b))) continue;
        const PieceInfo& pa = w_.pieces[a];
        const double ra = w_.materials[pa.material].radius, rb = w_.materials[w_.pieces[b].material].radius;
        const double reach = ra + rb;
        double lo[3], hi[3];  // b's box (its nodes), less the reach
        for (int d = 0; d < 3; ++d)
            lo[d] = w_.bounds.lo[3 * b + d] + rb + reach, hi[d] = w_.bounds.hi[3 * b + d] - rb - reach;
        std::pair<double, int32_t> top[kSamples];  // (depth in b's box, node), deepest first
        int nTop = 0;
        for (int32_t s = pa.surfBegin; s < pa.surfEnd; ++s) {
            const int32_t n = w_.surfNodes[s];
            if (dom && !dom->owns(n)) continue;
            double inBox = INFINITY;
            for (int d = 0; d < 3; ++d) inBox = std::min({inBox, X[3 * n + d] - lo[d], hi[d] - X[3 * n + d]});
            if (!(inBox > 0)) continue;
            if (nTop == kSamples && inBox <= top[nTop - 1].first) continue;
            int k = nTop < kSamples ? nTop++ : nTop - 1;
            for (; k > 0 && top[k - 1].first < inBox; --k) top[k] = top[k - 1];
            top[k] = {inBox, n};
        }
        DeepNode& f = deep[omp_get_thread_num()];
        for (int k = 0; k < nTop; ++k) {
            const int32_t n = top[k].second;
            const Eigen::Map<const Eigen::Vector3d> x(X + 3 * n);
            if (!(std::fabs(windingNumber(x, S.tri.data(), S.pieceTriStart[b], S.pieceTriStart[b + 1], X)) > 0.5))
                continue;
            double depth = INFINITY;  // to b's surface
            for (int32_t t = S.pieceTriStart[b]; t < S.pieceTriStart[b + 1]; ++t) {
                const int32_t* c = &S.tri[3 * t];
                depth = std::min(depth, (x - closestOnTriangle(x, Eigen::Map<const Eigen::Vector3d>(X + 3 * c[0]),
                                                               Eigen::Map<const Eigen::Vector3d>(X + 3 * c[1]),
                                                               Eigen::Map<const Eigen::Vector3d>(X + 3 * c[2]))
                                                 .point)
                                            .norm());
            }
            if (periodic && !(depth > reach)) continue;  // within the contact's sight: it pushes the node out
            if (periodic && isPushed(a, b)) {  // started interpenetrated, not yet out: still deep
                threadDeep[omp_get_thread_num()].emplace_back(std::min(a, b), std::max(a, b));
                break;
            }
            ++f.count;
            if (better(f, periodic ? depth - reach : depth, n))
                f.node = n, f.pa = a, f.pb = b, f.depth = depth, f.reach = reach;
        }
    }
    if (stillDeep) {
        stillDeep->clear();
        for (const auto& v : threadDeep) stillDeep->insert(stillDeep->end(), v.begin(), v.end());
        std::sort(stillDeep->begin(), stillDeep->end());
        stillDeep->erase(std::unique(stillDeep->begin(), stillDeep->end()), stillDeep->end());
    }
    DeepNode found;
    for (const DeepNode& t : deep) {
        found.count += t.count;
        if (t.node >= 0 && better(found, periodic ? t.depth - t.reach : t.depth, t.node))
            found.node = t.node, found.pa = t.pa, found.pb = t.pb, found.depth = t.depth, found.reach = t.reach;
    }
    return found;
}

void PieceContactPhase::finishStartCheck() {
    if (!startPending_) return;
    startPending_ = false;
    std::vector<std::pair<int32_t, int32_t>> seen;  // pairs point-polygon will push apart
    for (const auto& v : threadStartSeen_) seen.insert(seen.end(), v.begin(), v.end());
    std::sort(seen.begin(), seen.end());
    const DeepNode found = deepestInside(false, seen, nullptr);
    // Seen, but deeper than a cell of the other piece (its mean surface
    // edge): the documented limit of what the contact pushes apart (the
    // search reaches about a cell behind a face).  Two 0.2 m cubes of 5 cm
    // cells 10 cm into each other held 205 J and stayed: the nodes in the
    // middle are pushed both ways.  Refused like a piece inside a wall.
    const DeepNode deep = found.node < 0 ? deepestInside(false, {}, nullptr) : found;
    if (found.node < 0 && deep.node >= 0) {
        const double cell = meanSurfaceEdge(deep.pb);
        if (deep.depth > cell) {
            std::ostringstream m;
            m.precision(3);
            m << "piece " << deep.pa << " starts " << deep.depth << " m inside piece " << deep.pb << ": node "
              << deep.node - w_.pieces[deep.pa].nodeBegin << " of piece " << deep.pa << " is " << deep.depth
              << " m deep, more than a cell of piece " << deep.pb << " (its mean surface edge, " << cell
              << " m): the contact does not push pieces that deep into each other apart (nodes in the middle are "
                 "pushed both ways and hold them, or the springs' stored energy throws them apart). Place them "
                 "apart (by at least "
              << deep.depth + deep.reach << " m: that depth plus the contact reach " << deep.reach
              << " m), so that the meshes are at least the reach apart";
            throw InputError(m.str());
        }
    }
    if (found.node < 0) {  // accepted: these pairs separate, and the periodic check lets them until they are out
        warnStartPress();
        // (A refused set-up stays unchecked: a script that catches the error
        // and runs again without moving the pieces far enough apart is
        // refused again; it ran on until the periodic check.)
        std::fill(startChecked_.begin(), startChecked_.end(), 1);
        std::vector<std::pair<int32_t, int32_t>> all;
        std::set_union(startOverlap_.begin(), startOverlap_.end(), seen.begin(), seen.end(), std::back_inserter(all));
        all.erase(std::unique(all.begin(), all.end()), all.end());
        startOverlap_.swap(all);
        return;
    }
    const double reach = found.reach;
    std::ostringstream m;
    m.precision(3);
    m << "piece " << found.pa << " starts inside piece " << found.pb << ", deeper than the contact can see: node "
      << found.node - w_.pieces[found.pa].nodeBegin << " of piece " << found.pa << " is " << found.depth
      << " m inside, and no node of either lies inside the other within the contact's reach of its surface, so "
         "no contact would push them apart and they would stay one inside the other. Place them apart (by at "
         "least "
      << found.depth + reach << " m: that depth plus the contact reach " << reach
      << " m), or overlapping by less than a cell, where the contact separates them";
    throw InputError(m.str());
}

void PieceContactPhase::checkDeepOverlap(long iter, double time) {
    if (w_.pieces.size() < 2 || !anyKindOn()) return;  // (no contacts: st_.pairs is not kept)
    std::vector<std::pair<int32_t, int32_t>> stillDeep;
    const DeepNode found = deepestInside(true, startOverlap_, &stillDeep);
    startOverlap_.swap(stillDeep);  // a pair started interpenetrated is watched like any other once it is out
    if (found.node < 0) return;
    const PieceInfo& pa = w_.pieces[found.pa];
    const double ra = w_.materials[pa.material].radius, rb = w_.materials[w_.pieces[found.pb].material].radius;
    std::ostringstream m;
    m.precision(3);
    m << "QDEM: at step " << iter << " (t=" << time << " s) piece " << found.pa << " has sunk into piece " << found.pb
      << " deeper than their contact can see: node " << found.node - pa.nodeBegin << " of piece " << found.pa
      << " (surface node, global " << found.node << ") is " << found.depth << " m inside piece " << found.pb
      << ", beyond the contact reach r_a + r_b = " << ra << " + " << rb << " = " << found.reach << " m ("
      << found.count << " such node(s) found). No contact pushes it out any more: the pieces interpenetrate for "
      << "good and the result would be silently wrong. The contact is too soft for the load it carries (kn ~ E r "
         "per node). Use a stiffer material (QdemMat young), a larger radius r so that the reach covers the "
         "overlap, a smaller impact speed, or a finer mesh (more nodes share the load); pieces placed into "
         "each other must be apart, or overlap by less than the reach, by the first check "
         "period "
         "(doc/hard_cases.md, \"Deep overlap\")";
    throw StabilityError(m.str());
}

}  // namespace qdem
