// YADE spheres (standalone or clump members) that may touch QDEM pieces.  The
// Python glue fills the properties when YADE's collider refreshes its
// candidate lists and the states every step; the sphere-contact phase fills
// forceTorque.  Struct of arrays, sized on set-up only.
#pragma once
#include <cstdint>
#include <limits>
#include <vector>

#include "CellGrid.hpp"

namespace qdem {

struct SphereSet {
    // ---- per sphere, set when the candidate lists change ----------------------
    std::vector<int32_t> id;            // YADE body id
    std::vector<double> radius;         // [m]
    std::vector<double> young;          // Young's modulus of its material [Pa]
    std::vector<double> ktRatio;        // its material's ks/kn (FrictMat.poisson); < 0: none
    std::vector<double> friction;       // tan(frictionAngle)
    std::vector<double> restitution;    // its material's normal restitution; <= 0: none (FrictMat)
    std::vector<double> mass;           // mass that moves with it (the clump's for a member) [kg]
    std::vector<int32_t> pairStart;     // CSR over spheres: the pieces each sphere may touch
    std::vector<int32_t> pairPiece;
    // ---- per sphere, every step ------------------------------------------------
    std::vector<double> pos, vel, angVel;  // 3 each, at the time level of the QDEM nodes
    // 3 each: from pos to the point the sphere spins about (Obstacle::velocityAt
    // says why it matters): its clump's centre for a clump member, else 0.
    std::vector<double> spinOffset;
    std::vector<double> forceTorque;       // 6 each: force and torque on the sphere this step

    // ---- contact history: kSlots per (sphere, piece) pair -----------------------
    static constexpr int kSlots = 4;
    std::vector<int32_t> slotKey;  // 8 * triangle + feature; -1 = empty
    std::vector<double> slotShear; // tangential spring, 3 per slot
    std::vector<double> slotRef;   // reference overlap of a contact born deep (doc/contacts.md §5)
    std::vector<long> pairStamp;   // step at which the pair's slots were last written
    std::vector<double> pairForceTorque;  // 6 per pair: what the pair gave the sphere this step
    std::vector<uint8_t> pairComputed;    // this rank computed the pair this step (MPI: its owner)
    // Under MPI: the pairs whose sphere box meets the whole piece's box this
    // step (the same list on every rank: the boxes are reduced first).
    std::vector<int32_t> active;

    // ---- derived on set-up ------------------------------------------------------
    double radiusMax = 0;
    // The stable step (SpherePhase::setSpheres, doc/spheres.md "Stable time
    // step"): per piece, the stiffest sphere spring [N/m] and, of the spheres
    // it is paired with, the largest k/m on the sphere's side of the two-mass
    // mode [1/s^2] (a ball's tangential mass at its surface is 2m/7) and the
    // largest dashpot rate c/m_eff [1/s]; and the sphere side's own leapfrog
    // limit [s] (inf: no pair).  [0]: normal springs only (no friction, or
    // the regularised law), [1]: with the tangential springs of pairs with
    // friction.
    struct StepBound {
        std::vector<double> pieceK, pieceSphereW2, pieceSphereRate;
        double stableStep = std::numeric_limits<double>::infinity();
    };
    StepBound bound[2];

    // ---- working data of the phase (reused: no allocation per step) -------------
    std::vector<CellGrid> triGrid;       // per piece: its surface triangles by centroid
    std::vector<double> triPoint, triRadius, triNormal;  // per surface triangle (3, 1, 3)
    std::vector<double> pieceTriRadius;  // per piece: largest triangle bounding radius
    std::vector<uint8_t> pieceUsed;      // per piece: some sphere may touch it
    std::vector<uint8_t> triCurrent;     // per surface triangle: its nodes are current here (MPI)
    std::vector<std::vector<double>> threadForce;  // per thread, 3 per surface node
    std::vector<std::vector<double>> threadLoad;   // per thread, 2 per surface node (ContactLoad.hpp)

    int32_t size() const { return static_cast<int32_t>(id.size()); }
};

}  // namespace qdem
