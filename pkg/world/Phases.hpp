// The phases of World::step (doc/architecture.md), each with its own state
// (pkg/phases/) and given only the data it declares (Phase.hpp).  The World
// holds them through a pointer, so that World.hpp and whatever includes it
// need none of the phases' headers: only the world's own sources do.
#pragma once
#include <array>

#include "../phases/ElementPhase.hpp"
#include "../phases/IntegrationPhase.hpp"
#include "../phases/ObstaclePhase.hpp"
#include "../phases/PieceContactPhase.hpp"
#include "../phases/SleepPhase.hpp"
#include "../phases/SpherePhase.hpp"

namespace qdem {

class World;

struct WorldPhases {
    // Each phase's Data from the world's members (World.cpp).
    explicit WorldPhases(World& w);
    ObstaclePhase obstacle;
    PieceContactPhase pieceContact;
    SpherePhase sphere;
    ElementPhase element;
    IntegrationPhase integration;
    SleepPhase sleep;
    // In the order of the step; Checkpoint.cpp, addPiece and report() visit
    // them (a fixed array: report() is called every step from Python).
    const std::array<Phase*, 6> list{&obstacle, &pieceContact, &sphere, &element, &integration, &sleep};
};

}  // namespace qdem
