// Structured tetrahedral meshes of a rectangular box centred on the origin.
#pragma once
#include "TetMesh.hpp"

namespace qdem {

// nx*ny*nz cells over a box of size lx*ly*lz centred on the origin.
// tetsPerCell: 5 (alternating corner cut), 6 (Kuhn split along the main
// diagonal) or 12 (a body-centre node and two triangles per cell face; the
// seed paper's cubes: 8x8x8 cells give 1,241 nodes and 6,144 tets).
TetMesh boxMesh(int nx, int ny, int nz, double lx, double ly, double lz, int tetsPerCell);

}  // namespace qdem
