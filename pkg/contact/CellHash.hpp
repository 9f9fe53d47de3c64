// Integer cell coordinates and a table of the occupied cells, shared by the
// cell lists (CellGrid, BoxGrid).  The table holds each occupied cell once
// (open addressing, sized to the entry count, so memory does not depend on
// how far apart the pieces are) with the range of its entries in one packed
// array: a query reads a cell's entries as one contiguous run instead of
// walking a linked chain, and never meets another cell's entries.  The
// packing is a counting sort by cell; within a cell the entries are in
// descending entry order (the order the former linked chains, filled by
// pushing at the head, were walked in), so queries visit the same entries in
// the same order as before.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace qdem {

class CellTable {
public:
    // A table for up to `entries` entries in cells of side cellSize (at least
    // twice as many slots as entries: short probes).  No allocation once
    // grown to the largest count seen.
    void reset(double cellSize, std::size_t entries) {
        inv_ = 1.0 / cellSize;
        std::size_t size = 64;
        while (size < 2 * entries) size *= 2;
        mask_ = size - 1;
        begin_.assign(size, -1);
        end_.resize(size);
        key_.resize(3 * size);
        cellOf_.resize(entries);
    }
    int64_t coord(double v) const { return static_cast<int64_t>(std::floor(v * inv_)); }
    void setCellSize(double cellSize) { inv_ = 1.0 / cellSize; }

    // Counting sort, step 1: entry e lies in cell (x, y, z).  Entries are
    // noted in increasing order e = 0, 1, ...
    void note(int32_t e, int64_t x, int64_t y, int64_t z) {
        std::size_t s = hash(x, y, z);
        while (begin_[s] >= 0 && !same(s, x, y, z)) s = (s + 1) & mask_;
        if (begin_[s] < 0) {
            begin_[s] = 0, end_[s] = 0;  // counts until pack()
            key_[3 * s] = x, key_[3 * s + 1] = y, key_[3 * s + 2] = z;
        }
        ++end_[s];
        cellOf_[e] = static_cast<int32_t>(s);
    }
    // Step 2: cell ranges from the counts; then place(e) for e = n-1 down to 0
    // returns each entry's packed position (descending order within a cell).
    void pack() {
        int32_t off = 0;
        for (std::size_t s = 0; s <= mask_; ++s) {
            if (begin_[s] < 0) continue;
            const int32_t n = end_[s];
            begin_[s] = off, end_[s] = off;  // end_ is the fill pointer until all are placed
            off += n;
        }
    }
    int32_t place(int32_t e) { return end_[cellOf_[e]]++; }

    // The packed range [b, e) of cell (x, y, z); false when the cell is empty.
    bool find(int64_t x, int64_t y, int64_t z, int32_t& b, int32_t& e) const {
        for (std::size_t s = hash(x, y, z);; s = (s + 1) & mask_) {
            if (begin_[s] < 0) return false;
            if (same(s, x, y, z)) {
                b = begin_[s], e = end_[s];
                return true;
            }
        }
    }

private:
    bool same(std::size_t s, int64_t x, int64_t y, int64_t z) const {
        return key_[3 * s] == x && key_[3 * s + 1] == y && key_[3 * s + 2] == z;
    }
    std::size_t hash(int64_t x, int64_t y, int64_t z) const {
        uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                     static_cast<uint64_t>(z) * 0x165667B19E3779F9ull;
        h ^= h >> 32;
        h *= 0xD6E8FEB86659FD93ull;
        h ^= h >> 29;
        return static_cast<std::size_t>(h) & mask_;
    }

    double inv_ = 1;        // 1 / cell size
    std::size_t mask_ = 0;  // table size - 1 (a power of two)
    std::vector<int32_t> begin_, end_;  // per slot: packed range (begin -1: empty slot)
    std::vector<int64_t> key_;          // per slot: the cell's coordinates (3)
    std::vector<int32_t> cellOf_;       // per entry: its cell's slot (while building)
};

}  // namespace qdem
