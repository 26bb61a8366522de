// Helpers shared by the unit tests of meshes, solids, primitives and mesh structures in scenes
// (test_mesh.cpp, test_solid.cpp, test_primitives.cpp, test_structure_scenes.cpp): small vector
// arithmetic on geometry::Point, analytic reference values, meshes built in code and a scratch
// directory for the files the tests write.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <numbers>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

#include "geometry/mesh.hpp"
#include "geometry/primitives.hpp"

namespace turbid::test {

// The geometry types of the helpers' signatures, also for the tests that use this namespace.
using geometry::Point;
using geometry::SampledBody;
using geometry::TriangleMesh;

// ---- arithmetic -------------------------------------------------------------------------------

// Relative error |estimate - reference| / |reference|.
inline double rel(double estimate, double reference) { return std::abs(estimate - reference) / std::abs(reference); }

// Scalar product a . b.
inline double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Euclidean length |a|.
inline double norm(const Point& a) { return std::sqrt(dot(a, a)); }

// Difference a - b.
inline Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

// Cross product a x b.
inline Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// a + s b.
inline Point axpy(const Point& a, double s, const Point& b) { return {a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]}; }

// The surface point particle i of a sampled body names: x + depth n.
inline Point surface_point(const SampledBody& b, std::size_t i) {
  return {b.points[i][0] + b.depth[i] * b.normals[i][0], b.points[i][1] + b.depth[i] * b.normals[i][1],
          b.points[i][2] + b.depth[i] * b.normals[i][2]};
}

// Signed distance (negative inside) from p to the analytic solid cylinder of radius R and half
// length h whose unit axis `axis` passes through its centre c.
inline double cylinder_distance(const Point& p, const Point& c, const Point& axis, double R, double h) {
  const Point d = sub(p, c);
  const double along = dot(d, axis);
  const double radial = norm(axpy(d, -along, axis)) - R, cap = std::abs(along) - h;
  return std::min(std::max(radial, cap), 0.0) + std::hypot(std::max(radial, 0.0), std::max(cap, 0.0));
}

// ---- meshes in code ---------------------------------------------------------------------------

// UV sphere, outward faces; the equator ring lies exactly on z = 0 (nlat even).
inline TriangleMesh uv_sphere(double R, int nlat, int nlon) {
  constexpr double kPi = std::numbers::pi;
  TriangleMesh m;
  m.vertices.push_back({0, 0, R});
  for (int i = 1; i < nlat; ++i) {
    const double th = kPi * i / nlat;
    const double z = 2 * i == nlat ? 0.0 : R * std::cos(th), rho = 2 * i == nlat ? R : R * std::sin(th);
    for (int j = 0; j < nlon; ++j) {
      const double ph = 2 * kPi * j / nlon;
      m.vertices.push_back({rho * std::cos(ph), rho * std::sin(ph), z});
    }
  }
  m.vertices.push_back({0, 0, -R});
  const int south = int(m.vertices.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * nlon + (j % nlon); };
  for (int j = 0; j < nlon; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < nlat; ++i)
    for (int j = 0; j < nlon; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  for (int j = 0; j < nlon; ++j) m.triangles.push_back({south, ring(nlat - 1, j + 1), ring(nlat - 1, j)});
  return m;
}

// Prism over a counter-clockwise polygon (z in [z0, z1]); caps as a fan from vertex `fan`.
inline TriangleMesh prism(const std::vector<std::array<double, 2>>& poly, double z0, double z1, int fan = 0) {
  TriangleMesh m;
  const int n = int(poly.size());
  for (const auto& p : poly) m.vertices.push_back({p[0], p[1], z0});
  for (const auto& p : poly) m.vertices.push_back({p[0], p[1], z1});
  for (int i = 0; i < n; ++i) {
    const int a = i, b = (i + 1) % n;
    m.triangles.push_back({a, b, n + b});
    m.triangles.push_back({a, n + b, n + a});
  }
  for (int k = 1; k + 1 < n; ++k) {
    const int a = fan, b = (fan + k) % n, c = (fan + k + 1) % n;
    m.triangles.push_back({n + a, n + b, n + c});  // top, normal +z
    m.triangles.push_back({a, c, b});              // bottom, normal -z
  }
  return m;
}

// Closed cylinder of radius R and length L along z, centred at the origin, with `sides` sides.
inline TriangleMesh cylinder_mesh(double R, double L, int sides) {
  constexpr double kPi = std::numbers::pi;
  std::vector<std::array<double, 2>> poly;
  for (int j = 0; j < sides; ++j) poly.push_back({R * std::cos(2 * kPi * j / sides), R * std::sin(2 * kPi * j / sides)});
  return prism(poly, -0.5 * L, 0.5 * L);
}

// Box [-a/2, a/2] x [-b/2, b/2] x [-c/2, c/2] (12 triangles).
inline TriangleMesh box_mesh(double a, double b, double c) {
  return prism({{-a / 2, -b / 2}, {a / 2, -b / 2}, {a / 2, b / 2}, {-a / 2, b / 2}}, -c / 2, c / 2);
}

// ---- files ------------------------------------------------------------------------------------

// A directory turbid-test-<tag>-<pid> under the system's temporary directory, removed with the
// object (a test file holds one in a function-local static: removed at exit).
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string& tag)
      : path(std::filesystem::temp_directory_path() / ("turbid-test-" + tag + "-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
};

}  // namespace turbid::test
