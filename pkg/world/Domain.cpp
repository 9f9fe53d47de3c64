// Domain (pkg/parallel/Domain.hpp, where the phases see it as this rank's
// share and its exchanges) moves the World's rows between ranks: its
// implementation reads and writes the World, so it sits in the world layer.
#include "../parallel/Domain.hpp"

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "../core/Errors.hpp"
#include "Phases.hpp"
#include "World.hpp"
#include <cmath>

namespace qdem {

Domain::Domain(World& w, std::shared_ptr<Communicator> comm) : w_(w), comm_(std::move(comm)) {}

PartitionInput Domain::partitionInput(World& w, std::vector<int32_t>& pieceBegin, std::vector<double>& extra) {
    pieceBegin.assign(w.pieces.size() + 1, 0);
    for (std::size_t p = 0; p < w.pieces.size(); ++p) pieceBegin[p + 1] = w.pieces[p].nodeEnd;
    PartitionInput in;
    in.nNodes = static_cast<int32_t>(w.nNodes());
    in.nTets = static_cast<int32_t>(w.nTets());
    in.pos = w.pos.data();
    in.tetNodes = w.tetNodes.data();
    in.nPieces = static_cast<int32_t>(w.pieces.size());
    in.pieceNodeBegin = pieceBegin.data();
    // The contact work of each node: its contacts of the last step, as the
    // phases count them in their histories (Phase::addLoadWeights).
    extra.clear();
    if (w.settings.contactWork > 0 && w.iter > 0) {
        extra.assign(w.nNodes(), 0.0);
        for (const Phase* p : std::as_const(w).phases()) p->addLoadWeights(extra.data(), w.settings.contactWork);
        in.nodeExtraWeight = extra.data();
    }
    return in;
}

Partition splitWorld(const PartitionInput& in, PartitionOptions opt, int nRanks) {
    if (opt.firstRank < 0 || opt.firstRank >= nRanks)
        throw InputError("QDEM under MPI: the first rank given a share (" + std::to_string(opt.firstRank) +
                         ") must lie in [0, " + std::to_string(nRanks - 1) + "]: there are " + std::to_string(nRanks) +
                         " ranks");
    opt.nRanks = nRanks - opt.firstRank;
    Partition p = partitionHilbert(in, opt);
    shiftRanks(p, opt.firstRank);
    return p;
}

void Domain::build(const PartitionOptions& opt) {
    std::vector<int32_t> pieceBegin;
    std::vector<double> extra;
    const PartitionInput in = partitionInput(w_, pieceBegin, extra);
    // Every rank holds the same positions here (the same script built them,
    // or gatherAll made them so): every rank computes the same split.
    part_ = splitWorld(in, opt, size());
    checkSameEverywhere(in);
    halo_ = elementHalo(part_, in, rank());
    ghostForce_.assign(3 * w_.nNodes(), 0.0);
    const std::size_t nb = halo_.neighbours.size();
    sendBuf_.assign(nb, {});
    recvBuf_.assign(nb, {});
    elementGhost_.assign(w_.nNodes(), 0);
    for (const auto& g : halo_.recv)
        for (const int32_t n : g) elementGhost_[n] = 1;
    contactHalo_ = (w_.pieces.size() > 1 && w_.phases_->pieceContact.anyKindOn()) || sphereRadius() > 0;
    // The owned nodes the contact halo may send: those the contact phase
    // reads of another piece.  With the default broad phase, the surface
    // nodes; with the seed's cases (Settings.hpp BroadPhase) the nodes of the
    // tetrahedra registered: every tet (A) or the surface tets (B, C), whose
    // fourth node is interior.  A tet is only registered where all its nodes
    // are current (PieceContactPhase.cpp).
    const SurfaceIndex& S = w_.surfaceIndex();
    const BroadPhase bp = w_.settings.broadPhase;
    std::vector<uint8_t> sent(w_.nNodes(), 0);
    for (const int32_t n : halo_.ownedNodes) sent[n] = S.surfIndexOfNode[n] >= 0 || bp == BroadPhase::AllTets;
    haloTets_.clear();
    if (bp == BroadPhase::SurfaceTets || bp == BroadPhase::SurfaceFaces) {
        for (const int32_t t : S.surfTets)
            for (int k = 0; k < 4; ++k) {
                const int32_t n = w_.tetNodes[4 * t + k];
                if (owns(n)) sent[n] = 1;
            }
        for (const int32_t t : S.surfTets)
            if (ownsTet(t)) haloTets_.push_back(t);
    } else if (bp == BroadPhase::AllTets) {
        haloTets_ = halo_.ownedTets;
    }
    ownedSurf_.clear();
    for (const int32_t n : halo_.ownedNodes)
        if (sent[n]) ownedSurf_.push_back(n);
    cNbr_.clear(), cNbrPrev_.clear(), cRecv_.clear(), cSend_.clear();
    ghostTouched_.clear();
    built_ = everBuilt_ = true;
    markCurrent();
    if (contactHalo_) sendContactHalo();  // collective: every rank builds at the same step
}

namespace {

// FNV-1a over raw bytes.
struct Fnv {
    uint64_t h = 1469598103934665603ull;
    void bytes(const void* p, std::size_t n) {
        const auto* b = static_cast<const uint8_t*>(p);
        for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
    }
    template <class V>
    void vec(const V& v) {
        const std::size_t n = v.size();
        bytes(&n, sizeof n);
        if (n) bytes(v.data(), n * sizeof(v.data()[0]));
    }
    void real(double v) { bytes(&v, sizeof v); }
};

// Which of the hashes h[0..n) differ between ranks (bit i: h[i] does).  One
// reduction for all: two exact 32-bit halves of each (they fit a double),
// compared by min and max (the max as the min of the negatives).
uint32_t differing(Communicator& comm, const uint64_t* h, int n) {
    std::vector<double> v(4 * static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        v[4 * i] = double(h[i] >> 32), v[4 * i + 1] = double(h[i] & 0xffffffffu);
        v[4 * i + 2] = -v[4 * i], v[4 * i + 3] = -v[4 * i + 1];
    }
    comm.allreduceMin(v.data(), static_cast<int>(v.size()));
    uint32_t bits = 0;
    for (int i = 0; i < n; ++i)
        if (v[4 * i] != -v[4 * i + 2] || v[4 * i + 1] != -v[4 * i + 3]) bits |= 1u << i;
    return bits;
}

// "a, b and c" of the names whose bit is set.
std::string namesOf(uint32_t bits, const char* const* names, int n) {
    std::vector<std::string> on;
    for (int i = 0; i < n; ++i)
        if (bits >> i & 1u) on.emplace_back(names[i]);
    std::string r;
    for (std::size_t i = 0; i < on.size(); ++i)
        r += (i == 0 ? "" : i + 1 == on.size() ? " and " : ", ") + on[i];
    return r;
}

}  // namespace

// The split is computed by every rank alone: it must come out the same
// everywhere, or the halos do not match and messages would be cut.  A
// script that builds other scenes on other ranks (unseeded random positions
// or velocities, a load set on one rank) is refused on every rank, naming
// what differs.  At the first split every rank's whole node state comes from
// its own copy of the script, so all of it is compared; at a later split
// (pieces added, a rebalance) only what gatherAll made whole (positions).
void Domain::checkSameEverywhere(const PartitionInput& in) const {
    enum { kPos, kVel, kLoad, kMass, kN };
    static const char* const names[kN] = {"node positions", "node velocities",
                                          "loads (extForce) or blocked DOFs", "masses (densities)"};
    Fnv f[kN];
    f[kPos].bytes(&in.nNodes, sizeof in.nNodes);
    f[kPos].bytes(&in.nTets, sizeof in.nTets);
    f[kPos].bytes(in.pos, 3 * sizeof(double) * static_cast<std::size_t>(in.nNodes));
    f[kPos].vec(part_.nodeOwner);
    if (!everBuilt_) {
        f[kVel].vec(w_.vel);
        f[kLoad].vec(w_.extForce), f[kLoad].vec(w_.blocked);
        f[kMass].vec(w_.mass);
    }
    const uint64_t h[kN] = {f[0].h, f[1].h, f[2].h, f[3].h};
    const uint32_t bits = differing(*comm_, h, kN);
    if (bits)
        throw InputError("QDEM under MPI: the ranks hold different scenes (their " + namesOf(bits, names, kN) +
                         " differ), so they cannot share one split. Every rank must build the same scene: seed "
                         "random numbers alike on every rank (e.g. random.seed(1) before placing pieces or "
                         "drawing velocities), and change pieces on every rank, not on one");
}


void Domain::agreeOnCall(Call c) const {
    static const char* const names[] = {
        "at the end of the script", "in a step (O.run, O.step)",
        "in gatherAll (a VtkRecorder frame, a piece array read, QdemEngine's gather)",
        "in gatherState (O.save, qdem.saveState)", "in a rebalance"};
    double v[2] = {double(static_cast<int>(c)), -double(static_cast<int>(c))};
    comm_->allreduceMin(v, 2);
    const int lo = static_cast<int>(v[0]), hi = static_cast<int>(-v[1]);
    if (lo != hi)
        throw InputError(std::string("QDEM under MPI: the ranks reached different collective operations: some are ") +
                         names[lo] + ", others " + names[hi] +
                         ", so each would wait for the other for good. Every rank runs the same script: give every "
                         "rank the same O.run steps, and call O.save, qdem.saveState, VtkRecorder and piece reads on "
                         "every rank, not inside `if rank == 0:` (rank 0 alone writes the files)");
}

void Domain::checkYadeAlike(double dt) const {
    enum { kBodies, kDt, kGravity, kSettings, kMaterials, kN };
    static const char* const names[kN] = {"YADE bodies (walls, boxes, facets or spheres, or their states)",
                                          "time steps (O.dt)", "gravity (NewtonIntegrator.gravity)",
                                          "QdemEngine settings", "materials"};
    Fnv f[kN];
    const SphereSet& S = w_.spheres;
    f[kBodies].vec(S.id), f[kBodies].vec(S.radius), f[kBodies].vec(S.mass), f[kBodies].vec(S.pairStart);
    f[kBodies].vec(S.pairPiece), f[kBodies].vec(S.pos), f[kBodies].vec(S.vel), f[kBodies].vec(S.angVel), f[kBodies].vec(S.spinOffset);
    const std::size_t no = w_.obstacles.size();
    f[kBodies].bytes(&no, sizeof no);
    for (const Obstacle& o : w_.obstacles) {
        f[kBodies].bytes(&o.bodyId, sizeof o.bodyId);
        f[kBodies].bytes(o.pos.data(), 3 * sizeof(double));
        f[kBodies].bytes(o.vel.data(), 3 * sizeof(double));
    }
    f[kDt].real(dt);
    for (int d = 0; d < 3; ++d) f[kGravity].real(w_.gravity[d]);
    // Field by field (not the struct's bytes: its padding is undefined).
#define QDEM_HASH_SETTING(T, name, engineName, def, range, doc) \
    {                                                           \
        const T v = w_.settings.name;                           \
        f[kSettings].bytes(&v, sizeof v);                       \
    }
    QDEM_SETTINGS(QDEM_HASH_SETTING)
#undef QDEM_HASH_SETTING
    for (const Material& m : w_.materials) {
        for (const double v : {m.young, m.poisson, m.density, m.viscosity, m.frictionPiece, m.frictionWall, m.radius,
                               m.restitution})
            f[kMaterials].real(v);
        const int law = static_cast<int>(m.law);
        f[kMaterials].bytes(&law, sizeof law);
    }
    const uint64_t h[kN] = {f[0].h, f[1].h, f[2].h, f[3].h, f[4].h};
    const uint32_t bits = differing(*comm_, h, kN);
    if (bits)
        throw InputError("QDEM under MPI: the ranks' " + namesOf(bits, names, kN) +
                         " differ, so they would step one scene by different rules. Under plain mpiexec every rank "
                         "runs the same script and must build, set and step the same scene: seed random numbers "
                         "alike on every rank, and change bodies, O.dt, gravity, engine settings and materials on "
                         "every rank, not inside `if rank == 0:` (under yade.mpy, step with mp.mpirun: QDEM then "
                         "gathers the bodies from their owners itself, doc/parallel.md)");
}

void Domain::markCurrent() {
    current_.assign(w_.nNodes(), 0);
    for (const int32_t n : halo_.ownedNodes) current_[n] = 1;
    for (const auto& g : halo_.recv)
        for (const int32_t n : g) current_[n] = 1;
    for (const auto& g : cRecv_)
        for (const int32_t n : g) current_[n] = 1;
    currentSurf_.clear();
    for (std::size_t i = 0; i < w_.surfNodes.size(); ++i)
        if (current_[w_.surfNodes[i]]) currentSurf_.push_back(static_cast<int32_t>(i));
    ++currentVersion_;
}

void Domain::sendContactHalo() {
    const double t0 = omp_get_wtime();
    const long b0 = comm_->bytesSent, m0 = comm_->messagesSent;
    const SurfaceIndex& S = w_.surfaceIndex();
    // This rank's box of owned surface nodes, its longest surface edge now,
    // the largest particle radius: gathered from every rank.
    double mine[8] = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300, 0, 0};
    for (const int32_t n : ownedSurf_) {
        for (int d = 0; d < 3; ++d) {
            mine[d] = std::min(mine[d], w_.pos[3 * n + d]);
            mine[3 + d] = std::max(mine[3 + d], w_.pos[3 * n + d]);
        }
    }
    for (std::size_t e = 0; e < S.nEdges(); ++e) {
        const int32_t a = S.edge[2 * e], b = S.edge[2 * e + 1];
        if (!owns(a)) continue;
        double l2 = 0;
        for (int d = 0; d < 3; ++d) l2 += (w_.pos[3 * a + d] - w_.pos[3 * b + d]) * (w_.pos[3 * a + d] - w_.pos[3 * b + d]);
        mine[6] = std::max(mine[6], l2);
    }
    // The seed's broad phases register tets: their longest edge (owned tets
    // of the kind registered) instead.
    for (const int32_t t : haloTets_)
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) {
                const int32_t a = w_.tetNodes[4 * t + i], b = w_.tetNodes[4 * t + j];
                double l2 = 0;
                for (int d = 0; d < 3; ++d)
                    l2 += (w_.pos[3 * a + d] - w_.pos[3 * b + d]) * (w_.pos[3 * a + d] - w_.pos[3 * b + d]);
                mine[6] = std::max(mine[6], l2);
            }
    mine[6] = std::sqrt(mine[6]);
    for (const PieceInfo& p : w_.pieces) mine[7] = std::max(mine[7], w_.materials[p.material].radius);
    const int P = size(), me = rank();
    std::vector<double> all(8 * static_cast<std::size_t>(P));
    comm_->allgather(mine, 8, all.data());
    double hMax = 0, rMax = 0;
    for (int r = 0; r < P; ++r) hMax = std::max(hMax, all[8 * r + 6]), rMax = std::max(rMax, all[8 * r + 7]);
    // The reach the switched-on contact kinds declare (ContactKind::haloReach),
    // 5 % over: positions are the same on both sides, this is no skin, only
    // room for rounding in the box tests.
    double width = 1.05 * w_.phases_->pieceContact.haloReach(rMax, hMax);
    // The seed's broad phases: a tet is a candidate when its bounding sphere
    // (radius <= its longest edge h) grown by 2r holds the node, so its nodes
    // lie within 2r + 2h of it; its surface face's neighbours read one edge
    // further: 2r + 3h.
    if (!haloTets_.empty() || w_.settings.broadPhase != BroadPhase::Triangles)
        width = std::max(width, 1.05 * (2 * rMax + 3 * hMax));
    // YADE spheres: a pair is computed by the owner of the lowest node of the
    // triangles whose bounding sphere (radius <= 2h/3 of its longest edge)
    // comes within R + r of the sphere's centre.  Their nodes lie within
    // R + r + 4h/3 of the centre, so within 2 (R + r) + 8h/3 of each other:
    // with this width the owner sees them all (SpherePhase.cpp).
    const double Rs = sphereRadius();
    if (Rs > 0) width = std::max(width, 1.05 * (2 * (Rs + rMax) + 3 * hMax));
    haloSphereRadius_ = Rs;
    const auto boxOf = [&](int r) { return &all[8 * static_cast<std::size_t>(r)]; };
    const auto reaches = [&](const double* a, const double* b) {  // a grown by width meets b
        for (int d = 0; d < 3; ++d)
            if (a[d] - width > b[3 + d] || b[d] > a[3 + d] + width) return false;
        return true;
    };
    // Neighbours: the relation is symmetric (both boxes grown alike).
    cNbr_.clear();
    for (int r = 0; r < P; ++r)
        if (r != me && boxOf(r)[0] <= boxOf(r)[3] && boxOf(me)[0] <= boxOf(me)[3] && reaches(boxOf(r), boxOf(me)))
            cNbr_.push_back(r);
    const std::size_t nb = cNbr_.size();
    std::vector<std::vector<int32_t>> oldRecv = std::move(cRecv_);
    std::vector<int> oldNbr = cNbrPrev_;
    cSend_.assign(nb, {});
    cSendBuf_.assign(nb, {});
    cRecvBuf_.assign(nb, {});
    for (std::size_t i = 0; i < nb; ++i) {
        const double* b = boxOf(cNbr_[i]);
        std::vector<double>& buf = cSendBuf_[i];
        for (const int32_t n : ownedSurf_) {
            const double* x = &w_.pos[3 * n];
            bool in = true;
            for (int d = 0; d < 3 && in; ++d) in = x[d] >= b[d] - width && x[d] <= b[3 + d] + width;
            if (!in) continue;
            cSend_[i].push_back(n);
            buf.push_back(static_cast<double>(n));  // exact: ids are below 2^31
            buf.insert(buf.end(), {x[0], x[1], x[2], w_.vel[3 * n], w_.vel[3 * n + 1], w_.vel[3 * n + 2]});
        }
    }
    comm_->exchangeSized(cNbr_, cSendBuf_, cRecvBuf_);
    cRecv_.assign(nb, {});
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<double>& buf = cRecvBuf_[i];
        for (std::size_t at = 0; at + 7 <= buf.size(); at += 7) {
            const auto n = static_cast<int32_t>(buf[at]);
            cRecv_[i].push_back(n);
            for (int d = 0; d < 3; ++d) {
                w_.pos[3 * n + d] = buf[at + 1 + d];
                w_.vel[3 * n + d] = buf[at + 4 + d];
            }
        }
    }
    // A new set of ghosts: the contact lists are rebuilt (nodes that left are
    // stale from now on and must not be read).
    if (cRecv_ != oldRecv || cNbr_ != oldNbr) markCurrent();
    cNbrPrev_ = cNbr_;
    stepBytes += comm_->bytesSent - b0;
    stepMessages += comm_->messagesSent - m0;
    seconds += omp_get_wtime() - t0;
}

double Domain::sphereRadius() const { return w_.spheres.pairPiece.empty() ? 0.0 : w_.spheres.radiusMax; }

void Domain::ensureSphereHalo() {
    const double Rs = sphereRadius();
    if (Rs == 0 || (contactHalo_ && Rs <= haloSphereRadius_)) return;
    contactHalo_ = true;
    sendContactHalo();
}

void Domain::ownedTetRuns(int32_t piece, std::vector<TetSegment>& out) const {
    const PieceInfo& p = w_.pieces[piece];
    int32_t t = p.tetBegin;
    while (t < p.tetEnd) {
        while (t < p.tetEnd && !ownsTet(t)) ++t;
        const int32_t t0 = t;
        while (t < p.tetEnd && ownsTet(t)) ++t;
        if (t > t0) out.push_back({piece, t0, t});
    }
}

void Domain::exchange(std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) {
    const double t0 = omp_get_wtime();
    const long b0 = comm_->bytesSent, m0 = comm_->messagesSent;
    comm_->exchange(halo_.neighbours, send, recv);
    stepBytes += comm_->bytesSent - b0;
    stepMessages += comm_->messagesSent - m0;
    seconds += omp_get_wtime() - t0;
}

void Domain::returnGhostForces(const ThreadLayout& layout, const double* contactForce, bool contacts,
                               double* contactLoad) {
    stepBytes = stepMessages = 0;
    seconds = 0;
    // Per node: the force (3), then with contactLoad its contact load (2:
    // stiffness, dashpot; zeros for nodes off the surface) in the same message.
    const int32_t* surfIndex = w_.surfaceIndex().surfIndexOfNode.data();
    const std::size_t stride = contactLoad ? 5 : 3;
    const auto packLoad = [&](int32_t n, double* b) {
        const int32_t s = surfIndex[n];
        if (s >= 0) b[3] = contactLoad[2 * s], b[4] = contactLoad[2 * s + 1];
    };
    const std::size_t nb = halo_.neighbours.size();
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& ghosts = halo_.recv[i];
        std::vector<double>& b = sendBuf_[i];
        b.assign(stride * ghosts.size(), 0.0);
        for (std::size_t j = 0; j < ghosts.size(); ++j) {
            const int32_t n = ghosts[j];
            double* f = &b[stride * j];
            // The buffers in thread order, as the owner's integration sums its own.
            for (int t = 0; t < layout.nThreads; ++t)
                if (n >= layout.nodeLo[t] && n <= layout.nodeHi[t]) {
                    const double* s = layout.buffers[t].data() + layout.stride * (n - layout.nodeLo[t]);
                    f[0] += s[0], f[1] += s[1], f[2] += s[2];
                }
            if (contacts)
                for (int d = 0; d < 3; ++d) f[d] += contactForce[3 * n + d];
            if (contactLoad) packLoad(n, f);
        }
        recvBuf_[i].resize(stride * halo_.send[i].size());
    }
    exchange(sendBuf_, recvBuf_);
    // Contact ghosts: the contact force on each ghost received last time
    // (zero for element ghosts, whose contact force went above).
    const std::size_t nc = cNbr_.size();
    if (contactHalo_) {
        const double t0 = omp_get_wtime();
        const long b0 = comm_->bytesSent, m0 = comm_->messagesSent;
        for (std::size_t i = 0; i < nc; ++i) {
            std::vector<double>& b = cSendBuf_[i];
            b.assign(stride * cRecv_[i].size(), 0.0);
            if (contacts)
                for (std::size_t j = 0; j < cRecv_[i].size(); ++j) {
                    const int32_t n = cRecv_[i][j];
                    if (elementGhost_[n]) continue;
                    for (int d = 0; d < 3; ++d) b[stride * j + d] = contactForce[3 * n + d];
                    if (contactLoad) packLoad(n, &b[stride * j]);
                }
            cRecvBuf_[i].resize(stride * cSend_[i].size());
        }
        comm_->exchange(cNbr_, cSendBuf_, cRecvBuf_);
        stepBytes += comm_->bytesSent - b0;
        stepMessages += comm_->messagesSent - m0;
        seconds += omp_get_wtime() - t0;
    }
    // Summed in neighbour (= rank) order, element halo first: the same on
    // every run.  What the last step wrote is cleared first (the contact
    // halo's nodes change from step to step).  The loads are added to the
    // owners' own rows.
    for (const int32_t n : ghostTouched_)
        for (int d = 0; d < 3; ++d) ghostForce_[3 * n + d] = 0.0;
    ghostTouched_.clear();
    const auto add = [&](const std::vector<int32_t>& mine, const std::vector<double>& f) {
        for (std::size_t j = 0; j < mine.size(); ++j) {
            const int32_t n = mine[j];
            for (int d = 0; d < 3; ++d) ghostForce_[3 * n + d] += f[stride * j + d];
            ghostTouched_.push_back(n);
            if (!contactLoad || surfIndex[n] < 0) continue;
            contactLoad[2 * surfIndex[n]] += f[stride * j + 3];
            contactLoad[2 * surfIndex[n] + 1] += f[stride * j + 4];
        }
    };
    for (std::size_t i = 0; i < nb; ++i) add(halo_.send[i], recvBuf_[i]);
    for (std::size_t i = 0; i < nc && contactHalo_; ++i) add(cSend_[i], cRecvBuf_[i]);
}

void Domain::sendStates() {
    const std::size_t nb = halo_.neighbours.size();
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& mine = halo_.send[i];
        std::vector<double>& b = sendBuf_[i];
        b.resize(6 * mine.size());
        for (std::size_t j = 0; j < mine.size(); ++j)
            for (int d = 0; d < 3; ++d) {
                b[6 * j + d] = w_.pos[3 * mine[j] + d];
                b[6 * j + 3 + d] = w_.vel[3 * mine[j] + d];
            }
        recvBuf_[i].resize(6 * halo_.recv[i].size());
    }
    exchange(sendBuf_, recvBuf_);
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& ghosts = halo_.recv[i];
        for (std::size_t j = 0; j < ghosts.size(); ++j)
            for (int d = 0; d < 3; ++d) {
                w_.pos[3 * ghosts[j] + d] = recvBuf_[i][6 * j + d];
                w_.vel[3 * ghosts[j] + d] = recvBuf_[i][6 * j + 3 + d];
            }
    }
}

void Domain::forwardField(double* field) {
    const std::size_t nb = halo_.neighbours.size();
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& mine = halo_.send[i];
        std::vector<double>& b = sendBuf_[i];
        b.resize(3 * mine.size());
        for (std::size_t j = 0; j < mine.size(); ++j)
            for (int d = 0; d < 3; ++d) b[3 * j + d] = field[3 * mine[j] + d];
        recvBuf_[i].resize(3 * halo_.recv[i].size());
    }
    exchange(sendBuf_, recvBuf_);
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& ghosts = halo_.recv[i];
        for (std::size_t j = 0; j < ghosts.size(); ++j)
            for (int d = 0; d < 3; ++d) field[3 * ghosts[j] + d] = recvBuf_[i][3 * j + d];
    }
}

void Domain::returnPartials(const ThreadLayout& layout, double* field) {
    const std::size_t nb = halo_.neighbours.size();
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& ghosts = halo_.recv[i];
        std::vector<double>& b = sendBuf_[i];
        b.resize(3 * ghosts.size());
        for (std::size_t j = 0; j < ghosts.size(); ++j) layout.sumNode(ghosts[j], &b[3 * j]);
        recvBuf_[i].resize(3 * halo_.send[i].size());
    }
    exchange(sendBuf_, recvBuf_);
    for (std::size_t i = 0; i < nb; ++i) {
        const std::vector<int32_t>& mine = halo_.send[i];
        for (std::size_t j = 0; j < mine.size(); ++j)
            for (int d = 0; d < 3; ++d) field[3 * mine[j] + d] += recvBuf_[i][3 * j + d];
    }
}

void Domain::sumInRankOrder(double* v, int n) {
    const double t0 = omp_get_wtime();
    const int P = size();
    gathered_.resize(static_cast<std::size_t>(P) * n);
    comm_->allgather(v, n, gathered_.data());
    for (int k = 0; k < n; ++k) {
        double s = 0;
        for (int r = 0; r < P; ++r) s += gathered_[static_cast<std::size_t>(r) * n + k];
        v[k] = s;
    }
    seconds += omp_get_wtime() - t0;
}

std::string Domain::agree(const std::string& error) {
    double failed = error.empty() ? 0.0 : 1.0;
    comm_->allreduceMax(&failed, 1);
    if (failed == 0) return "";
    std::vector<uint8_t> mine(error.begin(), error.end()), all;
    std::vector<int> counts;
    comm_->allgatherv(mine, all, counts);
    // The error of the earliest phase (its order, the second character), of
    // the lowest rank among equals: a later phase's error on another rank
    // may only be a consequence of it.
    int best = -1;
    std::size_t bestAt = 0, at = 0;
    for (int r = 0; r < size(); ++r) {
        if (counts[r] >= 2 && (best < 0 || all[at + 1] < all[bestAt + 1])) best = r, bestAt = at;
        at += counts[r];
    }
    if (best < 0) return "SQDEM: a rank failed without a message";
    return std::string(1, static_cast<char>(all[bestAt])) + "QDEM rank " + std::to_string(best) + " of " +
           std::to_string(size()) + ": " +
           std::string(all.begin() + static_cast<std::ptrdiff_t>(bestAt) + 2,
                       all.begin() + static_cast<std::ptrdiff_t>(bestAt) + counts[best]);
}

void Domain::finishStep(const std::string& error) {
    const double t0 = omp_get_wtime();
        const std::size_t no = w_.obstacles.size();
    const bool energyOn = w_.settings.trackEnergy;
    // [failed, reactions (6 per obstacle), energies (10), sphere pairs, load]
    // of this rank.
    const std::size_t ne = energyOn ? 10 : 0, ns = w_.phases_->sphere.mpiValues();
    // Then each rank's run-time piece-contact limit in its own slots (zeros
    // in the others': the sums are every rank's values, PieceContactPhase).
    PieceContactPhase& pc = w_.phases_->pieceContact;
    const std::size_t nl = static_cast<std::size_t>(PieceContactPhase::kLimitValues) * size();
    const std::size_t nv = 1 + 6 * no + ne + ns + nl + 1;
    std::vector<double> v(nv);
    v[0] = error.empty() ? 0.0 : 1.0;
    v[nv - 1] = load();
    for (std::size_t i = 0; i < no; ++i)
        for (int d = 0; d < 3; ++d) {
            v[1 + 6 * i + d] = w_.obstacles[i].reactionForce[d];
            v[1 + 6 * i + 3 + d] = w_.obstacles[i].reactionTorque[d];
        }
    if (energyOn) {
        const Energy& e = w_.energy;
        const double es[10] = {e.kinetic, e.elastic,  e.gravity,      e.viscous,      e.contactElastic,
                               e.contactDamping, e.friction, e.boundaryWork, e.localDamping, e.sleep};
        std::copy(es, es + 10, v.begin() + 1 + 6 * no);
    }
    // The sphere pairs this rank computed (zeros for the others'): their
    // sums are each pair's owner's force, torque and history.
    if (ns > 0) w_.phases_->sphere.packPairs(v.data() + 1 + 6 * no + ne);
    pc.packStepLimit(v.data() + 1 + 6 * no + ne + ns, rank());
    // Summed (the load too, for its mean) and the load's maximum, in a tree
    // of fixed shape: the same bits on every rank and every run.
    v.push_back(v[nv - 1]);
    comm_->treeReduce(v.data(), static_cast<int>(nv), 1);
    const double sumLoad = v[nv - 1], maxLoad = v[nv];
    loadImbalance = sumLoad > 0 ? maxLoad * (size() - part_.firstRank) / sumLoad : 1.0;  // over the ranks with a share
    seconds += omp_get_wtime() - t0;
    if (v[0] > 0) {
        const std::string msg = agree(error);
        if (msg[0] == 'I') throw InputError(msg.substr(1));
        throw StabilityError(msg.substr(1));
    }
    for (std::size_t i = 0; i < no; ++i)
        for (int d = 0; d < 3; ++d) {
            w_.obstacles[i].reactionForce[d] = v[1 + 6 * i + d];
            w_.obstacles[i].reactionTorque[d] = v[1 + 6 * i + 3 + d];
        }
    if (energyOn) {
        const double* s = v.data() + 1 + 6 * no;
        w_.energyTotal_ = Energy{s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9]};
    }
    if (ns > 0 || !w_.spheres.pairPiece.empty()) w_.phases_->sphere.unpackPairs(v.data() + 1 + 6 * no + ne, w_.iter - 1);
    pc.unpackStepLimit(v.data() + 1 + 6 * no + ne + ns, size());
}

double Domain::load() const {
    long contacts = 0;
    if (w_.settings.contactWork > 0) {
        const PhaseReport r = w_.report();
        contacts = r.count("wall") + w_.phases_->pieceContact.contacts();
    }
    return static_cast<double>(halo_.ownedTets.size()) + w_.settings.contactWork * static_cast<double>(contacts);
}

void Domain::rebalance(const PartitionOptions& opt) {
    gatherAll();   // positions, velocities, forces: every rank alike
    gatherRows();  // and every state row
    ++rebalances;
    build(opt);  // the same new split on every rank: they now hold the same state
}

void Domain::gatherRows() {
    // Every row of every migrating state column from the rank that held it
    // true.  Every rank knows the owners, so the rows travel without ids.
    StateColumns cols = w_.stateColumns();
    const SurfaceIndex& S = w_.surfaceIndex();
    const auto nRows = [&](Rows k) -> std::size_t {
        switch (k) {
            case Rows::Node: return w_.nNodes();
            case Rows::SurfaceNode: return w_.surfNodes.size();
            case Rows::Edge: return S.nEdges();
            default: return 0;
        }
    };
    // Rows of pieces added since the split (nodes beyond it) are the same on
    // every rank already (every rank added them): -1, they stay.
    const auto nodeOwner = [&](int32_t n) { return n < static_cast<int32_t>(part_.nodeOwner.size()) ? owner(n) : -1; };
    const auto ownerOf = [&](Rows k, std::size_t row) -> int {
        switch (k) {
            case Rows::Node: return nodeOwner(static_cast<int32_t>(row));
            case Rows::SurfaceNode: return nodeOwner(w_.surfNodes[row]);
            default: return nodeOwner(std::min(S.edge[2 * row], S.edge[2 * row + 1]));
        }
    };
    std::vector<uint8_t> mine, all;
    for (const auto& c : cols.refs) {
        const std::size_t n = nRows(c.rows);
        if (n == 0 || c.count == 0) continue;
        const std::size_t rowBytes = c.count * c.elemSize / n;
        const auto* data = static_cast<const uint8_t*>(c.data);
        for (std::size_t row = 0; row < n; ++row)
            if (ownerOf(c.rows, row) == rank()) mine.insert(mine.end(), data + row * rowBytes, data + (row + 1) * rowBytes);
    }
    std::vector<int> counts;
    comm_->allgatherv(mine, all, counts);
    std::size_t at = 0;
    for (int r = 0; r < size(); ++r)
        for (const auto& c : cols.refs) {
            const std::size_t n = nRows(c.rows);
            if (n == 0 || c.count == 0) continue;
            const std::size_t rowBytes = c.count * c.elemSize / n;
            auto* data = static_cast<uint8_t*>(c.data);
            for (std::size_t row = 0; row < n; ++row)
                if (ownerOf(c.rows, row) == r) {
                    if (at + rowBytes > all.size()) throw InputError("rebalance: the ranks' states differ in size");
                    std::memcpy(data + row * rowBytes, &all[at], rowBytes);
                    at += rowBytes;
                }
        }
}

void Domain::gatherAll() {
    // Owned nodes' (id, x, v, f) of every rank, then written everywhere.
    constexpr std::size_t kRec = sizeof(int32_t) + 9 * sizeof(double);
    const double* cols[3] = {w_.pos.data(), w_.vel.data(), w_.force.data()};
    std::vector<uint8_t> mine, all;
    mine.reserve(halo_.ownedNodes.size() * kRec);
    for (const int32_t n : halo_.ownedNodes) {
        const std::size_t at = mine.size();
        mine.resize(at + kRec);
        std::memcpy(&mine[at], &n, sizeof n);
        for (int c = 0; c < 3; ++c) std::memcpy(&mine[at + sizeof n + 3 * c * sizeof(double)], cols[c] + 3 * n, 3 * sizeof(double));
    }
    std::vector<int> counts;
    comm_->allgatherv(mine, all, counts);
    double* out[3] = {w_.pos.data(), w_.vel.data(), w_.force.data()};
    for (std::size_t at = 0; at + kRec <= all.size(); at += kRec) {
        int32_t n;
        std::memcpy(&n, &all[at], sizeof n);
        if (n < 0 || n >= static_cast<int32_t>(w_.nNodes())) throw InputError("gatherAll: node id out of range");
        for (int c = 0; c < 3; ++c) std::memcpy(out[c] + 3 * n, &all[at + sizeof n + 3 * c * sizeof(double)], 3 * sizeof(double));
    }
}

}  // namespace qdem
