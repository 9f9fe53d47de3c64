// Where a piece's nodes, tets and surface nodes sit in the world's shared
// arrays, and its material and mass properties.
#pragma once
#include <cstdint>

#include "Surface.hpp"

namespace qdem {

struct PieceInfo {
    int32_t nodeBegin, nodeEnd;  // [begin, end) in the global node arrays
    int32_t tetBegin, tetEnd;    // [begin, end) in the global tet arrays
    int32_t surfBegin, surfEnd;  // [begin, end) in surfNodes
    int material;                // its contact material, and its elements' unless bonded
    // A bonded piece of several materials (World::tetMaterial): how many, and
    // the largest viscosity among them (= the material's for one).
    int32_t materialCount = 1;
    double maxViscosity = 0;
    Surface surface;             // in global node / tet ids
    double volume = 0, mass = 0;  // mass: rho V plus addedMass
    // Selective mass scaling (World::massScaling): the mass added to the
    // piece's elements [kg], and the largest added mass at one node over
    // that node's own (rho V / 4 summed) mass, at node addedMaxNode (global id, -1: none).
    double addedMass = 0, addedMaxNodeShare = 0, addedSurfaceMass = 0;
    int32_t addedMaxNode = -1;
    int32_t addedElements = 0;  // elements that got mass
    double minSurfaceNodeMass = 0, maxSurfaceNodeMass = 0;
    // Smallest m_i / w_i over the surface nodes (w_i: surfWeight): the
    // stiffest contact mode of the piece is sqrt(w_i kn / m_i) at that node.
    double minSurfaceMassPerWeight = 0;
    // Largest m_i / w_i (the softest-damped contact per unit stiffness, for
    // the dashpots on a dynamic obstacle) and the mean reference surface area
    // per surface node [m^2] (w_i = 1): a dynamic obstacle's stable step.
    double maxSurfaceMassPerWeight = 0;
    double minSurfaceWeight = 0;
    double meanSurfaceShare = 0;
};

}  // namespace qdem
