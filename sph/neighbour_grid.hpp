// Cell grid for neighbour search: particles are sorted by the index of their cell (cells of the
// kernel support 2 h_max, x fastest), so that the neighbours of a particle lie in 3 (2D) or 9 (3D)
// contiguous index ranges. The same layout is built by the CPU (counting sort) and CUDA (CUB radix
// sort) backends; the view below is what the physics passes read.
#pragma once
#include <cstdint>

#include "sph/config.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

template <int D>
struct GridView {
  Real origin[D];     // lower corner of cell (0, 0[, 0]) [m]
  Real inv_cell;      // 1 / cell size [1/m]
  int cells[D];       // number of cells per axis
  const std::uint32_t* cell_start;  // size cell_count + 1: particles of cell c are [start[c], start[c+1])
  // Optional (CPU): fluid particles in cells [0, c) for each c (size cell_count + 1), so that a wall
  // particle can see at once that no fluid is near it.
  const std::uint32_t* fluid_before = nullptr;

  TURBID_HD int cell_count() const {
    int n = 1;
    for (int k = 0; k < D; ++k) n *= cells[k];
    return n;
  }
  // Cell coordinates of a point; false if it lies outside the grid (or is NaN).
  TURBID_HD bool cell_of(const Vec<D>& x, int* c) const {
    for (int k = 0; k < D; ++k) {
      const Real f = (x[k] - origin[k]) * inv_cell;
      if (!(f >= Real(0) && f < Real(cells[k]))) return false;
      c[k] = int(f);
    }
    return true;
  }
  TURBID_HD std::uint32_t linear(const int* c) const {
    std::uint32_t idx = std::uint32_t(c[D - 1]);
    for (int k = D - 2; k >= 0; --k) idx = idx * std::uint32_t(cells[k]) + std::uint32_t(c[k]);
    return idx;
  }
  // True if a fluid particle may be in the cells around cell c (always true without fluid_before).
  TURBID_HD bool fluid_near(const int* c) const {
    if (!fluid_before) return true;
    bool any = false;
    for_each_cell_range(c, [&](std::uint32_t c0, std::uint32_t c1) { any = any || fluid_before[c1] > fluid_before[c0]; });
    return any;
  }
  // Calls f(begin, end) for every contiguous range of particles in the cells around cell c.
  template <class F>
  TURBID_HD void for_each_neighbour_range(const int* c, F&& f) const {
    for_each_cell_range(c, [&](std::uint32_t c0, std::uint32_t c1) { f(cell_start[c0], cell_start[c1]); });
  }
  // Calls f(first cell, last cell + 1) for every row of 3 cells around cell c (x fastest).
  template <class F>
  TURBID_HD void for_each_cell_range(const int* c, F&& f) const {
    const int x0 = c[0] > 0 ? c[0] - 1 : 0;
    const int x1 = c[0] + 1 < cells[0] ? c[0] + 1 : cells[0] - 1;
    if constexpr (D == 2) {
      for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
        if (y < 0 || y >= cells[1]) continue;
        const std::uint32_t row = std::uint32_t(y) * std::uint32_t(cells[0]);
        f(row + std::uint32_t(x0), row + std::uint32_t(x1) + 1);
      }
    } else {
      for (int z = c[2] - 1; z <= c[2] + 1; ++z) {
        if (z < 0 || z >= cells[2]) continue;
        for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
          if (y < 0 || y >= cells[1]) continue;
          const std::uint32_t row = (std::uint32_t(z) * std::uint32_t(cells[1]) + std::uint32_t(y)) * std::uint32_t(cells[0]);
          f(row + std::uint32_t(x0), row + std::uint32_t(x1) + 1);
        }
      }
    }
  }
};

}  // namespace turbid::sph
