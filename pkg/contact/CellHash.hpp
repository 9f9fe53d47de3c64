// Integer cell coordinates, a table of the occupied cells and the binning of
// entries by cell (CellBins), shared by the cell lists (CellGrid, BoxGrid).  The table holds each occupied cell once
// (open addressing, sized to the entry count, so memory does not depend on
// how far apart the pieces are) with the range of its entries in one packed
// array: a query reads a cell's entries as one contiguous run instead of
// walking a linked chain, and never meets another cell's entries.  The
// packing is a counting sort by cell; within a cell the entries are in
// descending entry order (the order the former linked chains, filled by
// pushing at the head, were walked in), so queries visit the same entries in
// the same order as before.
#pragma once
#include <algorithm>
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

// Entries binned by cell, packed cell by cell (a counting sort), indexed
// either as a dense block of cells or, when the occupied cells' block would
// hold more than 4 n + 64 cells (pieces far apart, long thin ones), through a
// CellTable.  Dense: cell offsets in x-y-z order, so the z cells of one
// (x, y) column are one contiguous run of slots.  Within a cell the entries
// are in descending entry order.
class CellBins {
public:
    void setCellSize(double cellSize) { t_.setCellSize(cellSize); }
    int64_t coord(double v) const { return t_.coord(v); }
    bool dense() const { return dense_; }  // which indexing the last build chose

    // n entries in cells (3 per entry); put(slot, e) is called once per entry,
    // slots of one cell in descending e.
    template <class Put>
    void build(const int64_t* cells, int32_t n, double cellSize, Put&& put) {
        int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
        for (int32_t i = 0; i < n; ++i)
            for (int d = 0; d < 3; ++d) {
                const int64_t c = cells[3 * i + d];
                lo[d] = i == 0 ? c : std::min(lo[d], c), hi[d] = i == 0 ? c : std::max(hi[d], c);
            }
        // Dense when the block is small (each extent checked first: no overflow).
        const int64_t limit = 4 * static_cast<int64_t>(n) + 64;
        dense_ = true;
        int64_t count = 1;
        for (int d = 0; d < 3; ++d) {
            const int64_t e = hi[d] - lo[d] + 1;
            dense_ = dense_ && e >= 0 && e <= limit;
            if (dense_) count *= e;
            dense_ = dense_ && count <= limit;
            lo_[d] = lo[d], dim_[d] = e;
        }
        if (dense_) {
            start_.assign(static_cast<std::size_t>(count) + 1, 0);
            for (int32_t i = 0; i < n; ++i) ++start_[denseIndex(&cells[3 * i]) + 1];
            for (std::size_t c = 0; c + 1 < start_.size(); ++c) start_[c + 1] += start_[c];
            fill_.assign(start_.begin() + 1, start_.end());  // each cell filled from its end: e = 0 last
            for (int32_t i = 0; i < n; ++i) put(--fill_[denseIndex(&cells[3 * i])], i);
        } else {
            t_.reset(cellSize, static_cast<std::size_t>(n));
            for (int32_t i = 0; i < n; ++i) t_.note(i, cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]);
            t_.pack();
            for (int32_t i = n - 1; i >= 0; --i) put(t_.place(i), i);
        }
    }

    // f(x, y, z, b, e) for each non-empty cell of the block [a, b] (cell
    // coordinates, x-y-z order): its slots [b, e).
    template <class F>
    void forCells(const int64_t* a, const int64_t* b, F&& f) const {
        if (dense_) {
            forDenseColumns(a, b, [&](int64_t i, int64_t j, const int32_t* s, int64_t z0, int64_t z1) {
                for (int64_t k = z0; k <= z1; ++k)
                    if (s[k] < s[k + 1]) f(i + lo_[0], j + lo_[1], k + lo_[2], s[k], s[k + 1]);
            });
            return;
        }
        for (int64_t i = a[0]; i <= b[0]; ++i)
            for (int64_t j = a[1]; j <= b[1]; ++j)
                for (int64_t k = a[2]; k <= b[2]; ++k) {
                    int32_t s0, s1;
                    if (t_.find(i, j, k, s0, s1)) f(i, j, k, s0, s1);
                }
    }

    // f(b, e) for runs of slots that together hold, in the same order, the
    // entries of the cells of the block [a, b]: one run per (x, y) column
    // when dense.
    template <class F>
    void forRuns(const int64_t* a, const int64_t* b, F&& f) const {
        if (dense_) {
            forDenseColumns(a, b, [&](int64_t, int64_t, const int32_t* s, int64_t z0, int64_t z1) {
                if (s[z0] < s[z1 + 1]) f(s[z0], s[z1 + 1]);
            });
            return;
        }
        forCells(a, b, [&](int64_t, int64_t, int64_t, int32_t s0, int32_t s1) { f(s0, s1); });
    }

private:
    std::size_t denseIndex(const int64_t* c) const {
        return static_cast<std::size_t>(((c[0] - lo_[0]) * dim_[1] + (c[1] - lo_[1])) * dim_[2] + (c[2] - lo_[2]));
    }
    // The block [a, b] within the dense one, relative to its lowest cell.
    bool clip(const int64_t* a, const int64_t* b, int64_t* u, int64_t* v) const {
        for (int d = 0; d < 3; ++d) {
            u[d] = std::max(a[d], lo_[d]) - lo_[d], v[d] = std::min(b[d], lo_[d] + dim_[d] - 1) - lo_[d];
            if (u[d] > v[d]) return false;
        }
        return true;
    }
    // f(i, j, s, z0, z1) for each (x, y) column of the dense block within
    // [a, b] (coordinates relative to its lowest cell, x then y): s the
    // column's first slots along z, [z0, z1] the z range within [a, b].
    template <class F>
    void forDenseColumns(const int64_t* a, const int64_t* b, F&& f) const {
        int64_t u[3], v[3];
        if (!clip(a, b, u, v)) return;
        for (int64_t i = u[0]; i <= v[0]; ++i)
            for (int64_t j = u[1]; j <= v[1]; ++j)
                f(i, j, &start_[static_cast<std::size_t>((i * dim_[1] + j) * dim_[2])], u[2], v[2]);
    }

    CellTable t_;
    bool dense_ = true;
    int64_t lo_[3] = {0, 0, 0}, dim_[3] = {0, 0, 0};  // dense block: lowest cell and extent
    std::vector<int32_t> start_, fill_;              // dense block: first slot of each cell (+ end)
};

}  // namespace qdem
