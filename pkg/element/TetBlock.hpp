// A block of kLanes tetrahedra in lane-major form: what the element kernel
// reads of the reference data, laid out so that one vector load fetches one
// quantity for all lanes.
//
// Why a copy of tetB / tetVol0 / tetNodes: read per tet, those arrays are
// 9 + 1 doubles and 4 ints at a tet stride, and the kernel had to copy them
// into lane arrays every step (about a third of the element phase's stores).
// The element phase keeps blocks of its threads' shares instead, rebuilt with
// its thread layout (ElementPhase.cpp); lanes past the end of a segment repeat
// its last tet and their forces are dropped.
#pragma once
#include <cstddef>
#include <cstdint>
#include "../core/Aligned.hpp"

namespace qdem {

constexpr int kLanes = 8;

struct alignas(64) TetBlock {
    double B[9][kLanes];       // inverse reference edge matrix, row-major entries
    double vol[kLanes];        // reference volume
    int32_t node[4][kLanes];   // corner node ids
};
static_assert(sizeof(TetBlock) % 64 == 0, "blocks stay cache-line aligned in an array");

// Fills b with tets e0 .. e0+count-1 (1 <= count <= kLanes) of the world
// arrays; the remaining lanes repeat the last tet.
inline void fillTetBlock(TetBlock& b, int32_t e0, int count, const int32_t* conn, const double* Bs,
                         const double* vol) {
    for (int l = 0; l < kLanes; ++l) {
        const int32_t e = e0 + (l < count ? l : count - 1);
        for (int m = 0; m < 9; ++m) b.B[m][l] = Bs[9 * e + m];
        b.vol[l] = vol[e];
        for (int k = 0; k < 4; ++k) b.node[k][l] = conn[4 * e + k];
    }
}


}  // namespace qdem
