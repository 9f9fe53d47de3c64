// Connected parts of a tetrahedral mesh.  A piece must be one part: the
// contact search skips pairs within a piece, so two parts of one mesh would
// pass through each other (issue 12).
#pragma once
#include <cstdint>
#include <vector>

#include "TetMesh.hpp"

namespace qdem {

struct MeshParts {
    int count = 0;
    std::vector<int32_t> tetPart;   // per tet, its part (0 = the part of tet 0, then by first tet)
    std::vector<int32_t> tetCount;  // per part, its tets
    std::vector<int32_t> nodeCount; // per part, its nodes
};

// Tets are joined when they share a node.  For a mesh whose surface passes
// extractSurface (manifold at every node) this is the same as sharing faces:
// the tets around a node then form one face-connected fan.
MeshParts meshParts(const TetMesh& m);

// Throws InputError naming the number of parts, their sizes and the fix
// (qdem.splitMesh) when the mesh has more than one part.
void checkOnePart(const TetMesh& m);

}  // namespace qdem
