// A graded element-size field sampled on a regular background grid: the
// size asked for near some places (a thin part's faces), growing away from
// them by `gradation` per unit length, capped everywhere.
//
//   size(p) = min(cap, min over seeds q of (size_q + gradation |p - q|))
//
// computed once by two raster sweeps of a 26-neighbour chamfer transform
// (the chamfer length is within 8 % of the Euclidean one), then read by
// trilinear interpolation in O(1).  Mesh_3 asks for the size at every
// refinement test; a lookup of the closest input face in an AABB tree of a
// scan's 80,000 triangles took half of the meshing time.  The grading keeps
// neighbouring elements within a bounded size ratio where the thin part
// meets the body, instead of a jump from one input face to the next.
#pragma once
#include <array>
#include <cstddef>
#include <vector>

namespace qdem {

class SizeGrid {
public:
    // The box [lo, hi] (widened by one spacing on each side) at a spacing of
    // at least `spacing`, coarser if the grid would exceed maxNodes nodes.
    SizeGrid(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double spacing, double cap,
             std::size_t maxNodes = 4000000);

    double spacing() const { return h_; }
    double cap() const { return cap_; }
    bool empty() const { return !seeded_; }
    // Grid node (i, j, k)'s position and its current value.
    std::array<double, 3> node(std::size_t i, std::size_t j, std::size_t k) const;
    std::array<std::size_t, 3> dims() const { return n_; }
    // The node index range whose positions lie within [lo, hi] widened by pad.
    void range(const std::array<double, 3>& lo, const std::array<double, 3>& hi, double pad,
               std::array<std::size_t, 3>& first, std::array<std::size_t, 3>& last) const;
    // Lowers node (i, j, k) to at most `size`.
    void lower(std::size_t i, std::size_t j, std::size_t k, double size);
    // Spreads the values set by lower() with the given gradation (size per length).
    void grade(double gradation);
    // The field at p (points outside the grid take the nearest grid point).
    double at(double x, double y, double z) const;

private:
    std::size_t index(std::size_t i, std::size_t j, std::size_t k) const { return (i * n_[1] + j) * n_[2] + k; }
    std::array<double, 3> lo_{};
    std::array<std::size_t, 3> n_{};
    double h_ = 0, cap_ = 0;
    bool seeded_ = false;
    std::vector<float> v_;
};

}  // namespace qdem
