// Sliver removal from an existing tetrahedral mesh with CGAL's tetrahedral
// isotropic remeshing (Tetrahedral_remeshing, CGAL >= 5.1).  Compiled only
// when CGAL is available (QDEM_HAVE_CGAL, target qdemmesher).
#pragma once
#include <cstdint>
#include <vector>

#include "TetMesh.hpp"

namespace qdem {

struct RemeshOptions {
    // Target edge length of the result; <= 0 selects the median length of
    // the input's boundary edges (the resolution of the surface it keeps).
    double targetEdge = -1.0;
    // Full passes of split / collapse / flip / smooth (CGAL adds three passes
    // of flip and smooth after them).
    int iterations = 8;
    // A boundary edge is a feature (kept: its vertices do not move, it is
    // only split or collapsed along itself) where the outward normals of its
    // two boundary triangles turn by more than this angle [degrees].
    double featureAngleDeg = 40.0;
    // While the worst element cuts the elastic step by more than this
    // against the median one, up to extraRounds more rounds of 3 passes.
    // 2.5 by this geometric measure is up to 3 by qdem's exact element
    // eigenvalues (a bumpy ball: 2.57 here, 2.99 by World.stableDt).
    double maxStepFactor = 2.5;
    int extraRounds = 3;
};

struct RemeshResult {
    TetMesh mesh;                         // positively oriented, no unused nodes
    // Numbered as the input's nodes once the nodes no tet uses are dropped:
    std::vector<int32_t> featureEdges;    // 2 per feature edge of the input
    std::vector<int32_t> corners;         // nodes fixed in place: >= 3 or exactly 1 feature edge
    std::size_t projected = 0;            // surface nodes moved onto the input surface afterwards
    std::size_t patches = 0;
    int rounds = 0;                       // calls of CGAL's remeshing (1 + extra rounds used)              // smooth surface patches between the feature edges
    double targetEdge = 0;                // the target edge length used
    double maxDeviation = 0;              // two-sided sampled distance between the surfaces (below)
    double maxDeviationOut = 0;           // result's boundary vertices and face centres to the input surface
    double maxDeviationIn = 0;            // input's boundary vertices and face centres to the result's surface
};

// Remeshes the interior and the boundary of `in` to a uniform edge length,
// removing slivers, while the boundary surface keeps its shape: the surface
// is cut into patches by the feature edges, boundary vertices move within
// their patch (CGAL projects them onto a smooth fit of it) and are put onto
// the input surface at the end; feature edges and corners stay.  Numbering
// is not kept: the result's nodes and tets are new.
//
// Throws InputError naming the problem for an invalid input (see checkMesh;
// a non-manifold surface) or when CGAL fails or yields an invalid mesh.
// The deviation is sampled at vertices and face centres with an AABB tree of
// the other surface's triangles (a lower bound of the Hausdorff distance,
// equal to it for faces smaller than their curvature radius).
RemeshResult remeshTets(const TetMesh& in, const RemeshOptions& opt);

// Feature edges of a mesh's boundary (pairs of node indices, a < b): the
// outward normals of the two boundary triangles turn by more than
// featureAngleDeg.
std::vector<int32_t> boundaryFeatureEdges(const TetMesh& m, double featureAngleDeg);

}  // namespace qdem
