// Viscoelastic normal spring-dashpot with a Coulomb-capped tangential spring
// (Cundall-Strack).  Shared by every contact kind: node-wall, point-polygon,
// edge-edge.  Why a tangential spring rather than regularised sliding: a block
// on a slope below the friction angle must stay put, not creep.  The
// regularised law (no history) is kept as an option for the accuracy study
// (World::frictionModel, doc/accuracy.md).  Formulas and sources:
// doc/formulation.md, "Contact law".
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace qdem {

struct ContactParams {
    double kn;        // normal stiffness [N/m]
    double cn;        // normal dashpot [N s/m]
    double kt;        // tangential stiffness [N/m]
    double ct;        // tangential dashpot [N s/m] (damps stick oscillations)
    double friction;  // Coulomb coefficient; 0 = no tangential force at all
    double vReg = 0;  // regularised law only: slip speed at which the full mu*Fn is reached [m/s]
    // Regularised law only: the mass the tangential force moves, the reduced
    // mass of the two contact points [kg] (its drag is integrated implicitly
    // against it); <= 0: infinite (the explicit drag).
    double mEff = 0;
};

// The part of a particle pair's law that depends on the two materials only
// (not on the masses): built by contact_detail::pairConst, tabulated per
// material pair once per step.
struct PairConst {
    double kn;     // normal stiffness
    double kt;     // tangential stiffness
    double xi;     // damping ratio from the pair's restitution
    double mu;     // friction coefficient
    double reach;  // sum of the radii
};

struct ContactResult {
    Eigen::Vector3d force;   // on the particle side (the obstacle gets minus this)
    double elastic = 0;      // energy stored in normal and tangential springs [J]
    double dampPower = 0;    // dashpot power (>= 0 while dissipating) [W]
    double slipWork = 0;     // energy dissipated by sliding this step [J]
};

// n: unit normal towards the particle; overlap > 0; vRel: particle velocity
// minus obstacle velocity at the contact point; shear: tangential spring
// elongation carried from step to step (updated in place); spin: the rate
// [rad/s] at which the contact turns about n, by which the spring is turned
// with it.
// Regularized: instead of the spring, viscous-regularised Coulomb sliding
// Ft = -mu Fn vt / max(|vt|, vReg): mu Fn against the slip above vReg, a
// viscous drag below it, no spring.  The drag c = mu Fn /
// vReg is far too stiff for the explicit step (c dt / m >> 2 at any useful
// vReg), so it is taken implicitly: backward Euler of the slip speed under
// this force alone, u' = u - dt |Ft| / m with |Ft| = mu Fn min(1, u'/vReg),
// gives |Ft| = min(mu Fn, c u / (1 + c dt / m)) (doc/contacts.md,
// "Regularised friction, implicit").  It never reverses the slip within a
// step.  `shear` carries the slip this force alone would have left (to
// estimate the other forces, below), not a spring.
template <bool Friction, bool Regularized = false>
inline ContactResult contactForce(const ContactParams& p, const Eigen::Vector3d& n, double overlap,
                                  const Eigen::Vector3d& vRel, double dt, Eigen::Vector3d& shear,
                                  double spin = 0.0) {
    ContactResult r;
    const double vn = vRel.dot(n);
    const double fnSpring = p.kn * overlap;
    double fn = fnSpring - p.cn * vn;
    if (fn < 0) fn = 0;  // a dashpot may not pull the surfaces together
    r.dampPower = (fnSpring - fn) * vn;  // = -(damping force) * (overlap rate)
    r.force = fn * n;
    r.elastic = 0.5 * fnSpring * overlap;
    if constexpr (Friction && Regularized) {
        const Eigen::Vector3d vt = vRel - vn * n;
        const double cap = p.friction * fn;
        const double c = cap / p.vReg;
        const double hm = p.mEff > 0 ? dt / p.mEff : 0.0;  // velocity change per unit force
        // Slip the step would end with without this force: the current slip
        // plus what the other forces added over the last step, v_n - p_{n-1}
        // (p: the slip this force alone would have left, kept in `shear`;
        // an exact zero there is a new contact, assumed unpushed).  Lagging
        // the other forces by one step is what makes a steadily pushed
        // contact creep at F/c, as the law says, not F/c + dt F/m.
        Eigen::Vector3d vFree = shear.isZero(0.0) ? vt : Eigen::Vector3d(2 * vt - shear);
        vFree -= vFree.dot(n) * n;  // on the current tangent plane
        const double u = vFree.norm();
        const double f = std::min(cap, c / (1 + c * hm) * u);
        const Eigen::Vector3d ft = u > 0 ? Eigen::Vector3d((-f / u) * vFree) : Eigen::Vector3d::Zero();
        r.force += ft;
        // Work at the force's time level: -ft . (v_{n-1/2} + v_{n+1/2}) / 2 dt
        // (where the ledger takes kinetic energy), with the predicted
        // v_{n+1/2} = vFree + ft dt / m: exact for the drag alone, and for a
        // steadily pushed contact.
        r.slipWork = -0.5 * dt * ft.dot(vt + vFree + hm * ft);
        shear = vt + hm * ft;
        if (shear.isZero(0.0)) shear = Eigen::Vector3d(0, 0, 1e-300);  // keep "not new"
    } else if constexpr (Friction) {
        // Carry the spring onto the current tangent plane, keeping its length,
        // so a rotating contact does not create or lose tangential force.
        const double len = shear.norm();
        shear -= shear.dot(n) * n;
        const double lenNew = shear.norm();
        if (lenNew > 0) shear *= len / lenNew;
        // And turn it with the contact about n (the twist): left in place, a
        // spring holding a force on a turning contact lagged behind it, the
        // contact crept at spin |Ft| / kt (doc/formulation.md, "Twist").
        // On the tangent plane now, so the turn keeps its length exactly:
        // the spring stores no energy by it.
        if (spin != 0) {
            const double a = spin * dt;
            shear = std::cos(a) * shear + std::sin(a) * n.cross(shear);
        }
        const double storedBefore = 0.5 * p.kt * shear.squaredNorm();
        const Eigen::Vector3d vt = vRel - vn * n;
        shear += vt * dt;
        Eigen::Vector3d ft = -p.kt * shear - p.ct * vt;
        const double ftMax = p.friction * fn;
        const double ftNorm = ft.norm();
        const bool slipping = ftNorm > ftMax;
        if (slipping) {
            // Sliding: the force is mu*Fn along the trial direction, and the
            // spring alone is reset to produce it, u = -Ft/kt.  (Not Luding's
            // -(Ft + ct v_t)/kt, which makes the spring cancel the dashpot:
            // at 1 m/s and restitution 0.3 it stored 0.039 J where the real
            // stretch holds 1e-4 J, booked as negative friction work, and
            // lost from the ledger when the contact ended with it: a kicked
            // block's books came out 4.6 % short, a paddle's 10 %.)
            // Nor longer than its trial length: when the spring alone is
            // under the cap and the dashpot takes the force over it (the
            // first steps of a fast oblique impact), the spring keeps its
            // trial stretch.  Reset to -Ft/kt there, it jumped to the full
            // cap in one step: a YADE sphere thrown at 1 m/s onto a slab
            // stored more than the force had done, booked as -3.5e-5 J of
            // friction work on its first step of contact.  Either way the
            // force is mu*Fn and the work lost is >= 0 (doc/formulation.md).
            ft *= ftNorm > 0 ? ftMax / ftNorm : 0.0;
            if (p.kt * shear.norm() > ftMax) shear = -ft / p.kt;
        }
        r.force += ft;
        const double stored = 0.5 * p.kt * shear.squaredNorm();
        r.elastic += stored;
        // Whatever the tangential force did and the spring did not store was
        // dissipated: by sliding, or by the tangential dashpot while stuck.
        const double lost = -ft.dot(vt) * dt - (stored - storedBefore);
        if (slipping) r.slipWork = lost;
        else r.dampPower += lost / dt;
    } else {
        shear.setZero();
    }
    return r;
}

// The law as every contact kind calls it: no tangential force at all unless
// friction is on (the caller's switch and a positive coefficient), then the
// tangential spring or, when chosen, the regularised law.
// spin: the contact's rate of turn about n (the spring's twist; the
// regularised law has no spring and ignores it).  Passed where one side is
// a rigid body (a YADE wall, box, facet or sphere): that body's spin
// (doc/formulation.md, "Twist"); 0 between pieces.
inline ContactResult lawForce(bool friction, bool regularized, const ContactParams& p, const Eigen::Vector3d& n,
                              double overlap, const Eigen::Vector3d& vRel, double dt, Eigen::Vector3d& shear,
                              double spin = 0.0) {
    if (!friction) return contactForce<false>(p, n, overlap, vRel, dt, shear);
    return regularized ? contactForce<true, true>(p, n, overlap, vRel, dt, shear)
                       : contactForce<true>(p, n, overlap, vRel, dt, shear, spin);
}

}  // namespace qdem
