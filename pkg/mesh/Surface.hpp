// The surface of a tetrahedral mesh: what contact detection works on.
#pragma once
#include <cstdint>
#include <vector>

#include "TetMesh.hpp"

namespace qdem {

struct Surface {
    std::vector<int32_t> triangles;  // 3 per boundary face, ordered so the normal points out
    std::vector<int32_t> triTet;     // owning tetrahedron of each boundary face
    std::vector<int32_t> edges;      // 2 per boundary edge (a < b), each once
    std::vector<int32_t> nodes;      // boundary nodes, ascending
    std::vector<int32_t> tets;       // tetrahedra owning at least one boundary face, ascending

    std::size_t nTriangles() const { return triangles.size() / 3; }
    std::size_t nEdges() const { return edges.size() / 2; }
};

// Extracts the boundary of a checked, positively oriented mesh.  A face shared
// by more than two tetrahedra, or a boundary edge not shared by exactly two
// boundary faces, makes the surface non-manifold: InputError names it.
Surface extractSurface(const TetMesh& m);

}  // namespace qdem
