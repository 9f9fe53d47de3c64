// Each thread's share of the tets (ThreadLayout) as blocks of kLanes tets
// (TetBlock.hpp), in share order: what the element kernel reads of the
// reference data.  Built with the layout; the element phase and the implicit
// viscous solve each keep one beside their layout.
#pragma once
#include <cstdint>
#include <vector>

#include "../core/Aligned.hpp"
#include "../element/TetBlock.hpp"
#include "ThreadLayout.hpp"

namespace qdem {

// Segment of a share: blocks [first, first + ceil((t1 - t0) / kLanes)),
// tets t0 .. t1-1 of one piece, all of one material (a share's segment is
// cut where tetMaterial changes: a bonded piece of several materials).
struct BlockSegment {
    int32_t piece, first, t0, t1, material;
    int count(int32_t e0) const { return t1 - e0 < kLanes ? t1 - e0 : kLanes; }  // live lanes of the block at e0
};

struct ThreadBlocks {
    AlignedVector<TetBlock> blocks;
    std::vector<BlockSegment> segments;
};

// blocks[t] for every thread t of layout (each thread fills its own: first
// touch); tetMaterial: each tet's material index (segments are cut where it changes).
void buildThreadBlocks(const ThreadLayout& layout, const int32_t* tetNodes, const double* tetB, const double* tetVol0,
                       const int32_t* tetMaterial, std::vector<ThreadBlocks>& blocks);

}  // namespace qdem
