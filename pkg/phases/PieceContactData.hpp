// What the piece-contact phase and its contact kinds (ContactKind.hpp) read
// and write of the world.
#pragma once
#include <cstdint>
#include <vector>

#include "../contact/SurfaceIndex.hpp"
#include "../core/Column.hpp"
#include "../material/Material.hpp"
#include "../parallel/DomainRef.hpp"
#include "../step/AwakeSet.hpp"
#include "../step/ContactForces.hpp"
#include "../step/Energy.hpp"
#include "../step/PieceBounds.hpp"
#include "../mesh/PieceInfo.hpp"
#include "../step/Settings.hpp"

namespace qdem {

struct PieceContactData {
    const Column<double>& pos;
    const Column<double>& vel;
    const Column<double>& refPos;      // feature edges are classified on the reference shape
    const Column<double>& mass;
    const Column<int32_t>& nodePiece;
    const Column<int32_t>& tetNodes;   // the seed's cases A/B/C register tetrahedra
    const Column<int32_t>& surfNodes;
    const Column<double>& surfWeight;
    const std::vector<PieceInfo>& pieces;
    const std::vector<Material>& materials;
    const Settings& settings;
    const long& iter;                  // the step contacts are stamped with
    SurfaceIndex& surface;             // triangles, edges; feature edges re-classified when the angle changes
    const AwakeSet& sleeping;          // which pieces sleep, the awake surface nodes
    const PieceBounds& bounds;         // which pieces can touch
    DomainRef domain;                  // under MPI: owned and current nodes, who computes a contact
    ContactForces& contacts;
    Energy& energy;                    // contact damping and friction
    std::vector<std::vector<double>>& threadPieceEnergy;  // contact energy between pieces, per piece
    // Per piece, what its stiffest element puts on a node of the leapfrog
    // condition (World::refreshElementModes): omega_e^2 and the explicit
    // viscous rate beta omega_e^2 (0 when implicit), for the run-time step
    // of the contacts (ContactLoad.hpp); empty: not checked.
    const std::vector<double>& pieceElementW2;
    const std::vector<double>& pieceElementRate;
};

}  // namespace qdem
