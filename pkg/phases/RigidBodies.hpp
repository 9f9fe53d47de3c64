// Adaptive rigidity (settings.rigidify; doc/formulation.md, "Adaptive
// rigidity"): the motion of the pieces the awake set marks rigid, and the
// indicators that say when a piece may become rigid or must deform again.
//
// A rigid piece keeps the deformed shape it had when it was made rigid: its
// node offsets from the centre of mass are stored in the body frame, so its
// strain, and the internal forces of that strain, are constant in the body
// frame.  Internal forces of an objective element law are self-equilibrated
// (per tet: zero net force, zero net torque), so the rigid body's motion is
// that of the external forces alone (contacts, gravity, extForce): no element
// pass and no viscous solve (its strain rate is zero), and its strain energy
// stays booked as it was.  The integration phase owns it (one writer of the
// rigid state); the sleep phase reads its indicators to switch pieces.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/AwakeSet.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/Settings.hpp"

namespace qdem {

struct WorldState;

class RigidBodies {
public:
    struct Data {
        const Column<double>& mass;
        const Column<double>& extForce;
        const Column<uint8_t>& blocked;
        const Column<double>& refPos;      // the smallest reference edge of each piece
        const Column<int32_t>& tetNodes;
        const Column<int32_t>& tetMaterial;  // the softest material of a piece sets its wake stiffness
        const std::vector<Material>& materials;
        const std::vector<PieceInfo>& pieces;
        const Eigen::Vector3d& gravity;
        const Settings& settings;
        const AwakeSet& sleeping;          // which pieces are rigid
        const ContactForces& contacts;
        Column<double>& pos;
        Column<double>& vel;
        Column<double>& force;             // the total (external) force on the rigid nodes, for output
        Energy& energy;                    // the removed deformation kinetic energy
    };
    explicit RigidBodies(const Data& data) : w_(data) {}

    // What one step of the rigid pieces adds to the ledger: kinetic energy at
    // the integer time level, -(work of gravity), -(work of extForce), and 1
    // if every new state is finite (else 0).
    struct StepSums {
        double kinetic = 0, gravity = 0, boundary = 0;
        bool finite = true;
    };
    // One leapfrog step of every rigid piece (a piece made rigid since the
    // last step starts from its nodes' state).  speed2[p]: the largest squared
    // node speed of rigid piece p (for the sleep phase).
    StepSums advance(double dt, double* speed2);
    // The strain-rate estimate of every awake deformable piece from its
    // nodes' velocities (after the step), and how long it has stayed below
    // settings.rigidStrainRate.
    void measure(double dt);
    // The sleep phase's switches: a deformable piece slow to deform for
    // rigidTime may become rigid; a rigid one whose load changed must deform.
    bool wantsRigid(std::size_t p) const;
    bool wantsDeformable(std::size_t p) const;
    // Pieces the sleep phase made deformable again (or put to sleep) since
    // the last step: their rigid state is dropped and their dwell starts again.
    void forgetStale();
    double strainRate(std::size_t p) const { return rate_[p]; }      // last estimate [1/s]
    double loadChange(std::size_t p) const { return loadChange_[p]; }  // rigid: relative change of its load
    double loadStrain(std::size_t p) const { return loadStrain_[p]; }  // rigid: the strain that change would make

    void piecesAdded();
    // Restarts: optional fields (files from before it load with no piece rigid).
    void saveFields(WorldState& s) const;
    void checkFields(const WorldState& s) const;
    void loadFields(const WorldState& s);

private:
    // Per piece: centre x, its velocity v (half step), angular momentum L
    // (half step, world frame), orientation q (w, x, y, z: body to world),
    // inverse inertia in the body frame (9), mass, the load scale for the
    // wake test, and whether the state is in use (1) or stale (0).
    static constexpr int kBody = 25;
    enum : int { kX = 0, kV = 3, kL = 6, kQ = 9, kIInv = 13, kMass = 22, kScale = 23, kOn = 24 };
    void start(std::size_t p, double& removed);
    // The piece's forces (into force), their sum and torque, the ledger's work terms.
    void sumForces(std::size_t p, const double* b, double* F, double* T, StepSums& s) const;
    void wakeTest(std::size_t p, const double* b, const Eigen::Matrix3d& R, const Eigen::Vector3d& w,
                  const double* F, const double* T);

    Data w_;
    std::vector<double> body_;      // kBody per piece
    std::vector<double> offset_;    // per node: offset from the centre in the body frame [m]
    std::vector<double> load0_;     // per node: the load deforming it when made rigid (body frame) [N]
    std::vector<uint8_t> loadSet_;  // per piece: load0_ recorded (its first rigid step)
    std::vector<double> belowFor_;  // per piece: time the estimate has been below the threshold [s]
    std::vector<double> rate_;      // per piece: last strain-rate estimate [1/s]
    std::vector<double> loadChange_;
    std::vector<double> loadStrain_;
    std::vector<uint8_t> wake_;     // per piece: its load changed, back to deformable
    std::vector<double> minEdge_;   // per piece: smallest reference edge [m]
    std::vector<double> wakeStiffness_;  // per piece: 2 E A, the load over the strain it makes [N]
    std::vector<StepSums> sums_;    // per piece, summed in piece order (same bits at any thread count)
};

}  // namespace qdem
