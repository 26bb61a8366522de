// Exact signed distances of placed solids (geometry/solid.hpp). References and tolerances, per test:
//  - primitives (box, sphere, cylinder; 2D rectangle and circle): analytic values worked out by hand
//    at chosen points of the shape's own frame (inside, outside near a face, beyond an edge, a corner
//    or a cylinder's rim, on the surface, far away), the point then placed by a scale, a rotation
//    about x, y, z (built here independently of placement.cpp: p' = Rz Ry Rx p) and a translation;
//    to 1e-12 m (rounding of the placement);
//  - a mesh box (12 triangles) against the primitive box, same placement, on a lattice of points
//    around it, edges and corners included: equal to 1e-12 m (both are exact);
//  - a UV-sphere mesh and a 128-sided cylinder mesh against the analytic sphere and cylinder: within
//    the tessellation error H (the Hausdorff distance of the inscribed polyhedron to the smooth
//    surface: R - the smallest distance of a face plane from the centre for the sphere, computed
//    from the mesh; R (1 - cos(pi / 128)) for the cylinder), and the sign right wherever
//    |d| > H; 2D sections of both (polygons inscribed in the circle: R (1 - cos(pi / n))) likewise;
//  - signs next to the surface: points 1e-9 of the size off the surface along the normal (face
//    centroids, vertices and edge midpoints of the sphere mesh; points of the box mesh on lines
//    parallel to x through its edges and vertices, where the inside test's symbolic perturbation
//    decides) get the right sign and |d| = the offset to 1e-12 m;
//  - early exit: with a cut-off the value equals the exact one where |d| < cut-off, otherwise it has
//    the same sign and cut-off <= |v| <= |d|;
//  - cost: 512000 queries on a lattice over the bounding box of a 20k-triangle sphere mesh (all of
//    them need the inside test) with a cut-off of 2 dx (dx = R / 25), reported (about 0.5 s in
//    Release); the bound asserted (10 s) only catches a pathological slowdown.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/mesh.hpp"
#include "geometry/solid.hpp"
#include "mesh_test_support.hpp"

namespace {

using turbid::geometry::MeshError;
using turbid::geometry::Placement;
using turbid::geometry::Solid;
using namespace turbid::test;

constexpr double kPi = std::numbers::pi;

// p' = Rz Ry Rx p + t (angles in degrees), written out here rather than taken from placement.cpp.
struct Frame {
  double R[3][3];
  Point t;
  Frame(Point deg, Point translation) : t(translation) {
    const double ax = deg[0] * kPi / 180, ay = deg[1] * kPi / 180, az = deg[2] * kPi / 180;
    const double Rx[3][3] = {{1, 0, 0}, {0, std::cos(ax), -std::sin(ax)}, {0, std::sin(ax), std::cos(ax)}};
    const double Ry[3][3] = {{std::cos(ay), 0, std::sin(ay)}, {0, 1, 0}, {-std::sin(ay), 0, std::cos(ay)}};
    const double Rz[3][3] = {{std::cos(az), -std::sin(az), 0}, {std::sin(az), std::cos(az), 0}, {0, 0, 1}};
    double Ryx[3][3] = {};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        R[i][j] = 0;
        for (int k = 0; k < 3; ++k) Ryx[i][j] += Ry[i][k] * Rx[k][j];
      }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) R[i][j] += Rz[i][k] * Ryx[k][j];
  }
  Point operator()(const Point& p) const {
    Point q = t;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) q[i] += R[i][j] * p[j];
    return q;
  }
};

Placement placement(double scale, Point deg, Point translation) {
  Placement pl;
  pl.scale = scale;
  pl.rotation_deg = deg;
  pl.translation = translation;
  return pl;
}

struct Probe {
  const char* what;
  Point local;      // in the shape's own (scaled) frame
  double expected;  // signed distance [m]
};

void expect_probes(const Solid& s, const Frame& f, const std::vector<Probe>& probes) {
  for (const Probe& pr : probes) {
    const Point p = f(pr.local);
    EXPECT_NEAR(s.signed_distance(p), pr.expected, 1e-12) << pr.what;
    // The early exit never changes a value below the cut-off, nor the sign beyond it.
    const double v = s.signed_distance(p, 0.01);
    if (std::abs(pr.expected) < 0.01 - 1e-9) {
      EXPECT_NEAR(v, pr.expected, 1e-12) << pr.what;
    } else {
      EXPECT_EQ(v < 0, pr.expected < 0) << pr.what;
      EXPECT_GE(std::abs(v), 0.01 - 1e-12) << pr.what;
    }
  }
}

// Analytic sphere (radius R, centre c): signed distance, negative inside.
double sphere_distance(const Point& p, const Point& c, double R) { return norm(sub(p, c)) - R; }

// ---- primitives ---------------------------------------------------------------------------------

TEST(SolidPrimitives, BoxIn3DAgainstHandValues) {
  // size 0.2 x 0.1 x 0.06 scaled by 2: half extents 0.2, 0.1, 0.06.
  const Point deg{30, -45, 60}, t{0.3, -0.1, 0.7};
  const Solid s = Solid::box({0.2, 0.1, 0.06}, 3, placement(2, deg, t));
  EXPECT_EQ(s.dims(), 3);
  expect_probes(s, Frame(deg, t),
                {
                    {"centre: the nearest face is z", {0, 0, 0}, -0.06},
                    {"inside, nearest face z", {0.05, 0.02, 0.03}, -0.03},
                    {"inside, nearest face x", {-0.19, 0.01, 0.0}, -0.01},
                    {"outside a face", {0.1, 0, 0.07}, 0.01},
                    {"outside a face, far", {1.0, 0.0, 0.0}, 0.8},
                    {"beyond an edge (x, y)", {0.23, 0.14, 0.0}, 0.05},
                    {"beyond an edge (y, z)", {0.0, -0.13, -0.1}, 0.05},
                    {"beyond a corner", {0.22, 0.12, 0.08}, 0.02 * std::sqrt(3.0)},
                    {"beyond a corner, far", {-0.5, -0.4, -0.36}, std::sqrt(0.09 + 0.09 + 0.09)},
                    {"on a face", {0.2, 0.05, 0.0}, 0.0},
                    {"on an edge", {-0.2, 0.1, 0.01}, 0.0},
                });
  // The bounding box holds the placed corners.
  const Frame f(deg, t);
  for (int c = 0; c < 8; ++c) {
    const Point q = f({(c & 1) ? 0.2 : -0.2, (c & 2) ? 0.1 : -0.1, (c & 4) ? 0.06 : -0.06});
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(s.bounds().min[k], q[k] + 1e-12);
      EXPECT_GE(s.bounds().max[k], q[k] - 1e-12);
    }
  }
}

TEST(SolidPrimitives, RectangleIn2DAgainstHandValuesAndIgnoresZ) {
  // 0.2 x 0.1 scaled by 1.5: half extents 0.15, 0.075; rotated 30 degrees about z.
  const Point deg{0, 0, 30}, t{0.3, -0.2, 0};
  const Solid s = Solid::box({0.2, 0.1, 123.0}, 2, placement(1.5, deg, t));
  EXPECT_EQ(s.dims(), 2);
  const Frame f(deg, t);
  expect_probes(s, f,
                {
                    {"centre", {0, 0, 0}, -0.075},
                    {"inside near the short side", {0.14, 0.0, 0}, -0.01},
                    {"outside the long side", {0.0, 0.08, 0}, 0.005},
                    {"beyond a corner", {0.18, -0.115, 0}, 0.05},
                    {"on a side", {-0.1, -0.075, 0}, 0.0},
                    {"far", {0.0, -2.075, 0}, 2.0},
                });
  // z does not matter in 2D.
  Point p = f({0.18, -0.115, 0});
  p[2] = 5.0;
  EXPECT_NEAR(s.signed_distance(p), 0.05, 1e-12);
  EXPECT_EQ(s.bounds().min[2], 0.0);
  EXPECT_EQ(s.bounds().max[2], 0.0);
}

TEST(SolidPrimitives, SphereAndCircleAgainstHandValues) {
  const Point deg{10, 20, 30}, t{1, 2, 3};
  const Solid s = Solid::sphere(0.1, 3, placement(2, deg, t));  // R = 0.2
  expect_probes(s, Frame(deg, t),
                {
                    {"centre", {0, 0, 0}, -0.2},
                    {"inside", {0.1, 0.1, 0.1}, std::sqrt(0.03) - 0.2},
                    {"outside", {0, 0.3, 0}, 0.1},
                    {"outside, oblique", {0.12, -0.16, 0.15}, 0.05},
                    {"on the surface", {0, 0, -0.2}, 0.0},
                    {"far", {3, 0, 4}, 4.8},
                });
  const Point deg2{0, 0, 45}, t2{0.5, 0.5, 0};
  const Solid c = Solid::sphere(0.1, 2, placement(0.5, deg2, t2));  // R = 0.05
  expect_probes(c, Frame(deg2, t2),
                {
                    {"centre", {0, 0, 0}, -0.05},
                    {"inside", {0.03, 0.0, 0}, -0.02},
                    {"on the circle", {0.03, 0.04, 0}, 0.0},
                    {"outside, far", {0.3, 0.4, 0}, 0.45},
                });
}

TEST(SolidPrimitives, CylinderAgainstHandValuesNearRimsAndCaps) {
  // R = 0.05, L = 0.4 scaled by 1.5: R = 0.075, half length 0.3.
  for (const Point deg : {Point{90, 0, 0}, Point{30, 45, 60}}) {
    SCOPED_TRACE("rotation " + std::to_string(deg[0]) + " " + std::to_string(deg[1]) + " " + std::to_string(deg[2]));
    const Point t{0.15, 0.25, 0.1};
    const Solid s = Solid::cylinder(0.05, 0.4, 3, placement(1.5, deg, t));
    const double a = 40 * kPi / 180;  // an azimuth off the axes
    expect_probes(s, Frame(deg, t),
                  {
                      {"centre: the side is nearer than the caps", {0, 0, 0}, -0.075},
                      {"inside near a cap", {0, 0, 0.29}, -0.01},
                      {"inside near the side", {0.04, 0.03, -0.1}, -0.025},
                      {"beyond a cap, within the radius", {0.03, 0.04, 0.32}, 0.02},
                      {"beyond the side", {0.1, 0, 0.1}, 0.025},
                      {"beyond the rim", {0.105 * std::cos(a), 0.105 * std::sin(a), -0.34}, 0.05},
                      {"on the rim", {0.075 * std::cos(a), 0.075 * std::sin(a), 0.3}, 0.0},
                      {"on a cap", {0.01, 0.02, -0.3}, 0.0},
                      {"far along the axis", {0, 0, 2}, 1.7},
                  });
  }
  // 2D: a circle of the radius (length ignored).
  const Point deg{0, 0, 15}, t{0.2, 0.3, 0};
  const Solid c = Solid::cylinder(0.05, 0.0, 2, placement(1, deg, t));
  expect_probes(c, Frame(deg, t), {{"centre", {0, 0, 0}, -0.05}, {"outside", {0.06, 0.08, 0}, 0.05}});
}

TEST(SolidPrimitives, RejectsBadArguments) {
  EXPECT_THROW(Solid::box({0.1, 0.0, 0.1}, 3), std::invalid_argument);
  EXPECT_THROW(Solid::box({0.1, 0.1, 0.1}, 4), std::invalid_argument);
  EXPECT_THROW(Solid::sphere(-1, 3), std::invalid_argument);
  EXPECT_THROW(Solid::sphere(1, 3, placement(0, {0, 0, 0}, {0, 0, 0})), std::invalid_argument);
  EXPECT_THROW(Solid::cylinder(0.1, 0.0, 3), std::invalid_argument);
  EXPECT_THROW(Solid::cylinder(0.1, 0.2, 2, placement(1, {10, 0, 0}, {0, 0, 0})), std::invalid_argument);
  EXPECT_THROW(Solid::box({0.1, 0.1, 0}, 2, placement(1, {0, 0, 0}, {0, 0, 0.1})), std::invalid_argument);
  EXPECT_NO_THROW(Solid::box({0.1, 0.1, 0}, 2, placement(1, {0, 0, 10}, {0.1, 0.2, 0})));
}

// ---- meshes ---------------------------------------------------------------------------------------

TEST(SolidMesh, BoxMeshEqualsThePrimitiveBoxEverywhere) {
  // 12 triangles: every face is split by a diagonal, an edge of the mesh that is not an edge of the
  // box. Both distances are exact, so they agree to rounding on a lattice of points inside, beyond
  // faces, edges and corners.
  const Point deg{20, -35, 110}, t{0.05, -0.3, 0.2};
  const Placement pl = placement(2, deg, t);
  const Solid m = Solid::mesh(box_mesh(0.2, 0.1, 0.06), 3, pl), b = Solid::box({0.2, 0.1, 0.06}, 3, pl);
  const Frame f(deg, t);
  double worst = 0;
  int inside = 0, outside = 0;
  for (int i = -14; i <= 14; ++i)
    for (int j = -12; j <= 12; ++j)
      for (int k = -6; k <= 6; ++k) {
        const Point p = f({0.025 * i, 0.0125 * j + 0.004, 0.0125 * k});
        const double dm = m.signed_distance(p), db = b.signed_distance(p);
        worst = std::max(worst, std::abs(dm - db));
        (db < 0 ? inside : outside)++;
      }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
  // In 2D the section by z = 0 of a box rotated about z is the rectangle.
  const Point deg2{0, 0, 25}, t2{0.4, 0.1, 0};
  const Solid m2 = Solid::mesh(box_mesh(0.2, 0.1, 0.06), 2, placement(1.5, deg2, t2));
  const Solid b2 = Solid::box({0.2, 0.1, 0}, 2, placement(1.5, deg2, t2));
  const Frame f2(deg2, t2);
  worst = 0;
  for (int i = -20; i <= 20; ++i)
    for (int j = -12; j <= 12; ++j) {
      const Point p = f2({0.01 * i, 0.0075 * j + 0.001, 0});
      worst = std::max(worst, std::abs(m2.signed_distance(p) - b2.signed_distance(p)));
    }
  EXPECT_LT(worst, 1e-12);
}

TEST(SolidMesh, SphereMeshWithinItsTessellationErrorOfTheSphere) {
  const double R = 0.05, scale = 1.5, Rs = R * scale;
  const TriangleMesh mesh = uv_sphere(R, 48, 96);
  // H = R - min over faces of the face plane's distance from the centre (inscribed, convex).
  double plane = 1e300;
  for (const auto& tr : mesh.triangles) {
    const Point a = mesh.vertices[tr[0]];
    const Point n = cross(sub(mesh.vertices[tr[1]], a), sub(mesh.vertices[tr[2]], a));
    plane = std::min(plane, std::abs(dot(n, a)) / norm(n));
  }
  const double H = (R - plane) * scale;
  ASSERT_LT(H, 3e-3 * Rs) << "test setup: a fine tessellation";
  const Point deg{15, 70, -40}, c{0.3, 0.2, -0.1};
  const Solid s = Solid::mesh(mesh, 3, placement(scale, deg, c));
  std::mt19937 rng(7u);
  std::uniform_real_distribution<double> u(-2.5 * Rs, 2.5 * Rs);
  double worst = 0;
  int wrong_sign = 0;
  for (int q = 0; q < 20000; ++q) {
    const Point p{c[0] + u(rng), c[1] + u(rng), c[2] + u(rng)};
    const double d = s.signed_distance(p), exact = sphere_distance(p, c, Rs);
    worst = std::max(worst, std::abs(d - exact));
    if (std::abs(exact) > H && (d < 0) != (exact < 0)) ++wrong_sign;
  }
  RecordProperty("sphere_mesh", "H " + std::to_string(H) + " m, worst |d - d_sphere| " + std::to_string(worst) + " m");
  EXPECT_LE(worst, H * (1 + 1e-9) + 1e-12);
  EXPECT_GT(worst, 0.2 * H) << "the mesh is not the sphere";
  EXPECT_EQ(wrong_sign, 0);

  // 2D: the equator (on z = 0 before placement, rotation about z only) is a 96-gon in the circle.
  const Solid s2 = Solid::mesh(mesh, 2, placement(scale, {0, 0, 33}, {c[0], c[1], 0}));
  const double H2 = Rs * (1 - std::cos(kPi / 96));
  worst = 0;
  wrong_sign = 0;
  for (int q = 0; q < 20000; ++q) {
    const Point p{c[0] + u(rng), c[1] + u(rng), 0.0};
    const double d = s2.signed_distance(p), exact = sphere_distance(p, {c[0], c[1], 0}, Rs);
    worst = std::max(worst, std::abs(d - exact));
    if (std::abs(exact) > H2 && (d < 0) != (exact < 0)) ++wrong_sign;
  }
  EXPECT_LE(worst, H2 * (1 + 1e-9) + 1e-12);
  EXPECT_GT(worst, 0.2 * H2);
  EXPECT_EQ(wrong_sign, 0);
}

TEST(SolidMesh, CylinderMeshWithinItsTessellationErrorIncludingRims) {
  const double R = 0.05, L = 0.4;
  const int sides = 128;
  const double H = R * (1 - std::cos(kPi / sides));
  // The pipe of the scenes: axis along y after [90, 0, 0]; and an oblique placement.
  for (const Point deg : {Point{90, 0, 0}, Point{30, 45, 60}}) {
    SCOPED_TRACE("rotation " + std::to_string(deg[0]) + " " + std::to_string(deg[1]) + " " + std::to_string(deg[2]));
    const Point c{0.1537, 0.2512, 0.1063};
    const Solid s = Solid::mesh(cylinder_mesh(R, L, sides), 3, placement(1, deg, c));
    const Frame f(deg, {0, 0, 0});
    const Point axis = f({0, 0, 1});
    std::mt19937 rng(11u);
    std::uniform_real_distribution<double> ur(0, 2.0 * R), ua(0, 2 * kPi), uz(-0.5 * L - 2 * R, 0.5 * L + 2 * R);
    double worst = 0, worst_rim = 0;
    int wrong_sign = 0;
    for (int q = 0; q < 20000; ++q) {
      // Uniform in a cylinder twice as wide and 2R longer at each end; a quarter of the points
      // beyond the rims (outside both the side and a cap).
      const double r = ur(rng), a = ua(rng);
      double z = uz(rng);
      if (q % 4 == 0) z = std::copysign(0.5 * L + 2 * R * std::abs(z) / (0.5 * L + 2 * R), z);  // beyond a cap
      const Point p = f({r * std::cos(a), r * std::sin(a), z});
      const Point x{p[0] + c[0], p[1] + c[1], p[2] + c[2]};
      const double d = s.signed_distance(x), exact = cylinder_distance(x, c, axis, R, 0.5 * L);
      worst = std::max(worst, std::abs(d - exact));
      if (r > R && std::abs(z) > 0.5 * L) worst_rim = std::max(worst_rim, std::abs(d - exact));
      if (std::abs(exact) > H && (d < 0) != (exact < 0)) ++wrong_sign;
    }
    EXPECT_LE(worst, H * (1 + 1e-9) + 1e-12);
    EXPECT_LE(worst_rim, H * (1 + 1e-9) + 1e-12) << "beyond the rims: the distance to the rim polygon";
    EXPECT_EQ(wrong_sign, 0);
  }
  // 2D: the mid-section (axis along z) is the 128-gon.
  const Point c{0.6, 0.3, 0};
  const Solid s2 = Solid::mesh(cylinder_mesh(R, L, sides), 2, placement(1, {0, 0, 0}, c));
  std::mt19937 rng(5u);
  std::uniform_real_distribution<double> u(-2 * R, 2 * R);
  double worst = 0;
  for (int q = 0; q < 20000; ++q) {
    const Point p{c[0] + u(rng), c[1] + u(rng), 0};
    const double d = s2.signed_distance(p), exact = sphere_distance(p, c, R);
    worst = std::max(worst, std::abs(d - exact));
    if (std::abs(exact) > H) {
      EXPECT_EQ(d < 0, exact < 0) << p[0] << " " << p[1];
    }
  }
  EXPECT_LE(worst, H * (1 + 1e-9) + 1e-12);
}

TEST(SolidMesh, SignsAreRightNextToTheSurface) {
  // Sphere mesh: face centroids, vertices and edge midpoints moved 1e-9 R along the outward
  // normal of the face (a vertex and an edge midpoint radially) inside and outside.
  const double R = 0.05, eps = 1e-9 * R;
  const TriangleMesh mesh = uv_sphere(R, 24, 48);
  const Solid s = Solid::mesh(mesh, 3);
  int wrong = 0;
  double worst = 0;
  for (const auto& tr : mesh.triangles) {
    const Point a = mesh.vertices[tr[0]], b = mesh.vertices[tr[1]], c = mesh.vertices[tr[2]];
    Point n = cross(sub(b, a), sub(c, a));
    n = {n[0] / norm(n), n[1] / norm(n), n[2] / norm(n)};
    const Point g{(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
    for (const double side : {-1.0, 1.0}) {
      const double d = s.signed_distance(axpy(g, side * eps, n));
      if ((d < 0) != (side < 0)) ++wrong;
      worst = std::max(worst, std::abs(std::abs(d) - eps));
      const Point mid{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
      for (const Point& q : {a, mid}) {
        const Point radial{q[0] / norm(q), q[1] / norm(q), q[2] / norm(q)};
        const double dq = s.signed_distance(axpy(q, side * eps, radial));
        if ((dq < 0) != (side < 0)) ++wrong;
      }
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_LT(worst, 1e-12) << "|d| is the offset from the face";
  // Vertices of the sphere mesh moved by 1e-9 R along x (those with |x| > R / 2, where x points out
  // of the polyhedron's cone at the vertex): the inside test's line through the point passes exactly
  // through the vertex.
  for (const Point& v : mesh.vertices) {
    if (std::abs(v[0]) < 0.5 * R) continue;
    for (const double side : {-1.0, 1.0}) {
      const double d = s.signed_distance({v[0] + side * std::copysign(eps, v[0]), v[1], v[2]});
      if ((d < 0) != (side < 0)) ++wrong;
    }
  }
  EXPECT_EQ(wrong, 0);
  // Box mesh, unrotated: points 1e-9 inside and outside its faces normal to x, on lines parallel to x
  // through the faces' diagonals (z = +-0.6 y: edges shared by two triangles, which the inside test's
  // line hits exactly) and elsewhere on the faces.
  const Solid b = Solid::mesh(box_mesh(0.2, 0.1, 0.06), 3);
  wrong = 0;
  double worst_box = 0;
  for (const double y : {-0.025, 0.0, 0.025, 0.04})
    for (const double z : {-0.015, 0.0, 0.015, 0.024})
      for (const double x : {-0.1, 0.1})
        for (const double side : {-1.0, 1.0}) {
          const double d = b.signed_distance({x + side * std::copysign(1e-9, x), y, z});
          if ((d < 0) != (side < 0)) ++wrong;
          worst_box = std::max(worst_box, std::abs(std::abs(d) - 1e-9));
        }
  EXPECT_EQ(wrong, 0);
  EXPECT_LT(worst_box, 1e-12);
}

TEST(SolidMesh, CutOffKeepsValuesBelowItAndSignsBeyond) {
  const Solid s = Solid::mesh(cylinder_mesh(0.05, 0.2, 64), 3, placement(1, {0, 90, 0}, {0.1, 0.1, 0.1}));
  std::mt19937 rng(3u);
  std::uniform_real_distribution<double> u(-0.05, 0.25);
  int below = 0, beyond = 0;
  for (int q = 0; q < 20000; ++q) {
    const Point p{u(rng), u(rng), u(rng)};
    const double cutoff = 0.02;
    const double exact = s.signed_distance(p), v = s.signed_distance(p, cutoff);
    if (std::abs(exact) < cutoff) {
      ++below;
      EXPECT_EQ(v, exact);
    } else {
      ++beyond;
      EXPECT_EQ(v < 0, exact < 0);
      EXPECT_GE(std::abs(v), cutoff);
      EXPECT_LE(std::abs(v), std::abs(exact));
    }
  }
  EXPECT_GT(below, 1000);
  EXPECT_GT(beyond, 1000);
}

TEST(SolidMesh, QueriesAroundASphereMeshAreFast) {
  // 2 x 100 x 99 = 19800 triangles; a lattice of 80^3 points over the sphere's bounding box grown
  // by 2 dx (dx = R / 25), the cut-off 2 dx as the carver would use it.
  const double R = 0.05, dx = R / 25;
  const auto t0 = std::chrono::steady_clock::now();
  const Solid s = Solid::mesh(uv_sphere(R, 100, 100), 3);
  const auto t1 = std::chrono::steady_clock::now();
  const int n = 80;
  const double lo = -R - 2 * dx, h = 2 * (R + 2 * dx) / n;
  std::size_t inside = 0, near = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double d = s.signed_distance({lo + (i + 0.5) * h, lo + (j + 0.5) * h, lo + (k + 0.5) * h}, 2 * dx);
        inside += d < 0;
        near += std::abs(d) < 2 * dx;
      }
  const auto t2 = std::chrono::steady_clock::now();
  const double build = std::chrono::duration<double>(t1 - t0).count(), query = std::chrono::duration<double>(t2 - t1).count();
  RecordProperty("timing", "build " + std::to_string(build) + " s, 512000 queries " + std::to_string(query) + " s");
  // Inside: the sphere's volume over the lattice cell, to the lattice's counting noise.
  const double expected = 4.0 / 3.0 * kPi * R * R * R / (h * h * h);
  EXPECT_NEAR(double(inside), expected, 0.01 * expected);
  EXPECT_GT(near, 0u);
  EXPECT_LT(build + query, 10.0);
}

TEST(SolidMesh, BadMeshesAndMissedSectionsAreMeshErrors) {
  TriangleMesh open = box_mesh(0.2, 0.1, 0.06);
  open.triangles.pop_back();
  EXPECT_THROW(Solid::mesh(open, 3), MeshError);
  TriangleMesh inverted = box_mesh(0.2, 0.1, 0.06);
  for (auto& tr : inverted.triangles) std::swap(tr[1], tr[2]);
  EXPECT_THROW(Solid::mesh(inverted, 3), MeshError);
  // The plane z = 0 misses a box lifted by 1 m.
  EXPECT_THROW(Solid::mesh(box_mesh(0.2, 0.1, 0.06), 2, placement(1, {0, 0, 0}, {0, 0, 1})), MeshError);
  EXPECT_THROW(Solid::mesh(box_mesh(0.2, 0.1, 0.06), 5), std::invalid_argument);
}

}  // namespace
