// Layered sampling of structure primitives (geometry/primitives.hpp). References: the analytic
// surface areas and volumes (sphere 4 pi R^2, 4/3 pi R^3; cylinder 2 pi R L + 2 pi R^2, pi R^2 L;
// circle 2 pi R, pi R^2; box 2(ab + bc + ca), abc), which the sampling reproduces by construction
// (each particle's volume / surface share is an exact piece of the shape), so they are asserted to
// 1e-12 relative, far inside the 1 % the brief allows; and the analytic second moments
// (sphere: int |x|^2 dV = 4/5 pi R^5; circle: int |x|^2 dA = pi R^4 / 2; cylinder about its axis:
// pi R^4 L / 2; box: int x^2 dV = a^3 b c / 12), which depend on where the particles sit and so carry
// the real sampling error: asserted within 1 % at R/dx = 10 and to shrink when dx halves.
// Depth: x + depth * normal must lie on the analytic surface (1e-12 m), and depth must be the exact
// distance to the nearest surface (1e-12 m; where faces tie, the distance to their shared edge/corner).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "geometry/primitives.hpp"
#include "mesh_test_support.hpp"

namespace {

using turbid::geometry::Placement;
using turbid::geometry::sample_box;
using turbid::geometry::sample_cylinder;
using turbid::geometry::sample_sphere;
using namespace turbid::test;

constexpr double kPi = std::numbers::pi;

// sum v (w_x x^2 + w_y y^2 + w_z z^2)
double moment(const SampledBody& b, Point w) {
  double m = 0;
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    const auto& p = b.points[i];
    m += b.volumes[i] * (w[0] * p[0] * p[0] + w[1] * p[1] * p[1] + w[2] * p[2] * p[2]);
  }
  return m;
}

void expect_consistent(const SampledBody& b) {
  ASSERT_EQ(b.normals.size(), b.points.size());
  ASSERT_EQ(b.volumes.size(), b.points.size());
  ASSERT_EQ(b.layer.size(), b.points.size());
  ASSERT_EQ(b.depth.size(), b.points.size());
  ASSERT_EQ(b.surface_share.size(), b.points.size());
  double v = 0, s = 0;
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    EXPECT_NEAR(norm(b.normals[i]), 1.0, 1e-12);  // unit normals, 1e-12 (brief)
    EXPECT_GT(b.volumes[i], 0.0);
    EXPECT_GE(b.layer[i], 0);
    EXPECT_GT(b.depth[i], 0.0);
    if (b.layer[i] != 0) {
      EXPECT_EQ(b.surface_share[i], 0.0);
    }
    v += b.volumes[i];
    s += b.surface_share[i];
  }
  EXPECT_NEAR(b.volume, v, 1e-12 * v);        // volume is the sum of the particle volumes
  EXPECT_NEAR(b.surface_area, s, 1e-12 * s);  // surface_area is the sum of the shares
}

// Depth of a particle at the given distances to the faces it may be nearest to: the minimum, or
// the distance to the shared edge/corner point where the nearest ones tie (1e-9 relative).
double expected_depth(std::vector<double> d) {
  const double m = *std::min_element(d.begin(), d.end());
  double sq = 0;
  for (double x : d)
    if (x <= m * (1 + 1e-9)) sq += x * x;
  return std::sqrt(sq);
}

// Cylinder about z (or a circle when L = 0, 2D): x + depth n on the surface, depth as above.
void expect_cylinder_depths(const SampledBody& b, double R, double L) {
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    const Point& p = b.points[i];
    const Point s = surface_point(b, i);
    const double r = std::hypot(p[0], p[1]), rs = std::hypot(s[0], s[1]);
    if (L == 0) {
      EXPECT_NEAR(b.depth[i], R - r, 1e-12);
      EXPECT_NEAR(rs, R, 1e-12);
      continue;
    }
    EXPECT_NEAR(b.depth[i], expected_depth({R - r, 0.5 * L - std::abs(p[2])}), 1e-12);
    const bool on_side = std::abs(rs - R) < 1e-12 && std::abs(s[2]) <= 0.5 * L + 1e-12;
    const bool on_cap = std::abs(std::abs(s[2]) - 0.5 * L) < 1e-12 && rs <= R + 1e-12;
    EXPECT_TRUE(on_side || on_cap) << "particle " << i;
  }
}

// Box of `size` centred at the origin (the first `dims` axes).
void expect_box_depths(const SampledBody& b, const Point& size, int dims) {
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    const Point& p = b.points[i];
    const Point s = surface_point(b, i);
    std::vector<double> faces;
    bool on_face = false, within = true;
    for (int k = 0; k < dims; ++k) {
      faces.push_back(0.5 * size[k] - std::abs(p[k]));
      on_face = on_face || std::abs(std::abs(s[k]) - 0.5 * size[k]) < 1e-12;
      within = within && std::abs(s[k]) <= 0.5 * size[k] + 1e-12;
    }
    EXPECT_NEAR(b.depth[i], expected_depth(faces), 1e-12);
    EXPECT_TRUE(on_face && within) << "particle " << i;
  }
}

double min_distance(const SampledBody& b) {
  double best = 1e300;
  for (std::size_t i = 0; i < b.points.size(); ++i)
    for (std::size_t j = i + 1; j < b.points.size(); ++j) {
      const Point d{b.points[i][0] - b.points[j][0], b.points[i][1] - b.points[j][1], b.points[i][2] - b.points[j][2]};
      best = std::min(best, dot(d, d));
    }
  return std::sqrt(best);
}

TEST(PrimitiveSphere, AreaVolumeAndMomentAgainstAnalytic) {
  const double R = 1.0;
  double moment_err[2];
  for (int r = 0; r < 2; ++r) {
    const double dx = r == 0 ? 0.1 : 0.05;  // R/dx = 10, 20
    const SampledBody b = sample_sphere(R, dx, 0, 3);
    expect_consistent(b);
    EXPECT_LT(rel(b.surface_area, 4 * kPi * R * R), 1e-12);
    EXPECT_LT(rel(b.volume, 4.0 / 3.0 * kPi * R * R * R), 1e-12);
    moment_err[r] = rel(moment(b, {1, 1, 1}), 0.8 * kPi * std::pow(R, 5));
    EXPECT_LT(moment_err[r], 0.01);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      EXPECT_GT(dot(b.normals[i], b.points[i]), 0.0);  // outward
      EXPECT_LT(norm(b.points[i]), R);
      EXPECT_NEAR(b.depth[i], R - norm(b.points[i]), 1e-12);
      EXPECT_NEAR(norm(surface_point(b, i)), R, 1e-12);
    }
  }
  EXPECT_LT(moment_err[1], 0.5 * moment_err[0]);  // O(dx^2): ~4x smaller, asserted 2x
}

TEST(PrimitiveCircle, PerimeterAreaAndMomentAgainstAnalytic) {
  const double R = 0.8;
  double moment_err[2];
  for (int r = 0; r < 2; ++r) {
    const double dx = r == 0 ? 0.08 : 0.04;  // R/dx = 10, 20
    for (const SampledBody& b : {sample_sphere(R, dx, 0, 2), sample_cylinder(R, 123.0, dx, 0, 2)}) {
      expect_consistent(b);
      EXPECT_LT(rel(b.surface_area, 2 * kPi * R), 1e-12);  // perimeter
      EXPECT_LT(rel(b.volume, kPi * R * R), 1e-12);        // area
      moment_err[r] = rel(moment(b, {1, 1, 0}), 0.5 * kPi * std::pow(R, 4));
      EXPECT_LT(moment_err[r], 0.01);
      expect_cylinder_depths(b, R, 0.0);
      for (std::size_t i = 0; i < b.points.size(); ++i) {
        EXPECT_EQ(b.points[i][2], 0.0);
        EXPECT_EQ(b.normals[i][2], 0.0);
        EXPECT_GT(dot(b.normals[i], b.points[i]), 0.0);  // outward
      }
    }
  }
  EXPECT_LT(moment_err[1], 0.5 * moment_err[0]);
}

TEST(PrimitiveCylinder, AreaVolumeAndMomentAgainstAnalytic) {
  const double R = 0.5, L = 1.3;
  double moment_err[2];
  for (int r = 0; r < 2; ++r) {
    const double dx = r == 0 ? 0.05 : 0.025;  // R/dx = 10, 20
    const SampledBody b = sample_cylinder(R, L, dx, 0, 3);
    expect_consistent(b);
    EXPECT_LT(rel(b.surface_area, 2 * kPi * R * L + 2 * kPi * R * R), 1e-12);
    EXPECT_LT(rel(b.volume, kPi * R * R * L), 1e-12);
    moment_err[r] = rel(moment(b, {1, 1, 0}), 0.5 * kPi * std::pow(R, 4) * L);
    EXPECT_LT(moment_err[r], 0.01);
    expect_cylinder_depths(b, R, L);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point& p = b.points[i];
      const Point& n = b.normals[i];
      EXPECT_LT(std::hypot(p[0], p[1]), R);
      EXPECT_LT(std::abs(p[2]), 0.5 * L);
      // Outward: the radial part of n points away from the axis, the axial part away from the middle.
      EXPECT_GE(n[0] * p[0] + n[1] * p[1], 0.0);
      EXPECT_GE(n[2] * p[2], 0.0);
      EXPECT_GT(dot(n, p), 0.0);
    }
  }
  EXPECT_LT(moment_err[1], 0.5 * moment_err[0]);
}

TEST(PrimitiveBox, AreaVolumeMomentAndNormals) {
  const double a = 1.0, bb = 0.6, c = 0.4;  // even cell counts: no cell is equidistant from opposite faces
  double moment_err[2];
  for (int r = 0; r < 2; ++r) {
    const double dx = r == 0 ? 0.05 : 0.025;
    const SampledBody b = sample_box({a, bb, c}, dx, 0, 3);
    expect_consistent(b);
    EXPECT_LT(rel(b.surface_area, 2 * (a * bb + bb * c + c * a)), 1e-12);
    EXPECT_LT(rel(b.volume, a * bb * c), 1e-12);
    // Midpoint rule in x: relative error (s/a)^2 / 2 against the analytic a^3 b c / 12.
    moment_err[r] = rel(moment(b, {1, 0, 0}), a * a * a * bb * c / 12);
    EXPECT_LT(moment_err[r], 0.01);
    expect_box_depths(b, {a, bb, c}, 3);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point& p = b.points[i];
      EXPECT_GT(dot(b.normals[i], p), 0.0);  // outward from the centre
      for (int k = 0; k < 3; ++k)
        if (b.normals[i][k] != 0) {
          EXPECT_GT(b.normals[i][k] * p[k], 0.0);
        }
    }
  }
  EXPECT_LT(moment_err[1], 0.5 * moment_err[0]);

  // 2D: perimeter 2(a + b), area a b.
  const SampledBody b2 = sample_box({a, bb, 0.0}, 0.05, 0, 2);
  expect_consistent(b2);
  EXPECT_LT(rel(b2.surface_area, 2 * (a + bb)), 1e-12);
  EXPECT_LT(rel(b2.volume, a * bb), 1e-12);
  EXPECT_EQ(b2.points.size(), 20u * 12u);
  expect_box_depths(b2, {a, bb, 0.0}, 2);
  // A cube with an odd cell count: corner, edge and centre ties (depth to the shared edge/corner).
  const SampledBody cube = sample_box({0.5, 0.5, 0.5}, 0.1, 0, 3);
  expect_consistent(cube);
  expect_box_depths(cube, {0.5, 0.5, 0.5}, 3);
  EXPECT_NEAR(cube.depth[0], 0.05 * std::sqrt(3.0), 1e-12);  // corner cell: to the corner
}

TEST(PrimitiveLayers, ShellDepthsAndLayerVolumes) {
  const double dx = 0.1;
  // Sphere R = 1, two shells of h = 0.1: analytic shell volume 4/3 pi (1 - 0.8^3).
  const SampledBody s = sample_sphere(1.0, dx, 2, 3);
  expect_consistent(s);
  EXPECT_LT(rel(s.volume, 4.0 / 3.0 * kPi * (1.0 - 0.512)), 1e-12);
  EXPECT_LT(rel(s.surface_area, 4 * kPi), 1e-12);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    ASSERT_TRUE(s.layer[i] == 0 || s.layer[i] == 1);
    EXPECT_NEAR(1.0 - norm(s.points[i]), (s.layer[i] + 0.5) * dx, 1e-12);  // depth (k + 0.5) dx
    EXPECT_NEAR(s.depth[i], (s.layer[i] + 0.5) * dx, 1e-12);
  }
  // Cylinder R = 0.5, L = 1.2, one layer of h = 0.1: pi R^2 L - pi (R - h)^2 (L - 2h).
  const SampledBody c = sample_cylinder(0.5, 1.2, dx, 1, 3);
  expect_consistent(c);
  EXPECT_LT(rel(c.volume, kPi * (0.25 * 1.2 - 0.16 * 1.0)), 1e-12);
  EXPECT_LT(rel(c.surface_area, 2 * kPi * 0.5 * 1.2 + 2 * kPi * 0.25), 1e-12);
  for (int l : c.layer) EXPECT_EQ(l, 0);
  expect_cylinder_depths(c, 0.5, 1.2);
  // Box 1 x 0.6 x 0.4, two layers of 0.1: abc - (a - 0.4)(b - 0.4)(c - 0.4).
  const SampledBody b = sample_box({1.0, 0.6, 0.4}, dx, 2, 3);
  expect_consistent(b);
  EXPECT_LT(rel(b.volume, 0.24), 1e-12);  // c - 0.4 = 0: two layers are the whole box
  const SampledBody b1 = sample_box({1.0, 0.6, 0.4}, dx, 1, 3);
  EXPECT_LT(rel(b1.volume, 0.24 - 0.8 * 0.4 * 0.2), 1e-12);
  EXPECT_EQ(b1.points.size(), 240u - 8u * 4u * 2u);
  // More layers than fit: the whole solid.
  EXPECT_EQ(sample_sphere(1.0, dx, 50, 3).points.size(), sample_sphere(1.0, dx, 0, 3).points.size());
}

TEST(PrimitivePlacement, RotatedBoxStaysInsideAndNormalsRotate) {
  const Point size{0.8, 0.5, 0.3};
  Placement pl;
  pl.rotation_deg = {30, -45, 70};
  pl.translation = {1.0, -2.0, 0.5};
  const SampledBody local = sample_box(size, 0.05, 0, 3);
  const SampledBody moved = sample_box(size, 0.05, 0, 3, pl);
  ASSERT_EQ(local.points.size(), moved.points.size());
  expect_consistent(moved);
  EXPECT_LT(rel(moved.volume, local.volume), 1e-12);
  // Rotation matrix Rz Ry Rx built independently from the three elementary rotations.
  const double d = kPi / 180;
  auto rx = [&](Point v) { const double c = std::cos(30 * d), s = std::sin(30 * d); return Point{v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]}; };
  auto ry = [&](Point v) { const double c = std::cos(-45 * d), s = std::sin(-45 * d); return Point{c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]}; };
  auto rz = [&](Point v) { const double c = std::cos(70 * d), s = std::sin(70 * d); return Point{c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]}; };
  // Local axes of the rotated box, to test "inside" in the box's own frame.
  const Point ex = rz(ry(rx({1, 0, 0}))), ey = rz(ry(rx({0, 1, 0}))), ez = rz(ry(rx({0, 0, 1})));
  for (std::size_t i = 0; i < moved.points.size(); ++i) {
    const Point rel_p{moved.points[i][0] - pl.translation[0], moved.points[i][1] - pl.translation[1],
                      moved.points[i][2] - pl.translation[2]};
    EXPECT_LT(std::abs(dot(rel_p, ex)), 0.5 * size[0]);
    EXPECT_LT(std::abs(dot(rel_p, ey)), 0.5 * size[1]);
    EXPECT_LT(std::abs(dot(rel_p, ez)), 0.5 * size[2]);
    const Point want_p = rz(ry(rx(local.points[i])));
    const Point want_n = rz(ry(rx(local.normals[i])));
    EXPECT_EQ(moved.depth[i], local.depth[i]);  // depth is invariant under the placement
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(rel_p[k], want_p[k], 1e-12);
      EXPECT_NEAR(moved.normals[i][k], want_n[k], 1e-12);
    }
  }
  // Scale 2 doubles the dimensions at the same spacing: volume x 8 (analytic 4/3 pi (2R)^3).
  Placement big;
  big.scale = 2.0;
  EXPECT_LT(rel(sample_sphere(0.5, 0.1, 0, 3, big).volume, 4.0 / 3.0 * kPi), 1e-12);
  // 2D: rotation about z only.
  Placement tilt;
  tilt.rotation_deg = {10, 0, 0};
  EXPECT_THROW(sample_box({1, 1, 0}, 0.1, 0, 2, tilt), std::invalid_argument);
}

TEST(PrimitiveSpacing, NoOverlapBruteForce) {
  // Small bodies (including R/dx = 6, odd sizes and the innermost shells): min distance >= dx/2.
  const double dx = 0.05;
  Placement pl;
  pl.rotation_deg = {15, 25, 35};
  const SampledBody bodies[] = {
      sample_sphere(0.3, dx, 0, 3),        sample_sphere(0.33, dx, 0, 2),
      sample_cylinder(0.25, 0.32, dx, 0, 3), sample_box({0.37, 0.21, 0.13}, dx, 0, 3, pl),
  };
  for (const auto& b : bodies) {
    ASSERT_GT(b.points.size(), 10u);
    EXPECT_GE(min_distance(b), 0.5 * dx);
  }
}

TEST(PrimitiveInput, RejectsBadArguments) {
  EXPECT_THROW(sample_sphere(1.0, 0.0, 0, 3), std::invalid_argument);
  EXPECT_THROW(sample_sphere(-1.0, 0.1, 0, 3), std::invalid_argument);
  EXPECT_THROW(sample_sphere(1.0, 0.1, 0, 4), std::invalid_argument);
  EXPECT_THROW(sample_cylinder(1.0, 0.0, 0.1, 0, 3), std::invalid_argument);
  EXPECT_THROW(sample_box({1, 0, 1}, 0.1, 0, 3), std::invalid_argument);
}

}  // namespace
