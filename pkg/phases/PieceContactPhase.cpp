// Piece-piece surface contacts (seed paper §3-4): the loop over the contact
// kinds (ContactKind.hpp) after the broad phase (PieceBroadPhase.cpp), and
// its bookkeeping: surface spins, the start and depth checks, the sum of the
// thread buffers with the run-time step limit.  Derivations and the rules
// that keep forces continuous: doc/contacts.md.
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

PieceContactPhase::PieceContactPhase(const Data& data) : w_(data), broad_(w_, st_) {
    for (const ContactKindRow& row : contactKinds())
        if (row.family == ContactFamily::PiecePiece) kinds_.push_back({&row, row.make()});
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
}

const ContactKind* PieceContactPhase::kind(const char* name) const {
    for (const Kind& k : kinds_)
        if (std::string(name) == k.row->name) return k.kernel.get();
    return nullptr;
}

double PieceContactPhase::haloReach(double rMax, double hMax) const {
    double reach = 0;
    if (w_.pieces.size() < 2) return reach;
    for (const Kind& k : kinds_)
        if (kindOn(k)) reach = std::max(reach, k.kernel->haloReach(rMax, hMax));
    return reach;
}

long PieceContactPhase::contacts() const {
    long n = 0;
    for (const Kind& k : kinds_) n += k.contacts;
    return n;
}

void PieceContactPhase::addLoadWeights(double* perNode, double work) const {
    for (const Kind& k : kinds_) k.kernel->addLoadWeights(w_, perNode, work);
}

void PieceContactPhase::run(double dt) {
    broadSeconds_ = sumSeconds_ = 0;
    for (Kind& k : kinds_) k.seconds = 0, k.contacts = 0, k.kernel->newStep();  // (a step with no pieces near runs none)
    maxOverlap_ = maxDepthRatio_ = 0;
    stepLimit_ = ContactStepLimit{};
    const std::size_t np = w_.pieces.size();
    noteSleepChanges();
    std::fill(frozen_.begin(), frozen_.end(), 0);
    if (np < 2 || !anyKindOn()) {  // no contacts: no overlap to refuse either
        startChecked_.assign(np, 1);
        return;
    }
    // The broad phase: neighbour pieces, then the lists the switched-on
    // kinds declare (their rows' Registration bits).
    const double t0 = omp_get_wtime();
    if (!broad_.neighbours(frozen_)) {  // nothing touches (history lapses: it is only valid from the previous step)
        startChecked_.assign(np, 1);    // (nor overlaps)
        return;
    }
    w_.contacts.begin();
    broad_.build(listsWanted());
    broadSeconds_ = omp_get_wtime() - t0;
    surfaceSpins();

    beginStartCheck();
    threadDeep_.assign(omp_get_max_threads(), DeepContact{});  // (same size each step: no allocation)
    // The kinds of the table, in order (ContactKind.hpp).
    KindStep ks{dt, w_.settings.frictionOn, w_, *this, st_, st_.threadForce, st_.threadLoad};
    for (Kind& k : kinds_) {
        if (!kindOn(k)) continue;
        const double tk = omp_get_wtime();
        k.contacts = k.kernel->run(ks);
        k.seconds = omp_get_wtime() - tk;
    }
    finishStartCheck();
    for (const DeepContact& d : threadDeep_) maxDepthRatio_ = std::max(maxDepthRatio_, d.ratio);
    if (maxDepthRatio_ > 1) checkContactDepth(dt);
    sumForces(ks);
}

// The thread buffers summed into the node contact forces, with each node's
// contact load and its stable step; the step's tallies booked.
void PieceContactPhase::sumForces(const KindStep& ks) {
    const Domain* dom = w_.domain.built();
    const bool all = w_.sleeping.everything();
    const int nth = static_cast<int>(st_.threadForce.size());
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
    for (Kind& k : kinds_) k.kernel->piecesAdded(w_);
    frozen_.resize(w_.pieces.size(), 0);
    broad_.piecesAdded(w_.pieces.size());
    sleepSeen_.resize(w_.pieces.size(), 0);
    startChecked_.resize(w_.pieces.size(), 0);
}

void PieceContactPhase::noteSleepChanges() {
    for (std::size_t p = 0; p < sleepSeen_.size(); ++p) {
        const uint32_t c = w_.sleeping.changes(p);
        if (c == sleepSeen_[p]) continue;
        sleepSeen_[p] = c;
        frozen_[p] = 0;
        broad_.sleepChanged(p);
    }
}

// The kinds' fields (ContactKind::saveFields).
void PieceContactPhase::saveFields(WorldState& s) const {
    for (const Kind& k : kinds_) k.kernel->saveFields(s);
}

void PieceContactPhase::checkFields(const WorldState& s) const {
    for (const Kind& k : kinds_) k.kernel->checkFields(s);
}

void PieceContactPhase::loadFields(const WorldState& s) {
    for (Kind& k : kinds_) k.kernel->loadFields(s, w_);
}

void PieceContactPhase::stateLoaded() {
    stepLimit_ = ContactStepLimit{};
    std::fill(frozen_.begin(), frozen_.end(), 0);
    broad_.stateLoaded();  // Verlet lists: rebuilt from the loaded positions
    startChecked_.assign(w_.pieces.size(), 1);  // a restart, not a set-up: contacts go on as saved
}

}  // namespace qdem
