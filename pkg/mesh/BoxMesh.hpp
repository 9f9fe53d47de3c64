// Structured tetrahedral meshes of a rectangular box centred on the origin.
#pragma once
#include "TetMesh.hpp"

namespace qdem {

// nx*ny*nz cells over a box of size lx*ly*lz centred on the origin.
// tetsPerCell: 5 (alternating corner cut), 6 (Kuhn split along a main
// diagonal pointing away from the box centre) or 12 (a body-centre node and
// two triangles per cell face; the seed paper's cubes: 8x8x8 cells give 1,241
// nodes and 6,144 tets).  Mirror symmetry about the box's mid-planes (equal
// lumped masses at mirror-image nodes, so a box dropped flat gets no torque
// from its mesh): exact for even cell counts with every split.  An odd count
// has a middle layer of cells that no split of a cell into these tets makes
// symmetric; with 6 and 12 the asymmetry stays in that layer, with 5 it spans
// the axis (the split alternates cell by cell).  Figures: doc/hard_cases.md.
TetMesh boxMesh(int nx, int ny, int nz, double lx, double ly, double lz, int tetsPerCell);

}  // namespace qdem
