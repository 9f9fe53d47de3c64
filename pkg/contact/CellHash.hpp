// Integer cell coordinates and their hash, shared by the cell lists
// (CellGrid, BoxGrid): cells live in a hash table sized to the item count, so
// memory does not depend on how far apart the pieces are.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace qdem {

struct CellHash {
    double inv = 1;        // 1 / cell size
    std::size_t mask = 0;  // table size - 1 (a power of two)

    // Table of at least twice `entries` buckets, cells of side cellSize.
    std::size_t reset(double cellSize, std::size_t entries) {
        inv = 1.0 / cellSize;
        std::size_t size = 64;
        while (size < 2 * entries) size *= 2;
        mask = size - 1;
        return size;
    }
    int64_t coord(double v) const { return static_cast<int64_t>(std::floor(v * inv)); }
    std::size_t operator()(int64_t x, int64_t y, int64_t z) const {
        const uint64_t h = static_cast<uint64_t>(x) * 73856093u ^ static_cast<uint64_t>(y) * 19349663u ^
                           static_cast<uint64_t>(z) * 83492791u;
        return static_cast<std::size_t>(h ^ (h >> 29)) & mask;
    }
};

}  // namespace qdem
