#include "fsi/wall_penetration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "sph/physics_params.hpp"

namespace turbid::fsi {

namespace {

using Key = std::array<long long, 3>;

Key cell_of(const float* x, int d, double size) {
  Key c{0, 0, 0};
  for (int k = 0; k < d; ++k) c[std::size_t(k)] = static_cast<long long>(std::floor(double(x[k]) / size));
  return c;
}

}  // namespace

FluidBehindWalls count_fluid_behind_walls(const PenetrationInput& in) {
  FluidBehindWalls out;
  const int d = in.dimensions;
  if (in.size == 0 || !in.ghost0 || !(in.radius > 0)) return out;
  const auto is_boundary = [&](std::size_t i) {
    return in.kind[i] == std::uint8_t(sph::Kind::wall) || in.kind[i] == std::uint8_t(sph::Kind::structure);
  };
  // Boundary particles sorted by cell (cells of the search radius): a fluid particle looks in the
  // 3^d cells around its own.
  std::vector<std::pair<Key, std::uint32_t>> cells;
  for (std::size_t i = 0; i < in.size; ++i)
    if (is_boundary(i)) cells.push_back({cell_of(in.position + i * std::size_t(d), d, in.radius), std::uint32_t(i)});
  if (cells.empty()) return out;
  std::sort(cells.begin(), cells.end());
  const double r2max = in.radius * in.radius;
  const auto surface_distance = [&](const float* xi, std::uint32_t b) -> double {
    const std::uint32_t slot = in.id[b] - in.first_id;
    if (in.id[b] < in.first_id || slot >= in.ghost0->size()) return std::numeric_limits<double>::quiet_NaN();
    const auto& g0 = (*in.ghost0)[slot];
    double g[3] = {g0[0], g0[1], g0[2]};
    if (in.kind[b] == std::uint8_t(sph::Kind::structure) && in.body && in.body[b] < in.rotation.size()) {
      const auto& R = in.rotation[in.body[b]];
      for (int a = 0; a < 3; ++a)
        g[a] = R[std::size_t(3 * a)] * g0[0] + R[std::size_t(3 * a + 1)] * g0[1] + R[std::size_t(3 * a + 2)] * g0[2];
    }
    double len2 = 0;
    for (int k = 0; k < d; ++k) len2 += g[k] * g[k];
    if (!(len2 > 0)) return std::numeric_limits<double>::quiet_NaN();
    const double len = std::sqrt(len2);
    const float* xb = in.position + std::size_t(b) * std::size_t(d);
    double s = 0;
    for (int k = 0; k < d; ++k) s += (double(xi[k]) - double(xb[k]) - 0.5 * g[k]) * g[k] / len;
    return s;
  };
  std::vector<std::pair<double, std::uint32_t>> near;  // (r^2, boundary particle) within the radius
  std::vector<std::uint32_t> behind;                    // of those, the ones whose surface it is behind
  for (std::size_t i = 0; i < in.size; ++i) {
    if (in.kind[i] != std::uint8_t(sph::Kind::fluid)) continue;
    const float* xi = in.position + i * std::size_t(d);
    const Key c = cell_of(xi, d, in.radius);
    near.clear();
    double best = r2max;
    Key n{0, 0, 0};
    const int zr = d == 3 ? 1 : 0;
    for (n[0] = c[0] - 1; n[0] <= c[0] + 1; ++n[0])
      for (n[1] = c[1] - 1; n[1] <= c[1] + 1; ++n[1])
        for (n[2] = c[2] - zr; n[2] <= c[2] + zr; ++n[2]) {
          auto it = std::lower_bound(cells.begin(), cells.end(), std::pair<Key, std::uint32_t>{n, 0});
          for (; it != cells.end() && it->first == n; ++it) {
            const float* xb = in.position + std::size_t(it->second) * std::size_t(d);
            double r2 = 0;
            for (int k = 0; k < d; ++k) r2 += (double(xi[k]) - xb[k]) * (double(xi[k]) - xb[k]);
            if (r2 >= r2max) continue;
            near.push_back({r2, it->second});
            best = std::min(best, r2);
          }
        }
    if (near.empty() || (in.inside > 0 && best > in.inside * in.inside)) continue;
    // The rule of sph::WallConstraintPass (its comment): behind some surface within `band` of the
    // nearest, and not in front of a surface that meets all of those at a convex edge.
    const double reach = std::sqrt(best) + in.band;
    const auto within = [&](double r2) { return r2 <= best || r2 <= reach * reach; };
    double s_max = -std::numeric_limits<double>::infinity();
    std::uint32_t deciding = near.front().second;
    behind.clear();
    for (const auto& [r2, b] : near) {
      if (!within(r2)) continue;
      const double s = surface_distance(xi, b);
      if (std::isnan(s) || s >= 0) continue;
      if (behind.empty() || s > s_max) s_max = s, deciding = b;
      behind.push_back(b);
    }
    if (behind.empty()) continue;
    bool outside = false;
    for (const auto& [r2, b] : near) {
      if (outside || !within(r2)) continue;
      const double s = surface_distance(xi, b);
      if (std::isnan(s) || s < 0) continue;
      // A convex edge: every surface the particle is behind lies behind the plane of b, by more
      // than band / 2 (dx/4; the pass's margin, which tells a tank's diagonal edge plane through
      // the next floor particle from a convex edge).
      outside = std::all_of(behind.begin(), behind.end(), [&](std::uint32_t e) {
        return surface_distance(in.position + std::size_t(e) * std::size_t(d), b) < -0.5 * in.band;
      });
    }
    if (outside) continue;
    if (s_max < -in.tolerance) {
      ++out.count;
      out.deepest = std::max(out.deepest, -s_max);
      if (in.kind[deciding] == std::uint8_t(sph::Kind::structure))
        ++out.inside_structures;
      else
        ++out.below_walls;
    }
  }
  return out;
}

}  // namespace turbid::fsi
