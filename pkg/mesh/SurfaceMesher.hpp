// Tetrahedral meshing of a closed triangle surface with CGAL Mesh_3.
// Compiled only when CGAL is available (QDEM_HAVE_CGAL, target qdemmesher).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "TetMesh.hpp"

namespace qdem {

// What meshClosedSurface did, for the caller to report.
struct SurfaceMeshReport {
    double surfaceVolume = 0;  // volume the input surface encloses
    double meshVolume = 0;     // volume of the tets returned
    double surfaceSize = 0;    // surface triangle size of the last meshing
    double facetDistance = 0;  // facet distance of the last meshing
    int passes = 0;            // meshings (more than 1: the surface was refined to keep the volume)
    double thinnest = 0;       // thickness of the thinnest part thinner than the cells (inf: none)
    std::size_t thinFaces = 0; // input faces on such parts
    std::size_t shortFeatures = 0;    // sharp-edge sets shorter than the surface size, smoothed away
    double shortFeatureMove = 0;      // the largest distance that smoothing moved an input vertex
};

// Fills the volume bounded by a closed, manifold, non-self-intersecting
// triangle surface with tetrahedra of target size cellSize.
//
//   vertices       3 coordinates per vertex (unused vertices are ignored)
//   triangles      3 vertex indices per triangle; any consistent or
//                  inconsistent orientation is accepted
//   cellSize       upper bound on the circumradius of the tets and on the
//                  size of the surface triangles and of sharp-edge segments
//   surfaceSize    upper bound on surface triangle and feature edge size; <= 0
//                  means cellSize (a smaller one refines the skin only)
//   facetDistance  upper bound on the distance between a surface triangle of
//                  the result and the input surface; <= 0 means cellSize/10
//   seed           seed of CGAL's random generators: equal inputs and seeds
//                  give identical meshes
//
// Sharp edges (dihedral angle sharper than 60 degrees) and corners of the
// input are kept, except sets of sharp edges shorter than the surface size
// (stray creases of a scan or an isosurface), which are smoothed away
// first (ShortFeatures.hpp).  Parts thinner than twice the cell size (measured through
// the body along the surface normals) get cells of half their thickness.
// With surfaceSize and facetDistance both <= 0 (the defaults), the surface is
// refined and meshed again (at most 4 meshings) until the mesh keeps 99 % of
// the volume the surface encloses.  Slivers flat on the surface, lower than
// the median element / 3, are removed.  `report`, when given, receives the
// volumes and the sizes of the last meshing.  The result holds only the tets inside the surface, nodes
// renumbered without unused ones, every tet positively oriented; it passes
// checkMesh.  Throws InputError naming the problem for invalid input (too few
// vertices, bad index, NaN, bad cellSize, an open or non-manifold surface, a
// self-intersecting surface, ...) or when no tet results.
TetMesh meshClosedSurface(const std::vector<double>& vertices, const std::vector<int32_t>& triangles,
                          double cellSize, double facetDistance = -1.0, unsigned seed = 0,
                          double surfaceSize = -1.0, SurfaceMeshReport* report = nullptr);

}  // namespace qdem
