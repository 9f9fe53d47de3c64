// The leapfrog update of the awake nodes: element forces (the element
// phase's thread buffers), contact forces, gravity and external forces.
#pragma once
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../core/Column.hpp"
#include "../parallel/DomainRef.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/Phase.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"
#include "../step/AwakeSet.hpp"
#include "RigidBodies.hpp"
#include "ViscousSolve.hpp"

namespace qdem {

class ElementPhase;

class IntegrationPhase final : public Phase {
public:
    // What it reads and writes of the world.
    struct Data {
        const Column<double>& mass;
        const Column<double>& extForce;
        const Column<uint8_t>& blocked;
        const Column<int32_t>& nodePiece;
        const std::vector<PieceInfo>& pieces;
        const Eigen::Vector3d& gravity;
        const Settings& settings;
        const AwakeSet& sleeping;          // the awake nodes
        const ElementPhase& elements;      // its thread buffers of element forces
        const ContactForces& contacts;
        DomainRef domain;                  // forces other ranks computed on this rank's nodes
        Column<double>& pos;
        Column<double>& vel;
        Column<double>& force;             // the total force of the step, for output
        Energy& energy;                    // kinetic, gravity work, local damping
        const long& iter;                  // steps done (the error names the step being made)
        const double& time;
        ViscousSolve::Data viscous;        // what the implicit viscous solve reads
    };
    explicit IntegrationPhase(const Data& data)
        : w_(data),
          viscous_(data.viscous),
          rigid_({.mass = data.mass, .extForce = data.extForce, .blocked = data.blocked,
                  .refPos = data.viscous.refPos, .tetNodes = data.viscous.tetNodes,
                  .tetMaterial = data.viscous.tetMaterial, .materials = data.viscous.materials, .pieces = data.pieces,
                  .gravity = data.gravity, .settings = data.settings, .sleeping = data.sleeping,
                  .contacts = data.contacts, .pos = data.pos, .vel = data.vel, .force = data.force,
                  .energy = data.energy}) {}
    const char* name() const override { return "integrate"; }
    void run(double dt) override;
    // "integrate" without the implicit viscous solve, "viscousSolve", and its
    // conjugate-gradient iterations in the last step ("viscousIterations")
    // and in all steps so far ("viscousIterationsTotal").
    void report(PhaseReport& r) const override;
    // The implicit solve's warm start (ViscousSolve::warmStart): migrated
    // between MPI ranks as node rows, and saved in restarts (files from
    // before it load with none: the next solve starts from 0).
    void stateColumns(StateColumns& c) override;
    void piecesAdded() override;
    void saveFields(WorldState& s) const override;
    void checkFields(const WorldState& s) const override;
    void loadFields(const WorldState& s) override;
    // Largest squared node speed of a piece in the last run (sleeping on only).
    double maxSpeed2(std::size_t piece) const;
    // The rigid pieces' motion and the indicators that switch them (settings.rigidify).
    const RigidBodies& rigid() const { return rigid_; }
    RigidBodies& rigid() { return rigid_; }

private:
    // One step's node update: where the forces come from and which nodes
    // move, as raw pointers and flags copied into the loops (read through a
    // reference or `this`, a pointer would be reloaded after every double
    // store).
    struct NodeUpdate {
        double* X;
        double* V;
        double* Fout;
        const double* Fext;
        const double* Fc;        // contact forces, read when withContacts
        const double* M;
        const double* Fg;        // forces from other ranks (MPI), or nullptr
        const uint8_t* blk;
        const int32_t* nodePiece;
        double g[3];
        const double* const* buf;  // per thread: its element force buffer
        const int32_t* bufLo;      // and the node range it covers
        const int32_t* bufHi;
        int stride, nth;
        bool withContacts;
        bool all;                  // every node awake: ids not read
        const int32_t* ids;        // the awake nodes
        int32_t count;
        double damp;
        bool sleepOn;              // track the pieces' largest speeds
        // The explicit force on node n: external, gravity, element buffers,
        // contacts and other ranks' forces, summed in this order.
        void explicitForce(int32_t n, double* f) const {
            for (int d = 0; d < 3; ++d) f[d] = Fext[3 * n + d] + M[n] * g[d];
            for (int t = 0; t < nth; ++t)
                if (n >= bufLo[t] && n <= bufHi[t]) {
                    const double* b = buf[t] + stride * (n - bufLo[t]);
                    f[0] += b[0];
                    f[1] += b[1];
                    f[2] += b[2];
                }
            if (withContacts)
                for (int d = 0; d < 3; ++d) f[d] += Fc[3 * n + d];
            if (Fg)
                for (int d = 0; d < 3; ++d) f[d] += Fg[3 * n + d];
        }
    };
    // The pointers and flags of this step (and the per-thread speed and flat
    // buffer arrays sized for it).
    NodeUpdate nodeUpdate();
    // With the implicit viscous solve: the explicit forces into force, then
    // the viscous correction q (nullptr without it).
    const double* viscousCorrection(NodeUpdate u, bool implicit, double dt);
    // The leapfrog update of the awake nodes, compiled per combination of the
    // implicit solve, local damping, energy and sleep tracking: kinetic
    // energy, gravity's work, damping's, 1 if every new state is finite (else
    // 0), the boundary's work.  dV: the velocity changes kept for the
    // viscous energy term (positions then move after it).
    template <bool Implicit, bool Damp, bool EnergyOn, bool SleepOn>
    std::array<double, 5> advance(NodeUpdate u, double dt, const double* Fq, double* dV);
    // advance for the run-time flags.
    std::array<double, 5> advanceAny(NodeUpdate u, double dt, const double* Fq, double* dV, bool energyOn);
    // The update of the common step (explicit, no damping or sleep
    // tracking, every node awake): kinetic energy, gravity's and the
    // boundary's work of the step (with EnergyOn), and 1 if every new state
    // is finite, else 0.
    template <bool EnergyOn>
    std::array<double, 4> advancePlain(double dt);
    // The rigid pieces' step (their ledger terms added), then the strain-rate
    // estimates of the deformable ones.
    void advanceRigid(double dt, bool energyOn, bool sleepOn);
    // Throws StabilityError naming the first visited node whose new state or
    // force is not finite and what made it so (called when the update found one).
    [[noreturn]] void reportNotFinite(const int32_t* ids, bool all, int32_t count, const double* force) const;

    Data w_;
    ViscousSolve viscous_;  // settings.viscousIntegration = Implicit
    RigidBodies rigid_;     // settings.rigidify
    std::vector<std::vector<double>> threadSpeed2_;  // per thread, per piece
    std::vector<const double*> bufPtr_;              // per thread: its element force buffer
    std::vector<int32_t> bufLo_, bufHi_;             // and the node range it covers
};

}  // namespace qdem
