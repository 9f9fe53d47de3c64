#include "ThreadBlocks.hpp"

#include <algorithm>

namespace qdem {

void buildThreadBlocks(const ThreadLayout& layout, const int32_t* tetNodes, const double* tetB, const double* tetVol0,
                       const int32_t* tetMaterial, std::vector<ThreadBlocks>& blocks) {
    blocks.resize(layout.nThreads);
#pragma omp parallel for num_threads(layout.nThreads) schedule(static, 1)
    for (int t = 0; t < layout.nThreads; ++t) {
        ThreadBlocks& tb = blocks[t];
        tb.segments.clear();
        int32_t n = 0;
        for (const TetSegment& sg : layout.share[t])
            for (int32_t a = sg.t0, b; a < sg.t1; a = b) {  // runs of one material
                for (b = a + 1; b < sg.t1 && tetMaterial[b] == tetMaterial[a]; ++b) {}
                tb.segments.push_back({sg.piece, n, a, b, tetMaterial[a]});
                n += (b - a + kLanes - 1) / kLanes;
            }
        tb.blocks.resize(n);
        for (const BlockSegment& s : tb.segments)
            for (int32_t e0 = s.t0, i = s.first; e0 < s.t1; e0 += kLanes, ++i)
                fillTetBlock(tb.blocks[i], e0, s.count(e0), tetNodes, tetB, tetVol0);
    }
}

}  // namespace qdem
