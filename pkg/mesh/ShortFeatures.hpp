// Sharp features of an input surface too short for the mesh to follow.
//
// Mesh_3 protects every sharp edge of the input (dihedral sharper than the
// feature angle) with balls along it, and the tetrahedra there are no larger
// than the feature.  A scan or an isosurface holds stray sharp edges a
// fraction of a millimetre long where a fillet is sampled coarsely: a plate
// on a ball (marching cubes, spacing 13 mm) had one 0.55 mm long, and the
// tetrahedra around it cut the piece's stable step 155x below its median
// element.  A feature shorter than the surface size cannot be drawn by
// triangles of that size anyway: its vertices are smoothed (each moved along
// its normal towards the mean of its neighbours, by at most half its shortest
// edge, a few rounds) until it is no longer sharp.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

namespace qdem {

struct ShortFeatureReport {
    std::size_t smoothed = 0;   // connected sharp-edge sets shorter than minLength that were smoothed
    std::size_t kept = 0;       // sharp-edge sets kept (at least minLength long)
    double longestMoved = 0;    // the largest distance a vertex was moved
};

// points: the surface's vertices (moved in place); tris: consistently
// oriented triangles of a closed manifold surface.  A set of sharp edges
// (angle between the outward normals of an edge's two triangles above
// featureAngleDeg) connected through shared vertices, of total length below
// minLength, is smoothed away; longer ones are left as they are.
ShortFeatureReport smoothShortFeatures(std::vector<std::array<double, 3>>& points,
                                       const std::vector<std::array<std::size_t, 3>>& tris, double featureAngleDeg,
                                       double minLength);

}  // namespace qdem
