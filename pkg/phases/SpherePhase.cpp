// Contacts between YADE spheres (standalone or clump members) and the surface
// triangles of QDEM pieces: the sphere's centre is a query point with reach
// R + r (sphere radius plus the pieces' particle radius), handled with the
// same closest-point, inside-test and one-contact-per-touch rules as a node
// (TouchSelection.hpp), so the force is continuous across triangle edges and
// corners.  Rules and sources: doc/spheres.md.
#include <omp.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <unordered_map>

#include "../contact/ContactLaw.hpp"
#include "../contact/ContactLoop.hpp"
#include "../core/ThreadPartials.hpp"
#include "../contact/Obstacle.hpp"
#include "../contact/ContactModel.hpp"
#include "../contact/Geometry.hpp"
#include "../core/Errors.hpp"
#include "../core/Format.hpp"
#include "../contact/ContactDetail.hpp"
#include "../contact/PointTriangle.hpp"
#include "../contact/TouchSelection.hpp"
#include "../parallel/Domain.hpp"
#include "../step/WorldState.hpp"
#include "ContactKind.hpp"
#include "ContactLoad.hpp"
#include "SpherePhase.hpp"

namespace qdem {

using Eigen::Vector3d;
using namespace contact_detail;

namespace {

// A YADE sphere as one side of the contact model (ContactModel.hpp), its
// material's (doc/spheres.md).
ContactSide sphereSide(const SphereSet& S, int32_t i) {
    return {S.young[i] * S.radius[i], S.ktRatio[i], S.restitution[i], S.friction[i], S.radius[i]};
}

}  // namespace

void SpherePhase::setSpheres(int32_t n, const int32_t* id, const double* radius, const double* young, const double* ktRatio,
                       const double* friction, const double* restitution, const double* mass, const int32_t* pairStart,
                       const int32_t* pairPiece) {
    const auto np = static_cast<int32_t>(w_.pieces.size());
    if (n < 0 || pairStart[0] != 0) throw InputError("setSpheres: bad sphere count or pair offsets");
    for (int32_t i = 0; i < n; ++i) {
        if (!(radius[i] > 0) || !std::isfinite(radius[i]))
            throw InputError(cat("sphere ", id[i], ": radius must be positive and finite, got ", radius[i]));
        if (!(young[i] > 0) || !std::isfinite(young[i]))
            throw InputError(cat("sphere ", id[i], ": material young must be positive and finite, got ", young[i]));
        if (!(mass[i] > 0) || !std::isfinite(mass[i]))
            throw InputError(cat("sphere ", id[i], ": mass must be positive and finite, got ", mass[i],
                                 " (a non-dynamic sphere needs a mass for the contact dashpot)"));
        if (!((friction[i] >= 0 && std::isfinite(friction[i])) || friction[i] == -1))
            throw InputError(cat("sphere ", id[i], ": friction must be >= 0 (or -1: none, the piece's alone), got ",
                                 friction[i]));
        if (!(restitution[i] <= 1) || std::isnan(restitution[i]))
            throw InputError(cat("sphere ", id[i], ": restitution must be <= 1, got ", restitution[i]));
        if (pairStart[i + 1] < pairStart[i]) throw InputError("setSpheres: pair offsets must not decrease");
        for (int32_t q = pairStart[i]; q < pairStart[i + 1]; ++q)
            if (pairPiece[q] < 0 || pairPiece[q] >= np)
                throw InputError(cat("sphere ", id[i], ": unknown piece ", pairPiece[q]));
    }
    SphereSet& S = w_.spheres;
    // The contact history of (id, piece) pairs kept: from a restart's state
    // if one was loaded since, else from the spheres set last.
    History old;
    if (hasLoaded_) {
        old = std::move(loaded_);
        hasLoaded_ = false;
    } else {
        old.id = std::move(S.id);
        old.pairStart = std::move(S.pairStart);
        old.pairPiece = std::move(S.pairPiece);
        old.key = std::move(S.slotKey);
        old.shear = std::move(S.slotShear);
        old.ref = std::move(S.slotRef);
        old.stamp = std::move(S.pairStamp);
    }

    S.id.assign(id, id + n);
    S.radius.assign(radius, radius + n);
    S.young.assign(young, young + n);
    S.ktRatio.assign(ktRatio, ktRatio + n);
    S.friction.assign(friction, friction + n);
    S.restitution.assign(restitution, restitution + n);
    S.mass.assign(mass, mass + n);
    S.pairStart.assign(pairStart, pairStart + n + 1);
    S.pairPiece.assign(pairPiece, pairPiece + pairStart[n]);
    S.pos.assign(3 * n, 0.0);
    S.vel.assign(3 * n, 0.0);
    S.angVel.assign(3 * n, 0.0);
    S.spinOffset.assign(3 * n, 0.0);
    S.forceTorque.assign(6 * n, 0.0);
    const int32_t nPairs = pairStart[n];
    constexpr int K = SphereSet::kSlots;
    S.slotKey.assign(K * static_cast<std::size_t>(nPairs), -1);
    S.slotShear.assign(3 * K * static_cast<std::size_t>(nPairs), 0.0);
    S.slotRef.assign(K * static_cast<std::size_t>(nPairs), 0.0);
    S.pairStamp.assign(nPairs, -2);
    S.pairForceTorque.assign(6 * static_cast<std::size_t>(nPairs), 0.0);
    S.pairComputed.assign(nPairs, 0);
    S.active.clear();
    carry(old);
    // Stiffest springs, for the stable time step: each pair's spring joins
    // two masses, the sphere's (m for the normal spring, its tangential mass
    // at the surface 2m/7 for the tangential one: 1/m + R^2/I = 7/(2m) for a
    // solid ball) and the triangle point's (at least the piece's lightest
    // surface node), so omega^2 = k (1/m_s + 1/m_node).  The dashpots are
    // 2 xi sqrt(k m_red) with m_red the reduced mass of the sphere and the
    // triangle point (sphereContacts), at most m_red of the heaviest surface
    // node: on the mode's own mass their damping ratio is xi sqrt(m_red
    // omega^2 / k), which the half-step-lagged dashpot turns into a lower
    // limit, leapfrogLimit(omega, xi_eff) (doc/spheres.md, "Time step").
    S.radiusMax = 0;
    for (SphereSet::StepBound& sb : S.bound) {
        sb.stableStep = std::numeric_limits<double>::infinity();
        sb.pieceK.assign(np, 0.0);
        sb.pieceSphereW2.assign(np, 0.0);
        sb.pieceSphereRate.assign(np, 0.0);
    }
    for (int32_t i = 0; i < n; ++i) {
        S.radiusMax = std::max(S.radiusMax, radius[i]);
        for (int32_t q = pairStart[i]; q < pairStart[i + 1]; ++q) {
            const int32_t pc = pairPiece[q];
            const PieceInfo& piece = w_.pieces[pc];
            const Material& b = w_.materials[piece.material];
            const PairConst c = mix(sphereSide(S, i), materialSide(b, b.frictionPiece));
            const double mReduced = mass[i] * piece.maxSurfaceNodeMass / (mass[i] + piece.maxSurfaceNodeMass);
            for (int withTangential = 0; withTangential < 2; ++withTangential) {
                SphereSet::StepBound& sb = S.bound[withTangential];
                const int modes = withTangential && c.mu > 0 ? 2 : 1;
                for (int mode = 0; mode < modes; ++mode) {
                    const double k = mode ? c.kt : c.kn, sphereInvMass = (mode ? 3.5 : 1.0) / mass[i];
                    const double w2 = k * (sphereInvMass + 1.0 / piece.minSurfaceNodeMass);
                    const double xiEff = c.xi * std::sqrt(mReduced * w2 / k);
                    sb.pieceK[pc] = std::max(sb.pieceK[pc], k);
                    sb.pieceSphereW2[pc] = std::max(sb.pieceSphereW2[pc], k * sphereInvMass);
                    sb.pieceSphereRate[pc] = std::max(sb.pieceSphereRate[pc], 2 * xiEff * std::sqrt(w2));
                    sb.stableStep = std::min(sb.stableStep, leapfrogLimit(std::sqrt(w2), xiEff));
                }
            }
        }
    }
}

void SpherePhase::carry(const History& old) {
    SphereSet& S = w_.spheres;
    constexpr int K = SphereSet::kSlots;
    std::unordered_map<int64_t, int32_t> oldPair;
    const auto keyOf = [](int32_t sphere, int32_t piece) { return (static_cast<int64_t>(sphere) << 20) ^ piece; };
    for (std::size_t i = 0; i + 1 < old.pairStart.size(); ++i)
        for (int32_t q = old.pairStart[i]; q < old.pairStart[i + 1]; ++q) oldPair[keyOf(old.id[i], old.pairPiece[q])] = q;
    for (int32_t i = 0; i < S.size(); ++i)
        for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1]; ++q) {
            const auto it = oldPair.find(keyOf(S.id[i], S.pairPiece[q]));
            if (it == oldPair.end()) continue;
            const auto o = static_cast<std::size_t>(it->second), at = static_cast<std::size_t>(q);
            S.pairStamp[at] = old.stamp[o];
            std::copy_n(&old.key[K * o], K, &S.slotKey[K * at]);
            std::copy_n(&old.ref[K * o], K, &S.slotRef[K * at]);
            std::copy_n(&old.shear[3 * K * o], 3 * K, &S.slotShear[3 * K * at]);
        }
}

void SpherePhase::sumPairForces() {
    SphereSet& S = w_.spheres;
    for (int32_t i = 0; i < S.size(); ++i) {
        double ft[6] = {0, 0, 0, 0, 0, 0};
        for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1]; ++q)
            for (int d = 0; d < 6; ++d) ft[d] += S.pairForceTorque[6 * static_cast<std::size_t>(q) + d];
        std::copy_n(ft, 6, &S.forceTorque[6 * static_cast<std::size_t>(i)]);
    }
}

// ---- under MPI ---------------------------------------------------------------

// A pair can hold contacts only when the sphere's box meets the piece's box
// (grown by its particle radius), the test the contact loop starts with.
// Under MPI the piece boxes are the whole pieces' (PieceBounds::update
// reduces them when spheres are coupled) and the spheres are YADE's, the
// same on every rank: so is this list, which sizes the reduction.
void SpherePhase::listActive() {
    SphereSet& S = w_.spheres;
    S.active.clear();
    for (int32_t i = 0; i < S.size(); ++i) {
        const double R = S.radius[i];
        for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1]; ++q) {
            const int32_t pb = S.pairPiece[q];
            bool overlap = true;
            for (int d = 0; d < 3 && overlap; ++d)
                overlap = S.pos[3 * i + d] - R <= w_.bounds.hi[3 * pb + d] && w_.bounds.lo[3 * pb + d] <= S.pos[3 * i + d] + R;
            if (overlap) S.active.push_back(q);
        }
    }
}

std::size_t SpherePhase::mpiValues() const { return kPairValues * w_.spheres.active.size(); }

void SpherePhase::packPairs(double* out) const {
    const SphereSet& S = w_.spheres;
    constexpr int K = SphereSet::kSlots;
    for (const int32_t q : S.active) {
        const auto at = static_cast<std::size_t>(q);
        double* o = out;
        out += kPairValues;
        if (!S.pairComputed[at]) {  // another rank's (or nobody's): zeros, the sum is the owner's
            std::fill(o, out, 0.0);
            continue;
        }
        o[0] = 1.0;
        std::copy_n(&S.pairForceTorque[6 * at], 6, o + 1);
        for (int k = 0; k < K; ++k) o[7 + k] = S.slotKey[K * at + k] + 1.0;  // exact: keys < 2^31
        std::copy_n(&S.slotRef[K * at], K, o + 7 + K);
        std::copy_n(&S.slotShear[3 * K * at], 3 * K, o + 7 + 2 * K);
    }
}

void SpherePhase::unpackPairs(const double* in, long phaseIter) {
    SphereSet& S = w_.spheres;
    constexpr int K = SphereSet::kSlots;
    // Every pair was looked at this step (serially too: a pair out of reach
    // keeps no contact): its stamp, and no contact unless its owner kept one.
    std::fill(S.pairStamp.begin(), S.pairStamp.end(), phaseIter);
    std::fill(S.slotKey.begin(), S.slotKey.end(), -1);
    std::fill(S.slotRef.begin(), S.slotRef.end(), 0.0);
    std::fill(S.pairForceTorque.begin(), S.pairForceTorque.end(), 0.0);
    for (const int32_t q : S.active) {
        const auto at = static_cast<std::size_t>(q);
        const double* v = in;
        in += kPairValues;
        if (v[0] > 1.5) {
            const auto i = std::upper_bound(S.pairStart.begin(), S.pairStart.end(), q) - S.pairStart.begin() - 1;
            throw StabilityError(cat("QDEM under MPI: the contacts of sphere ", S.id[i], " with piece ",
                                     S.pairPiece[at], " were computed on ", v[0],
                                     " ranks (internal error: the contact halo is too narrow for this sphere)"));
        }
        if (v[0] < 0.5) continue;  // no rank had a triangle within reach: no contact, as serially
        std::copy_n(v + 1, 6, &S.pairForceTorque[6 * at]);
        for (int k = 0; k < K; ++k) {
            S.slotKey[K * at + k] = static_cast<int32_t>(v[7 + k]) - 1;
            S.slotRef[K * at + k] = v[7 + K + k];
            if (S.slotKey[K * at + k] >= 0)  // the springs of live slots (empty ones are never read)
                std::copy_n(v + 7 + 2 * K + 3 * k, 3, &S.slotShear[3 * (K * at + k)]);
        }
    }
    sumPairForces();
}

// ---- restarts ------------------------------------------------------------------

void SpherePhase::saveFields(WorldState& s) const {
    const SphereSet& S = w_.spheres;
    const std::vector<int64_t> stamp(S.pairStamp.begin(), S.pairStamp.end());
    s.put("sphereId", S.id.data(), S.id.size());
    s.put("spherePairStart", S.pairStart.data(), S.pairStart.size());
    s.put("spherePairPiece", S.pairPiece.data(), S.pairPiece.size());
    s.put("sphereSlotKey", S.slotKey.data(), S.slotKey.size());
    s.put("sphereSlotShear", S.slotShear.data(), S.slotShear.size());
    s.put("sphereSlotRef", S.slotRef.data(), S.slotRef.size());
    s.put("spherePairStamp", stamp.data(), stamp.size());
}

void SpherePhase::checkFields(const WorldState& s) const {
    if (s.fields.count("sphereId") == 0) return;  // a state from before sphere histories were kept
    constexpr int K = SphereSet::kSlots;
    const std::size_t n = s.getAll<int32_t>("sphereId").size();
    const std::vector<int32_t> start = s.getAll<int32_t>("spherePairStart");
    const std::size_t pairs = start.empty() ? 0 : static_cast<std::size_t>(start.back());
    if (!(start.size() == n + 1 || (n == 0 && start.empty())))
        throw InputError("world state: spherePairStart does not fit sphereId");
    s.check<int32_t>("spherePairPiece", pairs);
    s.check<int32_t>("sphereSlotKey", K * pairs);
    s.check<double>("sphereSlotShear", 3 * K * pairs);
    s.check<double>("sphereSlotRef", K * pairs);
    s.check<int64_t>("spherePairStamp", pairs);
    for (const int32_t p : s.getAll<int32_t>("spherePairPiece"))
        if (p < 0 || p >= static_cast<int32_t>(w_.pieces.size()))
            throw InputError(cat("world state: a sphere pair names piece ", p, " of ", w_.pieces.size()));
}

void SpherePhase::loadFields(const WorldState& s) {
    if (s.fields.count("sphereId") == 0) return;
    History h;
    h.id = s.getAll<int32_t>("sphereId");
    h.pairStart = s.getAll<int32_t>("spherePairStart");
    h.pairPiece = s.getAll<int32_t>("spherePairPiece");
    h.key = s.getAll<int32_t>("sphereSlotKey");
    h.shear = s.getAll<double>("sphereSlotShear");
    h.ref = s.getAll<double>("sphereSlotRef");
    const std::vector<int64_t> stamp = s.getAll<int64_t>("spherePairStamp");
    h.stamp.assign(stamp.begin(), stamp.end());
    // Into the spheres set now (a state loaded into a running scene), and
    // kept for the next setSpheres (a scene whose spheres are listed again).
    SphereSet& S = w_.spheres;
    std::fill(S.slotKey.begin(), S.slotKey.end(), -1);
    std::fill(S.pairStamp.begin(), S.pairStamp.end(), -2);
    carry(h);
    loaded_ = std::move(h);
    hasLoaded_ = true;
}

// Per piece that a sphere may touch: its surface triangles binned by
// centroid, with bounding radii and unit normals of the current shape.
void SpherePhase::buildGrids() {
    SphereSet& S = w_.spheres;
    const SurfaceIndex& surf = w_.surface;
    const auto np = static_cast<int32_t>(w_.pieces.size());
    S.pieceUsed.assign(np, 0);
    for (int32_t p : S.pairPiece) S.pieceUsed[p] = 1;
    S.triGrid.resize(np);
    S.pieceTriRadius.assign(np, 0.0);
    S.triPoint.resize(3 * surf.nTris());
    S.triRadius.resize(surf.nTris());
    S.triNormal.resize(3 * surf.nTris());
    S.triCurrent.resize(surf.nTris());
    const Domain* dom = w_.domain.any();
    for (int32_t p = 0; p < np; ++p) {
        if (!S.pieceUsed[p]) continue;
        const int32_t t0 = surf.pieceTriStart[p], t1 = surf.pieceTriStart[p + 1];
        double rMax = 0;
#pragma omp parallel for schedule(static) reduction(max : rMax)
        for (int32_t t = t0; t < t1; ++t) {
            const int32_t* c = &surf.tri[3 * t];
            // Under MPI only triangles whose nodes are current here are seen
            // (the others' positions are stale on this rank).
            S.triCurrent[t] = !dom || (dom->current(c[0]) && dom->current(c[1]) && dom->current(c[2]));
            if (!S.triCurrent[t]) {
                S.triRadius[t] = 0;
                for (int k = 0; k < 3; ++k) S.triPoint[3 * t + k] = S.triNormal[3 * t + k] = 0;
                continue;
            }
            const Vector3d a = at(w_.pos, c[0]), b = at(w_.pos, c[1]), d = at(w_.pos, c[2]);
            const Vector3d m = (a + b + d) / 3.0;
            const Vector3d n = (b - a).cross(d - a).normalized();
            const double r = std::sqrt(std::max({(a - m).squaredNorm(), (b - m).squaredNorm(), (d - m).squaredNorm()}));
            for (int k = 0; k < 3; ++k) S.triPoint[3 * t + k] = m[k], S.triNormal[3 * t + k] = n[k];
            S.triRadius[t] = r;
            rMax = std::max(rMax, r);
        }
        S.pieceTriRadius[p] = rMax;
        // Cells twice the largest reach: a query then spans 2 cells per axis.
        const double reach = rMax + S.radiusMax + w_.materials[w_.pieces[p].material].radius;
        S.triGrid[p].build(&S.triPoint[3 * t0], t1 - t0, 2 * reach);
    }
}

void SpherePhase::run(double dt) {
    contacts_ = 0;
    SphereSet& S = w_.spheres;
    std::fill(S.forceTorque.begin(), S.forceTorque.end(), 0.0);
    std::fill(S.pairForceTorque.begin(), S.pairForceTorque.end(), 0.0);
    std::fill(S.pairComputed.begin(), S.pairComputed.end(), 0);
    if (S.size() == 0 || S.pairPiece.empty()) return;  // no sphere near any piece: nothing to do
    if (!kindSwitchedOn(contactKind(ContactFamily::PieceSphere), w_.settings)) return;  // (QdemEngine spheres=False)
    buildGrids();
    w_.contacts.begin();
    const int nth = omp_get_max_threads();
    if (static_cast<int>(S.threadForce.size()) != nth) S.threadForce.assign(nth, {});
    if (static_cast<int>(S.threadLoad.size()) != nth) S.threadLoad.assign(nth, {});
    double eEl = 0, eDamp = 0, eSlip = 0;
    long count = 0;
    if (w_.settings.frictionOn) sphereContacts<true>(dt, eEl, eDamp, eSlip, count);
    else sphereContacts<false>(dt, eEl, eDamp, eSlip, count);
    // Sum the thread buffers into the node contact forces (surface nodes of
    // the pieces spheres may touch).
    for (std::size_t p = 0; p < w_.pieces.size(); ++p) {
        if (!S.pieceUsed[p]) continue;
        const int32_t s0 = w_.pieces[p].surfBegin, s1 = w_.pieces[p].surfEnd;
#pragma omp parallel for schedule(static) num_threads(nth)
        for (int32_t s = s0; s < s1; ++s)
            for (int th = 0; th < nth; ++th)
                for (int d = 0; d < 3; ++d) w_.contacts.force[3 * w_.surfNodes[s] + d] += S.threadForce[th][3 * s + d];
        addThreadLoads(S.threadLoad, s0, s1, w_.contacts.beginLoad());  // (ContactLoad.hpp)
    }
    contacts_ = count;
    // Under MPI each rank holds only the pairs it computed: the sums come
    // with the end-of-step reduction (unpackPairs).
    if (!w_.domain.any()) sumPairForces();
    if (w_.settings.trackEnergy) {
        w_.energy.contactElastic += eEl;
        w_.energy.contactDamping += eDamp;
        w_.energy.friction += eSlip;
    }
}

namespace {

// One sphere as its contacts see it: at the nodes' time level.
struct SphereAt {
    int32_t i;
    Vector3d C, v, w, spinOff;  // centre, velocity, spin, offset to the point it spins about
    double R;
};

// The touches of sphere s with piece pb (its centre a query point of reach
// `reach`): the candidate triangles, the inside test for a centre behind a
// face, one contact per touch (TouchSelection.hpp).  keep[k] says which of
// cl's candidates are touches.
void findTouches(const SpherePhase::Data& w, const SphereAt& s, int32_t pb, double reach, bool overlap, double eps,
                 double cosFeature, CandidateList& cl, bool* keep) {
    const SphereSet& S = w.spheres;
    const SurfaceIndex& surf = w.surface;
    const double* X = w.pos.data();
    const Vector3d& C = s.C;
    Candidate* const cand = cl.c;
    const int32_t t0 = surf.pieceTriStart[pb];
    const double qr = S.pieceTriRadius[pb] + reach;
    cl.clear();
    const int& nc = cl.n;
    if (overlap) {
        const Vector3d lo = C.array() - qr, hi = C.array() + qr;
        S.triGrid[pb].forRange(lo.data(), hi.data(), [&](int32_t local) {
            const int32_t t = t0 + local;
            if (!S.triCurrent[t]) return;
            const double Rt = S.triRadius[t] + reach;
            if ((C - Eigen::Map<const Vector3d>(&S.triPoint[3 * t])).squaredNorm() > Rt * Rt) return;
            const int32_t* c = &surf.tri[3 * t];
            cl.consider(C, t, at(X, c[0]), at(X, c[1]), at(X, c[2]),
                        Eigen::Map<const Vector3d>(&S.triNormal[3 * t]), reach, true);
        });
    }
    for (int k = 0; k < nc; ++k) keep[k] = true;
    // Centre behind a face: inside the piece only if no front-facing
    // surface point is nearer (as for nodes, PointPolygon.cpp).
    if (cl.anyBehind)
        for (int k = 0; k < nc; ++k) {
            if (!cand[k].behind) continue;
            const double db = cand[k].dist;
            const Vector3d lo = C.array() - (S.pieceTriRadius[pb] + db);
            const Vector3d hi = C.array() + (S.pieceTriRadius[pb] + db);
            S.triGrid[pb].forRange(lo.data(), hi.data(), [&](int32_t local) {
                if (!keep[k]) return;
                const int32_t t = t0 + local;
                if (!S.triCurrent[t]) return;
                const int32_t* c = &surf.tri[3 * t];
                if (frontFaceNearer(C, at(X, c[0]), at(X, c[1]), at(X, c[2]),
                                    Eigen::Map<const Vector3d>(&S.triNormal[3 * t]), db))
                    keep[k] = false;
            });
        }
    selectTouches(C, cand, nc, keep, surf.triPiece.data(), eps, cosFeature);
}

// The contacts of sphere s with the piece of pair q: their forces (on the
// sphere into the pair's force and torque, on the triangle nodes into buf),
// history and energies (ContactLoop.hpp).  Returns how many.
template <bool Friction>
long pairContacts(const SpherePhase::Data& w, const ContactLoop<Friction>& loop, const SphereAt& s, int32_t q,
                  bool overlap, double cosFeature, CandidateList& cl, bool* keep, double* buf, double* load,
                  EnergyTally& tally) {
    SphereSet& S = w.spheres;
    const SurfaceIndex& surf = w.surface;
    constexpr int K = SphereSet::kSlots;
    const double dt = loop.dt();
    const int32_t i = s.i, pb = S.pairPiece[q];
    const Material& mb = w.materials[w.pieces[pb].material];
    const double reach = s.R + mb.radius;
    const int32_t t0 = surf.pieceTriStart[pb];
    S.pairComputed[q] = 1;
    Vector3d F = Vector3d::Zero(), T = Vector3d::Zero();
    int32_t* key = &S.slotKey[K * static_cast<std::size_t>(q)];
    double* shear = &S.slotShear[3 * K * static_cast<std::size_t>(q)];
    double* ref = &S.slotRef[K * static_cast<std::size_t>(q)];
    const bool watched = S.pairStamp[q] == w.iter - 1;
    if (!watched)  // history is only valid from the previous step
        for (int k = 0; k < K; ++k) key[k] = -1;
    S.pairStamp[q] = w.iter;
    const double eps = 1e-12 * reach;
    findTouches(w, s, pb, reach, overlap, eps, cosFeature, cl, keep);
    const Candidate* cand = cl.c;
    const int nc = cl.n;

    bool usedOld[K] = {false, false, false, false};
    int32_t kpiece[K];
    for (int k = 0; k < K; ++k) kpiece[k] = key[k] >= 0 ? pb : -1;
    // History slots of the touches, in order, then what touches
    // that ended while pressing hand over (TouchSelection.hpp).
    int slotOf[kCandidates];
    for (int k = 0, nT = 0; k < nc; ++k) {
        if (!keep[k] || nT == K) continue;
        const Candidate& c = cand[k];
        slotOf[k] = historySlot(key, kpiece, usedOld, K, historyKey(c.tri - t0, c.cp.feature), pb, cand, keep, nc,
                                surf.triPiece.data(), surf.pieceTriStart.data());
        if (slotOf[k] >= 0) usedOld[slotOf[k]] = true;
        ++nT;
    }
    const bool touched = touchedPiece(key, kpiece, K, pb);
    double handed[kCandidates];
    for (int k = 0; k < nc; ++k) handed[k] = 0.0;
    handOver(s.C, cand, nc, keep, surf.triPiece.data(), surf.pieceTriStart.data(), key, kpiece, ref, usedOld, K, eps,
             [&](int32_t) { return reach; }, handed);
    NewSlots<K> news;
    int32_t newKey[K];
    long count = 0;
    for (int k = 0; k < nc; ++k) {
        if (!keep[k] || news.full()) continue;
        const Candidate& c = cand[k];
        const int32_t* tn = &surf.tri[3 * c.tri];
        double mT;
        Vector3d vT;
        trianglePointState(c, tn, w.mass, w.vel, mT, vT);
        const PairConst pc = mix(sphereSide(S, i), materialSide(mb, mb.frictionPiece));
        const Vector3d nT(S.triNormal[3 * c.tri], S.triNormal[3 * c.tri + 1], S.triNormal[3 * c.tri + 2]);
        ContactGeometry g;
        candidateContact(c, s.C, nT, pc.reach, eps, g.n, g.overlap);
        // Contact point on the sphere, half the overlap inside it
        // (YADE's convention): the lever arm of friction.
        const Vector3d arm = -std::max(s.R - 0.5 * g.overlap, 0.0) * g.n;
        // Dashpots on the reduced mass of the sphere and the triangle point.
        g.mass = S.mass[i] * mT / (S.mass[i] + mT);
        // Tangential mass of a solid ball at its surface: 1/m + R^2/I = 7/(2m)
        // (a clump's is larger: this errs towards less drag, never towards reversing the slip).
        const double mBall = 2.0 / 7.0 * S.mass[i];
        g.slipMass = std::isfinite(mBall) ? mBall * mT / (mBall + mT) : mT;
        // The sphere's material point at the nodes' time level, half
        // a step back along its spin (Obstacle::velocityAt).
        const Vector3d fromSpin = arm - s.spinOff;
        g.vRel = s.v + s.w.cross(s.spinOff) + spinVelocity(s.w, fromSpin, dt) - vT;
        // The spring turns with the ball's spin about n: a rigid
        // body's, the same on every rank and smooth in time
        // (doc/formulation.md, "Twist").
        g.spin = s.w.dot(g.n);
        // A contact found deep on a sphere already watched was missed,
        // not made: it stores no energy it was not given (ContactDetail.hpp).
        // One that splits off a touch of the piece is born at zero force
        // (threshold 0: TouchSelection.hpp).
        const int slot = slotOf[k];
        ContactHistory h;
        if (slot >= 0) h.shear = shear + 3 * slot, h.ref = ref + slot;
        h.watched = watched;
        h.threshold = slot < 0 && touched ? 0.0 : pc.reach;
        h.handed = handed[k];
        newKey[news.n] = historyKey(c.tri - t0, c.cp.feature);
        ContactParams prm;
        const ContactResult r = loop.touch(pc, g, h, news, &tally.elastic, &tally, &prm);
        F += r.force;
        T += arm.cross(r.force);
        for (int j = 0; j < 3; ++j)
            if (c.cp.w[j] != 0) addTo(buf, surf.surfIndexOfNode[tn[j]], -c.cp.w[j] * r.force);
        // The springs on the triangle's corners in their run-time load rows
        // (ContactLoad.hpp; the ball's own side: StableDt's sphere part).
        const int32_t si[3] = {surf.surfIndexOfNode[tn[0]], surf.surfIndexOfNode[tn[1]], surf.surfIndexOfNode[tn[2]]};
        addSphereContactLoad(load, si, c.cp.w, mT, S.mass[i], prm, loop.turns(pc));
        ++count;
    }
    for (int k = 0; k < K; ++k) key[k] = k < news.n ? newKey[k] : -1;
    news.store(shear, ref);
    double* ft = &S.pairForceTorque[6 * static_cast<std::size_t>(q)];
    for (int d = 0; d < 3; ++d) ft[d] = F[d], ft[3 + d] = T[d];
    return count;
}

// Under MPI the pair is computed by the owner of the lowest-id node of the
// triangles within reach of the sphere (bounding spheres within R + r of its
// centre).  With the contact halo as wide as Domain::sendContactHalo makes
// it for spheres, that owner sees every such triangle, and a rank that sees
// another lowest node owns none of them: each pair is computed once
// (doc/parallel.md).
bool ownsPair(const SpherePhase::Data& w, const Domain& dom, const SphereAt& s, int32_t pb, double reach) {
    const SphereSet& S = w.spheres;
    const SurfaceIndex& surf = w.surface;
    const int32_t t0 = surf.pieceTriStart[pb];
    const double qr = S.pieceTriRadius[pb] + reach;
    int32_t lowest = INT32_MAX;
    const Vector3d lo = s.C.array() - qr, hi = s.C.array() + qr;
    S.triGrid[pb].forRange(lo.data(), hi.data(), [&](int32_t local) {
        const int32_t t = t0 + local;
        if (!S.triCurrent[t]) return;
        const double Rt = S.triRadius[t] + reach;
        if ((s.C - Eigen::Map<const Vector3d>(&S.triPoint[3 * t])).squaredNorm() > Rt * Rt) return;
        for (int k = 0; k < 3; ++k) lowest = std::min(lowest, surf.tri[3 * t + k]);
    });
    return lowest != INT32_MAX && dom.owner(lowest) == dom.rank();
}

// A sphere that moves more than its contact reach in one step near a piece
// can jump past the piece's surface before any contact sees it (a 2 cm
// sphere at 500 m/s went through a 0.1 m plate): refused, naming the step
// that would do.
[[noreturn]] void reportFastSphere(const SpherePhase::Data& w, int32_t i, int32_t piece, double dt) {
    const SphereSet& S = w.spheres;
    const double speed = Vector3d(S.vel[3 * i], S.vel[3 * i + 1], S.vel[3 * i + 2]).norm();
    const double reach = S.radius[i] + w.materials[w.pieces[piece].material].radius;
    throw StabilityError(cat("QDEM: YADE sphere ", S.id[i], " moves ", speed * dt, " m per step (", speed,
                             " m/s, dt = ", dt, " s) next to piece ", piece, ", more than its contact reach ", reach,
                             " m (sphere radius ", S.radius[i], " m + the piece's QdemMat radius): it can ",
                             "pass the piece's surface before any contact sees it. Lower O.dt below ", reach / speed,
                             " s, or the speed."));
}

}  // namespace

template <bool Friction>
void SpherePhase::sphereContacts(double dt, double& eEl, double& eDamp, double& eSlip, long& count) {
    SphereSet& S = w_.spheres;
    const int32_t n = S.size();
    const double cosFeature = std::cos(w_.settings.edgeFeatureAngle);
    const std::size_t nSurf = w_.surfNodes.size();
    const ContactLoop<Friction> loop(dt, w_.settings.frictionModel == FrictionModel::Regularized,
                                     w_.settings.frictionRegVelocity);
    const Domain* dom = w_.domain.any();

    // Too fast to be seen (reportFastSphere): the lowest sphere index found,
    // so that every thread count (and every MPI rank: all hold every sphere)
    // says the same.
    int32_t fastSphere = INT32_MAX, fastPiece = -1;
    ThreadPartials<3> energyParts(omp_get_max_threads());  // elastic, damping, slip: added in thread order
#pragma omp parallel reduction(+ : count)
    {
        EnergyTally tally;
        std::vector<double>& bufv = S.threadForce[omp_get_thread_num()];
        bufv.assign(3 * nSurf, 0.0);  // capacity kept: allocates on growth only
        double* buf = bufv.data();
        std::vector<double>& loadv = S.threadLoad[omp_get_thread_num()];
        loadv.assign(2 * nSurf, 0.0);
        CandidateList cl;  // the one candidate policy (PointTriangle.hpp)
        bool keep[kCandidates];
        // Static chunks: a sphere goes to the same thread every run, so a given
        // thread count gives the same bits.  nowait: the region ends with the loop.
#pragma omp for schedule(static, 16) nowait
        for (int32_t i = 0; i < n; ++i) {
            const SphereAt s{i, Vector3d(S.pos[3 * i], S.pos[3 * i + 1], S.pos[3 * i + 2]),
                             Vector3d(S.vel[3 * i], S.vel[3 * i + 1], S.vel[3 * i + 2]),
                             Vector3d(S.angVel[3 * i], S.angVel[3 * i + 1], S.angVel[3 * i + 2]),
                             Vector3d(S.spinOffset[3 * i], S.spinOffset[3 * i + 1], S.spinOffset[3 * i + 2]),
                             S.radius[i]};
            for (int32_t q = S.pairStart[i]; q < S.pairStart[i + 1]; ++q) {
                const int32_t pb = S.pairPiece[q];
                const double reach = s.R + w_.materials[w_.pieces[pb].material].radius;
                bool overlap = true;  // piece box (grown by r) against the sphere's
                for (int d = 0; d < 3 && overlap; ++d)
                    overlap = s.C[d] - s.R <= w_.bounds.hi[3 * pb + d] && w_.bounds.lo[3 * pb + d] <= s.C[d] + s.R;
                if (overlap && dt * s.v.norm() > reach) {
#pragma omp critical(qdemFastSphere)
                    if (i < fastSphere) fastSphere = i, fastPiece = pb;
                }
                if (dom) {
                    if (!overlap) continue;  // no contact: unpackPairs clears it on every rank
                    if (!ownsPair(w_, *dom, s, pb, reach)) continue;
                }
                count += pairContacts<Friction>(w_, loop, s, q, overlap, cosFeature, cl, keep, buf, loadv.data(), tally);
            }
        }
        energyParts.set(omp_get_thread_num(), {tally.elastic, tally.damp, tally.slip});
    }
    const std::array<double, 3> energySum = energyParts.sum();
    eEl += energySum[0];
    eDamp += energySum[1];
    eSlip += energySum[2];
    if (fastSphere != INT32_MAX) reportFastSphere(w_, fastSphere, fastPiece, dt);
}

template void SpherePhase::sphereContacts<true>(double, double&, double&, double&, long&);
template void SpherePhase::sphereContacts<false>(double, double&, double&, double&, long&);

}  // namespace qdem
