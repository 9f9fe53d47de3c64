#include "ThreadLayout.hpp"

#include <algorithm>
#include <limits>

namespace qdem {

void ThreadLayout::build(const int32_t* tetNodes, std::size_t tets, int threads) {
    nThreads = std::max(1, threads);
    nTets = tets;
    tetBegin.assign(nThreads + 1, 0);
    nodeLo.assign(nThreads, std::numeric_limits<int32_t>::max());
    nodeHi.assign(nThreads, -1);
    buffers.assign(nThreads, {});
    for (int t = 0; t <= nThreads; ++t) tetBegin[t] = static_cast<int32_t>(tets * t / nThreads);
    for (int t = 0; t < nThreads; ++t) {
        for (int32_t e = tetBegin[t]; e < tetBegin[t + 1]; ++e)
            for (int k = 0; k < 4; ++k) {
                nodeLo[t] = std::min(nodeLo[t], tetNodes[4 * e + k]);
                nodeHi[t] = std::max(nodeHi[t], tetNodes[4 * e + k]);
            }
        if (nodeHi[t] < nodeLo[t]) nodeLo[t] = 0, nodeHi[t] = -1;  // empty chunk
        buffers[t].assign(3 * static_cast<std::size_t>(nodeHi[t] - nodeLo[t] + 1), 0.0);
    }
}

}  // namespace qdem
