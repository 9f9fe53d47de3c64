// The leapfrog update of the awake nodes: element forces (the element
// phase's thread buffers), contact forces, gravity and external forces.
#pragma once
#include <cstddef>
#include <vector>

#include "../world/Phase.hpp"
#include "ViscousSolve.hpp"

namespace qdem {

class ElementPhase;

class IntegrationPhase final : public Phase {
public:
    IntegrationPhase(World& world, const ElementPhase& elements) : Phase(world), elements_(elements), viscous_(world) {}
    const char* name() const override { return "integrate"; }
    void run(double dt) override;
    // "integrate" without the implicit viscous solve, "viscousSolve", and its
    // conjugate-gradient iterations in the last step ("viscousIterations")
    // and in all steps so far ("viscousIterationsTotal").
    void report(PhaseReport& r) const override;
    // Largest squared node speed of a piece in the last run (sleeping on only).
    double maxSpeed2(std::size_t piece) const;

private:
    const ElementPhase& elements_;
    ViscousSolve viscous_;  // settings.viscousIntegration = Implicit
    std::vector<std::vector<double>> threadSpeed2_;  // per thread, per piece
};

}  // namespace qdem
