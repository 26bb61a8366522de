// Layered sampling of boxes, spheres/circles and cylinders; see primitives.hpp for the layout and
// the volume formulas.
#include "geometry/primitives.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace turbid::geometry {

namespace {

constexpr double kPi = std::numbers::pi;

// Number of cells of size ~dx along `extent` (at least one).
int cells(double extent, double dx) { return std::max(1, int(std::lround(extent / dx))); }

// Number of shells to keep: layers <= 0 or too many -> all of them.
int kept(int layers, int available) { return layers <= 0 ? available : std::min(layers, available); }

Point unit(Point v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / n, v[1] / n, v[2] / n};
}

void check_common(const char* who, double dx, int dims, const Placement& pl) {
  const std::string w(who);
  if (!(dx > 0) || !std::isfinite(dx)) throw std::invalid_argument(w + ": spacing dx must be positive");
  if (dims != 2 && dims != 3) throw std::invalid_argument(w + ": dims must be 2 or 3");
  if (!(pl.scale > 0) || !std::isfinite(pl.scale))
    throw std::invalid_argument(w + ": placement scale must be positive");
  if (dims == 2 && (pl.rotation_deg[0] != 0 || pl.rotation_deg[1] != 0 || pl.translation[2] != 0))
    throw std::invalid_argument(w + ": in 2D only a rotation about z and an in-plane translation are allowed");
}

void push(SampledBody& b, const Point& p, const Point& n, double depth, double v, int layer, double surface_share) {
  b.points.push_back(p);
  b.normals.push_back(n);
  b.depth.push_back(depth);
  b.volumes.push_back(v);
  b.layer.push_back(layer);
  b.surface_share.push_back(layer == 0 ? surface_share : 0.0);
  b.volume += v;
  if (layer == 0) b.surface_area += surface_share;
}

// p' = Rz Ry Rx p + t for points, Rz Ry Rx n for normals (the dimensions are already scaled).
void place(SampledBody& b, const Placement& pl) {
  const PlacementMap map(pl);
  for (auto& p : b.points) p = map.move(p);
  for (auto& n : b.normals) n = unit(map.rotate(n));
}

// Circle of radius R about the origin in the xy-plane: rings r_k = R - (k + 0.5) h.
SampledBody circle(double R, double dx, int layers) {
  const int K = cells(R, dx);
  const double h = R / K;
  const int keep = kept(layers, K);
  const int N0 = std::max(1, int(std::lround(2 * kPi * (R - 0.5 * h) / h)));
  SampledBody b;
  for (int k = 0; k < keep; ++k) {
    const double ro = R - k * h, ri = ro - h, rk = ro - 0.5 * h;
    const int N = k == 0 ? N0 : std::max(1, int(std::lround(2 * kPi * rk / h)));
    const double v = kPi * (ro * ro - ri * ri) / N;
    const double offset = (k % 2) * kPi / N;  // stagger neighbouring rings
    for (int i = 0; i < N; ++i) {
      const double a = offset + 2 * kPi * i / N;
      const Point n{std::cos(a), std::sin(a), 0.0};
      push(b, {rk * n[0], rk * n[1], 0.0}, n, R - rk, v, k, 2 * kPi * R / N0);
    }
  }
  return b;
}

}  // namespace

SampledBody sample_box(Point size, double dx, int layers, int dims, const Placement& pl) {
  check_common("sample_box", dx, dims, pl);
  for (int k = 0; k < dims; ++k)
    if (!(size[k] > 0) || !std::isfinite(size[k])) throw std::invalid_argument("sample_box: size must be positive");
  int n[3] = {1, 1, 1};
  double s[3] = {1, 1, 1};
  for (int k = 0; k < dims; ++k) {
    size[k] *= pl.scale;
    n[k] = cells(size[k], dx);
    s[k] = size[k] / n[k];
  }
  // Area of the cell face normal to axis k (a length in 2D).
  double face[3];
  for (int k = 0; k < 3; ++k) {
    face[k] = 1;
    for (int m = 0; m < dims; ++m)
      if (m != k) face[k] *= s[m];
  }
  const double cell_volume = dims == 3 ? s[0] * s[1] * s[2] : s[0] * s[1];
  SampledBody b;
  for (int iz = 0; iz < n[2]; ++iz)
    for (int iy = 0; iy < n[1]; ++iy)
      for (int ix = 0; ix < n[0]; ++ix) {
        const int idx[3] = {ix, iy, iz};
        int layer = 1 << 30;
        double best = 1e300;  // distance to the nearest face
        double share = 0;     // exact area of this cell's faces on the box surface
        for (int k = 0; k < dims; ++k) {
          layer = std::min({layer, idx[k], n[k] - 1 - idx[k]});
          best = std::min(best, (std::min(idx[k], n[k] - 1 - idx[k]) + 0.5) * s[k]);
          if (idx[k] == 0) share += face[k];
          if (idx[k] == n[k] - 1) share += face[k];
        }
        if (layers > 0 && layer >= layers) continue;
        // Vector to the nearest face point, or to the shared edge/corner point where faces tie.
        Point to_surface{0, 0, 0};
        const double tol = 1e-9 * best;
        for (int k = 0; k < dims; ++k) {
          const double lo = (idx[k] + 0.5) * s[k], hi = (n[k] - idx[k] - 0.5) * s[k];
          if (std::min(lo, hi) > best + tol) continue;
          to_surface[k] = lo < hi - tol ? -lo : hi;  // a tie between both faces of one axis: +
        }
        const double depth = std::sqrt(to_surface[0] * to_surface[0] + to_surface[1] * to_surface[1] +
                                       to_surface[2] * to_surface[2]);
        const Point normal = unit(to_surface);
        Point p{-0.5 * size[0] + (ix + 0.5) * s[0], -0.5 * size[1] + (iy + 0.5) * s[1], 0.0};
        if (dims == 3) p[2] = -0.5 * size[2] + (iz + 0.5) * s[2];
        push(b, p, normal, depth, cell_volume, layer, share);
      }
  place(b, pl);
  return b;
}

SampledBody sample_sphere(double radius, double dx, int layers, int dims, const Placement& pl) {
  check_common("sample_sphere", dx, dims, pl);
  if (!(radius > 0) || !std::isfinite(radius)) throw std::invalid_argument("sample_sphere: radius must be positive");
  const double R = radius * pl.scale;
  SampledBody b;
  if (dims == 2) {
    b = circle(R, dx, layers);
  } else {
    const int K = cells(R, dx);
    const double h = R / K;
    const int keep = kept(layers, K);
    const double golden = kPi * (3.0 - std::sqrt(5.0));  // golden angle [rad]
    const double r0 = R - 0.5 * h;
    const int N0 = std::max(1, int(std::lround(4 * kPi * r0 * r0 / (h * h))));
    for (int k = 0; k < keep; ++k) {
      const double ro = R - k * h, ri = ro - h, rk = ro - 0.5 * h;
      const int N = k == 0 ? N0 : std::max(1, int(std::lround(4 * kPi * rk * rk / (h * h))));
      const double v = 4.0 / 3.0 * kPi * (ro * ro * ro - ri * ri * ri) / N;
      const double twist = k * 0.5 * golden;  // decorrelate neighbouring shells
      for (int i = 0; i < N; ++i) {
        const double z = 1.0 - (2.0 * i + 1.0) / N;
        const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double a = twist + golden * i;
        const Point n = unit({rho * std::cos(a), rho * std::sin(a), z});
        push(b, {rk * n[0], rk * n[1], rk * n[2]}, n, R - rk, v, k, 4 * kPi * R * R / N0);
      }
    }
  }
  place(b, pl);
  return b;
}

SampledBody sample_cylinder(double radius, double length, double dx, int layers, int dims,
                            const Placement& pl) {
  check_common("sample_cylinder", dx, dims, pl);
  if (!(radius > 0) || !std::isfinite(radius)) throw std::invalid_argument("sample_cylinder: radius must be positive");
  const double R = radius * pl.scale;
  SampledBody b;
  if (dims == 2) {
    b = circle(R, dx, layers);
    place(b, pl);
    return b;
  }
  if (!(length > 0) || !std::isfinite(length)) throw std::invalid_argument("sample_cylinder: length must be positive");
  const double L = length * pl.scale;
  const int Kr = cells(R, dx), Kz = cells(L, dx);
  const double hr = R / Kr, hz = L / Kz;
  // Ring i: radius r_i, N_i points, annulus area A_i.
  std::vector<double> ring_r(Kr), ring_area(Kr);
  std::vector<int> ring_n(Kr);
  for (int i = 0; i < Kr; ++i) {
    const double ro = R - i * hr, ri = ro - hr;
    ring_r[i] = ro - 0.5 * hr;
    ring_n[i] = std::max(1, int(std::lround(2 * kPi * ring_r[i] / hr)));
    ring_area[i] = kPi * (ro * ro - ri * ri);
  }
  for (int j = 0; j < Kz; ++j) {
    const int jcap = std::min(j, Kz - 1 - j);  // slices to the nearer cap
    const double z = -0.5 * L + (j + 0.5) * hz;
    const double cap_dist = (jcap + 0.5) * hz;
    const double cap_dir = j < Kz - 1 - j ? -1.0 : 1.0;  // tie (middle slice): +z
    for (int i = 0; i < Kr; ++i) {
      const int layer = std::min(i, jcap);
      if (layers > 0 && layer >= layers) continue;
      const int N = ring_n[i];
      const double v = ring_area[i] * hz / N;
      double share = 0;
      if (i == 0) share += 2 * kPi * R * hz / N;
      if (j == 0) share += ring_area[i] / N;
      if (j == Kz - 1) share += ring_area[i] / N;
      const double side_dist = (i + 0.5) * hr;
      const double tol = 1e-9 * std::min(side_dist, cap_dist);
      const bool side = side_dist <= cap_dist + tol, cap = cap_dist <= side_dist + tol;
      // Distance to the nearer of side and cap, or to the rim along the normal where they tie.
      const double depth = side && cap ? std::hypot(side_dist, cap_dist) : (side ? side_dist : cap_dist);
      const double offset = ((i + j) % 2) * kPi / N;  // stagger neighbouring rings
      for (int q = 0; q < N; ++q) {
        const double a = offset + 2 * kPi * q / N;
        const double c = std::cos(a), s = std::sin(a);
        const Point normal =
            unit({side ? side_dist * c : 0.0, side ? side_dist * s : 0.0, cap ? cap_dist * cap_dir : 0.0});
        push(b, {ring_r[i] * c, ring_r[i] * s, z}, normal, depth, v, layer, share);
      }
    }
  }
  place(b, pl);
  return b;
}

}  // namespace turbid::geometry
