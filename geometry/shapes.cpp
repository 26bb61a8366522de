// Lattice sampling of boxes, tank walls and 2D polylines, and extrusion across y; see shapes.hpp.
#include "geometry/shapes.hpp"

#include <cmath>
#include <stdexcept>

namespace turbid::geometry {

namespace {

int cells_along(double length, double dx) {
  return std::max(1, int(std::floor(length / dx + 0.5)));
}

}  // namespace

Aabb lattice_box(const Aabb& box, double dx, int dims) {
  Aabb out = box;
  for (int k = 0; k < dims; ++k) out.max[k] = box.min[k] + cells_along(box.max[k] - box.min[k], dx) * dx;
  return out;
}

std::vector<Point> fill_box(const Aabb& box, double dx, int dims) {
  if (!(dx > 0)) throw std::invalid_argument("fill_box: spacing must be positive");
  int n[3] = {1, 1, 1};
  for (int k = 0; k < dims; ++k) n[k] = cells_along(box.max[k] - box.min[k], dx);
  std::vector<Point> pts;
  pts.reserve(std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]));
  for (int iz = 0; iz < n[2]; ++iz)
    for (int iy = 0; iy < n[1]; ++iy)
      for (int ix = 0; ix < n[0]; ++ix) {
        Point p{box.min[0] + (ix + 0.5) * dx, box.min[1] + (iy + 0.5) * dx, 0.0};
        if (dims == 3) p[2] = box.min[2] + (iz + 0.5) * dx;
        pts.push_back(p);
      }
  return pts;
}

std::vector<Point> box_shell(const Aabb& box, double dx, int dims, int layers) {
  if (layers <= 0) return fill_box(box, dx, dims);
  int n[3] = {1, 1, 1};
  for (int k = 0; k < dims; ++k) n[k] = cells_along(box.max[k] - box.min[k], dx);
  std::vector<Point> pts;
  for (const auto& p : fill_box(box, dx, dims)) {
    bool near_surface = false;
    for (int k = 0; k < dims; ++k) {
      const int i = int(std::floor((p[k] - box.min[k]) / dx));
      near_surface = near_surface || i < layers || i >= n[k] - layers;
    }
    if (near_surface) pts.push_back(p);
  }
  return pts;
}

std::vector<Point> container_walls(const Aabb& box, double dx, int dims, int layers,
                                   const std::array<bool, 6>& open) {
  if (!(dx > 0)) throw std::invalid_argument("container_walls: spacing must be positive");
  int n[3] = {1, 1, 1};
  int lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  // index range, inclusive
  for (int k = 0; k < 3; ++k) {
    if (k < dims) {
      n[k] = cells_along(box.max[k] - box.min[k], dx);
      lo[k] = open[2 * k] ? 0 : -layers;
      hi[k] = open[2 * k + 1] ? n[k] - 1 : n[k] - 1 + layers;
    }
  }
  std::vector<Point> pts;
  for (int iz = lo[2]; iz <= hi[2]; ++iz)
    for (int iy = lo[1]; iy <= hi[1]; ++iy)
      for (int ix = lo[0]; ix <= hi[0]; ++ix) {
        const int idx[3] = {ix, iy, iz};
        bool inside = true;
        for (int k = 0; k < dims; ++k) inside = inside && idx[k] >= 0 && idx[k] < n[k];
        if (inside) continue;
        Point p{box.min[0] + (ix + 0.5) * dx, box.min[1] + (iy + 0.5) * dx, 0.0};
        if (dims == 3) p[2] = box.min[2] + (iz + 0.5) * dx;
        pts.push_back(p);
      }
  return pts;
}

std::vector<Point> polyline_walls(const std::vector<Point>& v, bool closed, double dx, int layers, int side) {
  if (v.size() < 2) throw std::invalid_argument("polyline_walls: need at least two points");
  std::vector<Point> pts;
  const std::size_t segments = closed ? v.size() : v.size() - 1;
  for (std::size_t s = 0; s < segments; ++s) {
    const Point& a = v[s];
    const Point& b = v[(s + 1) % v.size()];
    const double ex = b[0] - a[0], ey = b[1] - a[1];
    const double len = std::hypot(ex, ey);
    if (len <= 0) continue;
    const double tx = ex / len, ty = ey / len;
    // right of travel: (ty, -tx); left: (-ty, tx)
    const double nx = side < 0 ? ty : -ty, ny = side < 0 ? -tx : tx;
    const int m = cells_along(len, dx);
    for (int l = 0; l < layers; ++l)
      for (int i = 0; i < m; ++i) {
        const double t = (i + 0.5) * len / m;
        const double off = (l + 0.5) * dx;
        pts.push_back({a[0] + t * tx + off * nx, a[1] + t * ty + off * ny, 0.0});
      }
  }
  return pts;
}

std::vector<Point> extrude_across_y(const std::vector<Point>& section, double y_min, double y_max, double dx) {
  if (!(dx > 0)) throw std::invalid_argument("extrude_across_y: spacing must be positive");
  if (!(y_max > y_min)) throw std::invalid_argument("extrude_across_y: the span needs y_min < y_max");
  const int n = cells_along(y_max - y_min, dx);
  std::vector<Point> pts;
  pts.reserve(section.size() * std::size_t(n));
  for (int k = 0; k < n; ++k)
    for (const Point& p : section) pts.push_back({p[0], y_min + (k + 0.5) * dx, p[1]});
  return pts;
}

}  // namespace turbid::geometry
