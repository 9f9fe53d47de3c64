// The per-contact sequence every contact kernel runs, written once: from a
// contact its kind's geometry measured (normal, overlap, relative velocity,
// masses, area weights) and its history slot, the born-deep reference, the
// pair's law constants, the force, the new history (spring, reference) and
// the energy booked.  The split is YADE's Ig2 / Ip2 / Law2 (LAMMPS
// GRANULAR's geometry / sub-model / force):
//   geometry  ContactGeometry, filled by the kernel (point-polygon,
//             edge-edge, sphere-triangle, node-obstacle: how a kind finds
//             its contacts is its own business);
//   model     Model::params: the pair's mixed constants (PairConst,
//             ContactModel.hpp) on the contact's masses and weights ->
//             ContactParams;
//   law       Law::force: the spring-dashpot with Coulomb friction
//             (lawForce, ContactLaw.hpp).
// Inline, no allocation, no virtual call: the kernels' inner loops call it
// once per contact.  The arithmetic is the kernels' own, in their order, so
// the results are the same bits as before it was shared.
// doc/architecture.md, "One contact loop".
#pragma once
#include <Eigen/Core>

#include "ContactDetail.hpp"
#include "ContactLaw.hpp"
#include "ContactModel.hpp"
#include "TouchSelection.hpp"

namespace qdem {

// What the kind's geometry measured of one contact (Ig2).
struct ContactGeometry {
    Eigen::Vector3d n;     // unit normal, towards the query side (node, sphere centre, first edge)
    double overlap;        // reach - gap [m]; beyond the reach when the query point is behind the surface
    Eigen::Vector3d vRel;  // the query side's contact point's velocity minus the other side's [m/s]
    double spin = 0;       // the contact's rate of turn about n [rad/s]: the spring turns with it
    double mass;           // reduced mass of the two contact points: the dashpots' [kg]
    double slipMass;       // the mass the regularised friction's drag moves [kg] (usually `mass`)
    // Area weights (doc/contacts.md, "Area weights"): the springs kn, kt
    // times stiffWeight, the dashpots cn, ct times dampWeight (its square
    // root, which keeps the damping ratio).  1, 1: a contact of a whole point.
    double stiffWeight = 1, dampWeight = 1;
};

// What the contact's history holds and how it was carried (the slot the
// kind's matching found, TouchSelection.hpp historySlot, or -1).
struct ContactHistory {
    const double* shear = nullptr;  // the slot's tangential spring (3 values); nullptr: a new contact
    const double* ref = nullptr;    // the slot's born-deep reference (when the kind keeps them)
    bool watched = false;           // the query point was looked at on the previous step
    // Born-deep threshold of a new contact (ContactDetail.hpp bornDeepRef):
    // the reach (a contact found deeper was missed, not made), or 0 (a touch
    // that splits off, an edge crossing: born at zero force).
    double threshold = 0;
    // Squared depths handed to this touch by touches of the same piece that
    // ended while pressing (TouchSelection.hpp handOver); 0: none.
    double handed = 0;
    // The spring is stored times this (edge-edge: sqrt of its weight, so a
    // spring carried to another weight keeps its energy); 0: stored as is.
    double shearScale = 0;
};

// The kinds' history rows without a born-deep reference (node-obstacle:
// the obstacle's overlap is always the node's own, never missed).
enum class Reference { Kept, None };

// The contacts a query point (or edge) keeps this step, in order: written
// over its history slots at the end (its keys by the kind: slot i of the
// kind's key arrays belongs to entry i here).
template <int K>
struct NewSlots {
    int n = 0;
    Eigen::Vector3d shear[K];
    double ref[K];
    bool full() const { return n == K; }
    // The kept slots over the old ones; slots past n keep a reference of 0
    // (their spring is never read: the kind's empty key marks them).
    void store(double* shearOut, double* refOut) const {
        for (int k = 0; k < K; ++k) {
            if (refOut) refOut[k] = k < n ? ref[k] : 0.0;
            if (k < n)
                for (int d = 0; d < 3; ++d) shearOut[3 * k + d] = shear[k][d];
        }
    }
};

// Per-thread energy tallies of a contact kernel [J]: added in thread order
// after the loop (ThreadPartials.hpp).
struct EnergyTally {
    double elastic = 0;  // kinds that book stored energy per thread (spheres), not per piece
    double damp = 0;     // by the dashpots
    double slip = 0;     // by sliding
};

// Ip2: the pair's constants (mixed once per pair) on the contact's masses
// and area weights.
struct MixedPairModel {
    static ContactParams params(const PairConst& c, const ContactGeometry& g, double regVelocity) {
        const PairLaw law = pairLaw(c, g.mass);
        return {g.stiffWeight * law.kn, g.dampWeight * law.cn, g.stiffWeight * law.kt, g.dampWeight * law.ct,
                law.mu,                 regVelocity,           g.slipMass};
    }
};

// Law2: the viscoelastic normal spring-dashpot with a Coulomb-capped
// tangential spring, or the regularised friction (ContactLaw.hpp).
struct SpringDashpotLaw {
    static ContactResult force(bool friction, bool regularized, const ContactParams& p, const Eigen::Vector3d& n,
                               double delta, const Eigen::Vector3d& vRel, double dt, Eigen::Vector3d& shear,
                               double spin) {
        return lawForce(friction, regularized, p, n, delta, vRel, dt, shear, spin);
    }
};

// The sequence, with the step's constants: Friction is the kernel's compile-
// time switch (friction on in the settings), frictionOn the same at run time
// for a kernel compiled once for both; a contact has friction when both are
// on and its pair's coefficient is positive.
template <bool Friction, Reference Ref = Reference::Kept, class Model = MixedPairModel,
          class Law = SpringDashpotLaw>
class ContactLoop {
public:
    ContactLoop(double dt, bool regularized, double regVelocity, bool frictionOn = true)
        : dt_(dt), regularized_(regularized), frictionOn_(frictionOn), regVelocity_(regVelocity) {}

    double dt() const { return dt_; }
    bool regularized() const { return regularized_; }
    // Whether the contact's spring turns (and so whether the kind need
    // measure its spin): friction on, a positive coefficient, the spring law.
    bool turns(const PairConst& c) const { return Friction && frictionOn_ && c.mu > 0 && !regularized_; }

    // One contact: its reference (born deep, handed over), its force, its
    // new history slot (pushed onto `out`: the reference kept is
    // out.ref[out.n - 1], the spring acts on overlap - reference), its
    // energy: the stored energy into *elastic (the piece's ledger entry, a
    // thread tally; nullptr: not booked), dissipation into `tally` (nullptr:
    // not booked).  Returns the force on the query side and the energies;
    // the constants the law used go to *used (contact loads, dynamic
    // obstacles; nullptr: not wanted).  (A plain ContactResult back, not a
    // struct with the constants: returning those too changed how the
    // compiler paired the callers' cross products into vector FMAs, and
    // with it the last bits of a sphere's torque.)
    template <int K>
    ContactResult touch(const PairConst& c, const ContactGeometry& g, const ContactHistory& h, NewSlots<K>& out,
                        double* elastic, EnergyTally* tally, ContactParams* used = nullptr) const {
        const ContactParams p = Model::params(c, g, regVelocity_);
        Eigen::Vector3d sh = Eigen::Vector3d::Zero();
        if (h.shear) {
            sh = Eigen::Vector3d(h.shear[0], h.shear[1], h.shear[2]);
            if (h.shearScale != 0) sh /= h.shearScale;
        }
        double ref = 0.0;
        if constexpr (Ref == Reference::Kept) {
            ref = contact_detail::bornDeepRef(h.shear != nullptr, h.shear ? *h.ref : 0.0, h.watched, g.overlap,
                                              h.threshold, g.vRel.dot(g.n), dt_);
            if (h.handed > 0) ref = contact_detail::handOverRef(g.overlap, ref, h.handed);
        }
        const bool friction = Friction && frictionOn_ && p.friction > 0;
        const ContactResult r = Law::force(friction, regularized_, p, g.n, g.overlap - ref, g.vRel, dt_, sh, g.spin);
        out.shear[out.n] = h.shearScale != 0 ? Eigen::Vector3d(sh * h.shearScale) : sh;
        out.ref[out.n] = ref;
        ++out.n;
        if (elastic) *elastic += r.elastic;
        if (tally) {
            tally->damp += r.dampPower * dt_;
            tally->slip += r.slipWork;
        }
        if (used) *used = p;
        return r;
    }

private:
    double dt_;
    bool regularized_;
    bool frictionOn_;
    double regVelocity_;
};

// The slot of the previous step's history that a contact continues, by the
// kind's own key (match(k): slot k holds this contact's key); the last
// match, -1: a new contact.  (Point and sphere touches match by surface
// feature and inherit springs: TouchSelection.hpp historySlot.)
template <class Match>
inline int matchSlot(int K, Match&& match) {
    int slot = -1;
    for (int k = 0; k < K; ++k)
        if (match(k)) slot = k;
    return slot;
}

}  // namespace qdem
