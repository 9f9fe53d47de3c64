// Rigid YADE bodies that QDEM surface nodes touch: Wall (infinite plane),
// Box (oriented box) and Facet (triangle).  Their state is copied in from
// YADE every step; their reactions are summed here and handed back to YADE
// through O.forces.
#pragma once
#include <string>
#include <vector>
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace qdem {

// Velocity about a spin centre of the material point now at arm r, spinning
// at w, at the time level of the QDEM nodes' velocities (the step just
// made): the arm taken half a step back, w x (r - (w x r) dt/2)
// (Obstacle::velocityAt says why; the sphere contact uses it too).
inline Eigen::Vector3d spinVelocity(const Eigen::Vector3d& w, const Eigen::Vector3d& r, double dt) {
    return w.cross(r - 0.5 * dt * w.cross(r));
}

enum class ObstacleKind : int { Wall = 0, Box = 1, Facet = 2 };

struct Obstacle {
    ObstacleKind kind = ObstacleKind::Wall;
    int bodyId = -1;      // YADE body id (the key of tangential-spring history)
    double young = 0;     // the body material's Young modulus; <= 0 means rigid
    double friction = -1; // its Coulomb coefficient (the contact takes the smaller of it and the
                          // piece's frictionWall, ContactModel.hpp); < 0: none, frictionWall alone
    // How YADE moves the body under the reactions (set by scanObstacles, not
    // part of the signature): 1/mass when a translation is free, 1/(smallest
    // principal moment of inertia) when a rotation is free; both 0 for a
    // fixed body (Body.dynamic false, or every DOF blocked); infinite for a
    // free DOF of zero mass or inertia.  For a clump member, its clump's, and
    // armOffset the distance from the member's position to the clump's.
    double invMass = 0, invInertia = 0, armOffset = 0;
    int axis = 2;         // Wall: normal axis 0/1/2
    int sense = 0;        // Wall: 0 both sides, +1 positive side only, -1 negative side only
    Eigen::Vector3d halfExtents = Eigen::Vector3d::Zero();  // Box
    Eigen::Vector3d localVerts[3];                           // Facet, body frame

    // State at the current step (set by World::setObstacleState).
    Eigen::Vector3d pos = Eigen::Vector3d::Zero();
    Eigen::Quaterniond ori = Eigen::Quaterniond::Identity();
    Eigen::Vector3d vel = Eigen::Vector3d::Zero();
    Eigen::Vector3d angVel = Eigen::Vector3d::Zero();
    // The point whose velocity vel + angVel x (spinCentre - pos) is: a clump
    // member's clump centre (YADE sets a member's vel from its clump's at the
    // member's current place), else pos itself.
    Eigen::Vector3d spinCentre = Eigen::Vector3d::Zero();

    // Derived from the state.
    Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
    Eigen::Vector3d worldVerts[3];
    Eigen::Vector3d lo, hi;  // axis-aligned bounds (walls: infinite across)

    // Reaction of the last step: force on the body and torque about its
    // position (what goes to O.forces).
    Eigen::Vector3d reactionForce = Eigen::Vector3d::Zero();
    Eigen::Vector3d reactionTorque = Eigen::Vector3d::Zero();

    void updateDerived();
    // Does YADE move it under the reactions (StableDt.cpp, ObstaclePhase.cpp)?
    bool dynamic() const { return invMass > 0 || invInertia > 0; }
    // Largest distance from pos to a point of its surface (infinite for a wall).
    double extentRadius() const;
    // sum of 1/m and r^2/I for a contact force applied at distance r from pos:
    // the largest acceleration per unit force it gets there (r measured
    // from the clump's centre for a clump member).
    double mobilityAt(double r) const {
        const double arm = r + armOffset;
        return invMass + (invInertia > 0 ? invInertia * arm * arm : 0.0);
    }
    // Velocity of the obstacle's material point now at p, at the time level
    // of the QDEM nodes' velocities: the step just made, x_n - x_{n-1} over
    // dt (leapfrog).  YADE's vel is that for the spin centre, but
    // vel + w x r takes the arm r where the point is now, not where it was
    // half a step ago (r - w x r dt/2): off by -w x (w x r) dt/2, a
    // centripetal term.  Against nodes that move on the exact chord, that
    // bias reads as a steady radial slip: a piece stuck on a turntable crept
    // towards the axis by w^2 r dt/2 (doc/contacts.md, "Rotating bodies").
    Eigen::Vector3d velocityAt(const Eigen::Vector3d& p, double dt) const {
        const Eigen::Vector3d r = p - spinCentre;
        return vel + angVel.cross(spinCentre - pos) + spinVelocity(angVel, r, dt);
    }
};

// "box (YADE body 3, mass 0.002 kg)": a dynamic obstacle in error messages.
std::string describeDynamic(const Obstacle& o);

// Did a point that moved from `from` to `to` (relative to the obstacle)
// pass through a thin obstacle's surface: the plane of a two-sided wall, or
// a facet's triangle?  (One-sided walls and boxes are solid: a point behind
// or inside them is pushed out, not lost.)
bool crossedThin(const Obstacle& o, const Eigen::Vector3d& from, const Eigen::Vector3d& to);

// Distance from p to the obstacle's surface (a wall's plane, a box's faces,
// a facet's triangle), whichever side p is on.
double distanceToSurface(const Obstacle& o, const Eigen::Vector3d& p);

// How far behind a one-sided wall's plane x lies (<= 0: on its side); 0 for
// the other kinds.
double depthBehind(const Obstacle& o, const Eigen::Vector3d& x);

// What identifies a list of obstacles apart from their motion: kind, body,
// material and shape of each, flattened (18 numbers per obstacle).  Equal
// signatures mean contact histories and reactions by index stay valid.
std::vector<double> obstacleSignature(const std::vector<Obstacle>& obstacles);

// Where a particle of radius r centred at x touches an obstacle.
struct ObstacleHit {
    Eigen::Vector3d normal;  // unit, from the obstacle towards the particle
    Eigen::Vector3d point;   // contact point on the obstacle surface
    double overlap;          // > 0 when in contact
    int side = 0;            // kept as history: two-sided walls and facets, +1/-1 side of the particle;
                             // boxes, the face +-(local axis + 1)
};

// Returns false when the particle does not touch the obstacle.  prevSide is
// the side the particle was on when the contact began (0 = new contact): a
// particle pushed through a two-sided wall or facet by a hard impact is then
// still pushed back to where it came from, instead of being let through; one
// pushed into a box, back out of the face it came in by.
bool touchObstacle(const Obstacle& o, const Eigen::Vector3d& x, double r, int prevSide, ObstacleHit& hit);

}  // namespace qdem
