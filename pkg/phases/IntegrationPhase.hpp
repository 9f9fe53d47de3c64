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
#include "../world/ContactForces.hpp"
#include "../world/Energy.hpp"
#include "../world/Phase.hpp"
#include "../world/PieceInfo.hpp"
#include "../world/Settings.hpp"
#include "ViscousSolve.hpp"

namespace qdem {

class ElementPhase;
class SleepPhase;

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
        const SleepPhase& sleeping;        // the awake nodes
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
    explicit IntegrationPhase(const Data& data) : w_(data), viscous_(data.viscous) {}
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

private:
    // Throws StabilityError naming the first visited node whose new state or
    // force is not finite and what made it so (called when the update found one).
    // The update of the common step (explicit, no damping or sleep
    // tracking, every node awake): kinetic energy, gravity's and the
    // boundary's work of the step (with EnergyOn), and 1 if every new state
    // is finite, else 0.
    template <bool EnergyOn>
    std::array<double, 4> advancePlain(double dt);
    [[noreturn]] void reportNotFinite(const int32_t* ids, bool all, int32_t count, const double* force) const;

    Data w_;
    ViscousSolve viscous_;  // settings.viscousIntegration = Implicit
    std::vector<std::vector<double>> threadSpeed2_;  // per thread, per piece
    std::vector<const double*> bufPtr_;              // per thread: its element force buffer
    std::vector<int32_t> bufLo_, bufHi_;             // and the node range it covers
};

}  // namespace qdem
