// Inner nodes driven through a box, a facet or a two-sided wall: the piece
// crushed through itself against it (ObstacleCrushCheck.cpp).
#pragma once
#include <cstdint>
#include <vector>

#include "../contact/ContactModel.hpp"
#include "ObstaclePhase.hpp"

namespace qdem {

// Throws StabilityError naming the first inner node (non-surface node) of an
// awake piece that went through one of the boxes, facets or two-sided walls
// it can reach (pieceObstacles, CSR by piece, with their pairs' constants)
// in the step just made, with the impact speed, the wave speed and the
// stopping distance.  surfaceNode: per node, 1 on the surface (refilled
// when the node count changes).
void checkInnerNodesThrough(const ObstaclePhase::Data& w, const std::vector<int>& pieceObstacles,
                            const std::vector<int>& pieceObstacleBegin, const std::vector<PairConst>& pairConst,
                            std::vector<uint8_t>& surfaceNode, double dt);

}  // namespace qdem
