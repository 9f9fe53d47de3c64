// The one contact model of QDEM: how the two sides of any contact mix into
// the pair's spring-dashpot and friction constants, and the dashpots from the
// masses.  A side is a QDEM material (a node or surface point of a piece), a
// rigid or elastic YADE obstacle (wall, box, facet), or a YADE sphere.  Every
// contact kind (ObstaclePhase, point-polygon, edge-edge, SpherePhase) and the
// stable step (StableDt.cpp: the stiffest pair a piece can meet) call it, so
// the rules live here only.  Sources: doc/formulation.md "Contact law",
// doc/contacts.md, doc/spheres.md.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "../material/Material.hpp"
#include "ContactLaw.hpp"

namespace qdem {

// What one side of a contact brings to the mixing rules.  "None" values take
// the other side's.
struct ContactSide {
    double stiffness;    // E r of this side [N/m]; infinite: rigid
    double ktRatio;      // its kt / kn; < 0: none
    double restitution;  // its normal restitution; <= 0: none
    double friction;     // its Coulomb coefficient; < 0: none
    double radius;       // its share of the contact reach [m]
};

// kt / kn of a material of Poisson's ratio nu: Mindlin's 2 (1 - nu) / (2 - nu).
inline double mindlinRatio(double poisson) { return 2 * (1 - poisson) / (2 - poisson); }

// A QDEM material; friction is its frictionPiece or frictionWall, whichever
// the other side asks for.
inline ContactSide materialSide(const Material& m, double friction) {
    return {m.young * m.radius, mindlinRatio(m.poisson), m.restitution, friction, m.radius};
}
// A YADE obstacle met by a node of radius r: its Young's modulus over the
// node's radius (young <= 0: rigid); it adds nothing to the reach.
inline ContactSide obstacleSide(double young, double friction, double nodeRadius) {
    return {young > 0 ? young * nodeRadius : std::numeric_limits<double>::infinity(), -1, 0, friction, 0};
}
// The stiffest thing a piece can meet (a rigid wall, or another piece: at
// most the rigid value): for the stable step.
inline ContactSide rigidSide() { return obstacleSide(0, -1, 0); }

// The mixing rules (YADE's FrictPhys for the stiffness, the geometric mean
// of the restitutions, the smaller friction coefficient, the mean of the
// kt/kn ratios): the mass-independent constants of the pair.
inline PairConst mix(const ContactSide& a, const ContactSide& b) {
    PairConst c;
    if (!std::isfinite(a.stiffness)) c.kn = 2 * b.stiffness;
    else if (!std::isfinite(b.stiffness)) c.kn = 2 * a.stiffness;
    else c.kn = 2 * a.stiffness * b.stiffness / (a.stiffness + b.stiffness);
    const double ratio =
        a.ktRatio >= 0 && b.ktRatio >= 0 ? 0.5 * (a.ktRatio + b.ktRatio) : (a.ktRatio >= 0 ? a.ktRatio : b.ktRatio);
    c.kt = c.kn * ratio;
    const double e = a.restitution > 0 && b.restitution > 0 ? std::sqrt(a.restitution * b.restitution)
                                                            : (a.restitution > 0 ? a.restitution : b.restitution);
    c.xi = dampingRatioFromRestitution(e);
    c.mu = a.friction >= 0 && b.friction >= 0 ? std::min(a.friction, b.friction)
                                              : std::max(0.0, a.friction >= 0 ? a.friction : b.friction);
    c.reach = a.radius + b.radius;
    return c;
}

// Spring-dashpot constants of a pair whose contact moves the effective mass
// m (the reduced mass of the two contact points; a node's mass against an
// obstacle): dashpots 2 xi sqrt(k m) keep the pair's damping ratio.
struct PairLaw {
    double kn, cn, kt, ct, mu, reach;
};

inline PairLaw pairLaw(const PairConst& c, double m) {
    return {c.kn, 2 * c.xi * std::sqrt(c.kn * m), c.kt, 2 * c.xi * std::sqrt(c.kt * m), c.mu, c.reach};
}
inline PairLaw pairLaw(const PairConst& c, double ma, double mb) { return pairLaw(c, ma * mb / (ma + mb)); }

}  // namespace qdem
