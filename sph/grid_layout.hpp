// The domain of a run and the cell grid laid over it, computed once on the host and shared by
// both backends: where the cells start, their size per axis and, on periodic axes, the period.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "sph/neighbour_grid.hpp"

namespace turbid::sph {

// Particles outside this box are removed at the next neighbour update. On a periodic axis the box
// is one period: particles leaving through one face come back through the other.
struct Domain {
  double min[3] = {0, 0, 0};
  double max[3] = {0, 0, 0};
  bool periodic[3] = {false, false, false};
};

struct GridLayout {
  double origin[3] = {0, 0, 0};
  double inv_cell[3] = {1, 1, 1};
  double period[3] = {0, 0, 0};
  int cells[3] = {1, 1, 1};
  std::size_t cell_count = 1;

  // Cells of at least `cell` [m] (the kernel support); a periodic axis gets a whole number of
  // equal cells over its period, at least 3 so that no cell is its own neighbour twice.
  static GridLayout make(const Domain& domain, int dimensions, double cell) {
    GridLayout g;
    for (int k = 0; k < dimensions; ++k) {
      const double length = domain.max[k] - domain.min[k];
      g.origin[k] = domain.min[k];
      if (domain.periodic[k]) {
        // A whole number of supports is enough: 1e-5 absorbs the float rounding of h (a pair closer
        // than 2h but farther than the cell then lies within 1e-5 of 2h, where the kernel vanishes).
        const int n = int(std::floor(length / cell * (1 + 1e-5)));
        if (n < 3)
          throw std::runtime_error("a periodic axis must be at least 3 kernel supports long (" +
                                   std::to_string(3.0 * cell) + " m), got " + std::to_string(length) + " m");
        g.cells[k] = n;
        g.inv_cell[k] = n / length;
        g.period[k] = length;
      } else {
        g.cells[k] = std::max(1, int(std::ceil(length / cell)));
        g.inv_cell[k] = 1.0 / cell;
      }
      g.cell_count *= std::size_t(g.cells[k]);
    }
    if (g.cell_count > (std::size_t(1) << 31))
      throw std::runtime_error("domain too large for the cell grid; give a smaller domain");
    return g;
  }

  template <int D>
  GridView<D> view(const std::uint32_t* cell_start, const std::uint32_t* fluid_before) const {
    GridView<D> v;
    for (int k = 0; k < D; ++k) {
      v.origin[k] = Real(origin[k]);
      v.inv_cell[k] = Real(inv_cell[k]);
      v.cells[k] = cells[k];
      v.period[k] = Real(period[k]);
      v.periodic = v.periodic || period[k] > 0;
    }
    v.cell_start = cell_start;
    v.fluid_before = fluid_before;
    return v;
  }
};

}  // namespace turbid::sph
