// The rotation Rz Ry Rx of a Placement; see placement.hpp.
#include "geometry/placement.hpp"

#include <cmath>
#include <numbers>

namespace turbid::geometry {

PlacementMap::PlacementMap(const Placement& pl) : t_(pl.translation), scale_(pl.scale) {
  const double d2r = std::numbers::pi / 180.0;
  const double cx = std::cos(pl.rotation_deg[0] * d2r), sx = std::sin(pl.rotation_deg[0] * d2r);
  const double cy = std::cos(pl.rotation_deg[1] * d2r), sy = std::sin(pl.rotation_deg[1] * d2r);
  const double cz = std::cos(pl.rotation_deg[2] * d2r), sz = std::sin(pl.rotation_deg[2] * d2r);
  // Rz * Ry * Rx, row-major.
  const double m[3][3] = {
      {cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx},
      {sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx},
      {-sy, cy * sx, cy * cx},
  };
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m_[i][j] = m[i][j];
}

Point PlacementMap::rotate(const Point& v) const {
  return {m_[0][0] * v[0] + m_[0][1] * v[1] + m_[0][2] * v[2], m_[1][0] * v[0] + m_[1][1] * v[1] + m_[1][2] * v[2],
          m_[2][0] * v[0] + m_[2][1] * v[1] + m_[2][2] * v[2]};
}

Point PlacementMap::move(const Point& p) const {
  const Point r = rotate(p);
  return {r[0] + t_[0], r[1] + t_[1], r[2] + t_[2]};
}

Point PlacementMap::rotate_back(const Point& v) const {
  return {m_[0][0] * v[0] + m_[1][0] * v[1] + m_[2][0] * v[2], m_[0][1] * v[0] + m_[1][1] * v[1] + m_[2][1] * v[2],
          m_[0][2] * v[0] + m_[1][2] * v[1] + m_[2][2] * v[2]};
}

Point PlacementMap::move_back(const Point& p) const { return rotate_back({p[0] - t_[0], p[1] - t_[1], p[2] - t_[2]}); }

Point PlacementMap::apply(const Point& p) const { return move({scale_ * p[0], scale_ * p[1], scale_ * p[2]}); }

}  // namespace turbid::geometry
