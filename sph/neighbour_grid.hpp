// Cell grid for neighbour search: particles are sorted by the index of their cell (cells of the
// kernel support 2 h_max, x fastest), so that the neighbours of a particle lie in 3 (2D) or 9 (3D)
// contiguous index ranges. The same layout is built by the CPU (counting sort) and CUDA (CUB radix
// sort) backends; the view below is what the physics passes read.
//
// Periodic axes: the cells tile the period exactly (cell size period / floor(period / 2 h_max),
// at least 3 cells), and the neighbour cells of an edge cell wrap around to the other side. Each
// range comes with the image offset to add to its particles' positions, so that x_i - (x_j + offset)
// is the pair vector to the nearest image.
#pragma once
#include <cstdint>

#include "sph/config.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

template <int D>
struct GridView {
  Real origin[D];     // lower corner of cell (0, 0[, 0]) [m]
  Real inv_cell[D];   // 1 / cell size per axis [1/m]
  int cells[D];       // number of cells per axis
  Real period[D];     // length of a periodic axis [m]; 0: not periodic
  bool periodic = false;  // some axis is periodic
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
      const Real f = (x[k] - origin[k]) * inv_cell[k];
      if (!(f >= Real(0) && f < Real(cells[k]))) {
        // A wrapped coordinate may round onto a face of a periodic axis: the edge cell.
        if (period[k] == Real(0) || !(f >= Real(-1e-3) && f <= Real(cells[k]))) return false;
        c[k] = f < Real(0) ? 0 : cells[k] - 1;
        continue;
      }
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
    for_each_cell_range(c, [&](std::uint32_t c0, std::uint32_t c1, const Vec<D>&) {
      any = any || fluid_before[c1] > fluid_before[c0];
    });
    return any;
  }
  // True if a particle other than fluid (wall, structure, buffer) may be in the cells around cell c
  // (always true without fluid_before): cells [0, c) hold cell_start[c] - fluid_before[c] of them.
  TURBID_HD bool boundary_near(const int* c) const {
    if (!fluid_before) return true;
    bool any = false;
    for_each_cell_range(c, [&](std::uint32_t c0, std::uint32_t c1, const Vec<D>&) {
      any = any || cell_start[c1] - fluid_before[c1] > cell_start[c0] - fluid_before[c0];
    });
    return any;
  }
  // Calls f(begin, end, offset) for every contiguous range of particles in the cells around cell
  // c; offset is the image shift of those particles (zero unless the range wraps a periodic axis).
  template <class F>
  TURBID_HD TURBID_INLINE void for_each_neighbour_range(const int* c, F&& f) const {
    for_each_cell_range(c, [&](std::uint32_t c0, std::uint32_t c1, const Vec<D>& offset) {
      f(cell_start[c0], cell_start[c1], offset);
    });
  }
  // Calls f(first cell, last cell + 1, offset) for every run of cells in the rows of 3 cells
  // around cell c (x fastest); a row that wraps a periodic x axis gives two runs.
  template <class F>
  TURBID_HD TURBID_INLINE void for_each_cell_range(const int* c, F&& f) const {
    Vec<D> offset = Vec<D>::zero();
    if (!periodic) {
      // The common case: rows clipped at the grid's faces, no image offsets.
      const int x0 = c[0] > 0 ? c[0] - 1 : 0;
      const int x1 = c[0] + 1 < cells[0] ? c[0] + 1 : cells[0] - 1;
      if constexpr (D == 2) {
        for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
          if (y < 0 || y >= cells[1]) continue;
          const std::uint32_t row = std::uint32_t(y) * std::uint32_t(cells[0]);
          f(row + std::uint32_t(x0), row + std::uint32_t(x1) + 1, offset);
        }
      } else {
        for (int z = c[2] - 1; z <= c[2] + 1; ++z) {
          if (z < 0 || z >= cells[2]) continue;
          for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
            if (y < 0 || y >= cells[1]) continue;
            const std::uint32_t row =
                (std::uint32_t(z) * std::uint32_t(cells[1]) + std::uint32_t(y)) * std::uint32_t(cells[0]);
            f(row + std::uint32_t(x0), row + std::uint32_t(x1) + 1, offset);
          }
        }
      }
      return;
    }
    if constexpr (D == 2) {
      for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
        int yy = y;
        if (!wrap(1, yy, offset[1])) continue;
        row_runs(c[0], std::uint32_t(yy) * std::uint32_t(cells[0]), offset, f);
      }
    } else {
      for (int z = c[2] - 1; z <= c[2] + 1; ++z) {
        int zz = z;
        if (!wrap(2, zz, offset[2])) continue;
        for (int y = c[1] - 1; y <= c[1] + 1; ++y) {
          int yy = y;
          if (!wrap(1, yy, offset[1])) continue;
          row_runs(c[0], (std::uint32_t(zz) * std::uint32_t(cells[1]) + std::uint32_t(yy)) * std::uint32_t(cells[0]),
                   offset, f);
        }
      }
    }
  }

 private:
  // Maps a neighbour cell coordinate onto the grid: false if it is off a non-periodic axis; on a
  // periodic one it wraps, and `offset` gets the image shift of its particles.
  TURBID_HD TURBID_INLINE bool wrap(int axis, int& k, Real& offset) const {
    offset = Real(0);
    if (k >= 0 && k < cells[axis]) return true;
    if (period[axis] == Real(0)) return false;
    if (k < 0) {
      k += cells[axis];
      offset = -period[axis];
    } else {
      k -= cells[axis];
      offset = period[axis];
    }
    return true;
  }
  template <class F>
  TURBID_HD TURBID_INLINE void row_runs(int cx, std::uint32_t row, Vec<D> offset, F& f) const {
    const int n = cells[0];
    if (period[0] == Real(0) || (cx > 0 && cx + 1 < n)) {
      const int x0 = cx > 0 ? cx - 1 : 0;
      const int x1 = cx + 1 < n ? cx + 1 : n - 1;
      offset[0] = Real(0);
      f(row + std::uint32_t(x0), row + std::uint32_t(x1) + 1, offset);
      return;
    }
    // Periodic x at an edge cell (n >= 3): the cells on the grid, then the wrapped one.
    offset[0] = Real(0);
    if (cx == 0) {
      f(row, row + 2, offset);
      offset[0] = -period[0];
      f(row + std::uint32_t(n - 1), row + std::uint32_t(n), offset);
    } else {
      offset[0] = period[0];
      f(row, row + 1, offset);
      offset[0] = Real(0);
      f(row + std::uint32_t(n - 2), row + std::uint32_t(n), offset);
    }
  }
};

}  // namespace turbid::sph
