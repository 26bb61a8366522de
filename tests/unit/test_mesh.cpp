// Structures from mesh files (geometry/mesh.hpp). The test meshes are written from code into a
// temporary directory: a UV sphere as ASCII and binary STL, a closed cylinder as OBJ, a box as ASCII
// PLY (quad faces), an L-shaped prism as OBJ, and broken files for every error class.
// References and tolerances, per test:
//  - loading: the in-code mesh itself (vertex count after merging, area, volume to 1e-6 relative,
//    the float precision assimp reads with);
//  - sphere R = 0.05 m (48 x 96 UV tessellation: the mesh is within 0.2 % of 4 pi R^2 and 4/3 pi R^3,
//    asserted) and cylinder R = 0.05 m, L = 0.2 m (128 sides: 2 pi R L + 2 pi R^2, pi R^2 L) sampled
//    at dx = 0.01 (R/dx = 5, the CI spacing) and 0.005: sampled surface_area and volume within 1 % of
//    the analytic values; 2D sections (circle pi R^2, 2 pi R) within 1 %;
//  - normals within 10 degrees of the radial direction, x + depth n within 0.05 dx of the mesh
//    (the sphere's surface give or take the tessellation's sagitta);
//  - the L-shaped prism (faces on the lattice planes): volume exact to 1e-9, depth equal to the
//    analytic distance to the prism's surface (incl. the re-entrant edge) to 1e-12 m;
//  - placement: a box scaled by 2, rotated 90 degrees about z and translated: volume (abc s^3) to
//    1e-9, the particles' bounding box = the rotated box shrunk by dx/2 to 1e-9 m;
//  - errors: MeshError naming the file and the defect.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "geometry/mesh.hpp"
#include "geometry/primitives.hpp"
#include "mesh_test_support.hpp"

namespace {

using turbid::geometry::load_mesh;
using turbid::geometry::MeshError;
using turbid::geometry::Placement;
using turbid::geometry::sample_mesh;
namespace fs = std::filesystem;
using namespace turbid::test;

constexpr double kPi = std::numbers::pi;
constexpr double kR = 0.05;  // sphere and cylinder radius [m]
constexpr double kL = 0.2;   // cylinder length [m]

// ---- meshes in code ---------------------------------------------------------------------------

TriangleMesh flipped(TriangleMesh m) {
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

// ---- writers ----------------------------------------------------------------------------------

// This file's scratch directory, removed at exit.
const fs::path& scratch() {
  static const ScratchDir dir("mesh");
  return dir.path;
}

std::string path_of(const std::string& name) { return (scratch() / name).string(); }

Point face_normal(const TriangleMesh& m, const std::array<int, 3>& t) {
  const Point n = cross(sub(m.vertices[t[1]], m.vertices[t[0]]), sub(m.vertices[t[2]], m.vertices[t[0]]));
  const double l = norm(n);
  return l > 0 ? Point{n[0] / l, n[1] / l, n[2] / l} : Point{0, 0, 0};
}

std::string write_ascii_stl(const std::string& name, const TriangleMesh& m) {
  const std::string p = path_of(name);
  std::FILE* f = std::fopen(p.c_str(), "w");
  std::fprintf(f, "solid test\n");
  for (const auto& t : m.triangles) {
    const Point n = face_normal(m, t);
    std::fprintf(f, " facet normal %.9g %.9g %.9g\n  outer loop\n", n[0], n[1], n[2]);
    for (int v : t) std::fprintf(f, "   vertex %.9g %.9g %.9g\n", m.vertices[v][0], m.vertices[v][1], m.vertices[v][2]);
    std::fprintf(f, "  endloop\n endfacet\n");
  }
  std::fprintf(f, "endsolid test\n");
  std::fclose(f);
  return p;
}

std::string write_binary_stl(const std::string& name, const TriangleMesh& m) {
  const std::string p = path_of(name);
  std::ofstream f(p, std::ios::binary);
  char header[80] = "binary STL written by the turbid unit tests";
  f.write(header, 80);
  const std::uint32_t n = std::uint32_t(m.triangles.size());
  f.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : m.triangles) {
    const Point nn = face_normal(m, t);
    float rec[12] = {float(nn[0]), float(nn[1]), float(nn[2])};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) rec[3 + 3 * c + k] = float(m.vertices[t[c]][k]);
    f.write(reinterpret_cast<const char*>(rec), sizeof rec);
    const std::uint16_t attr = 0;
    f.write(reinterpret_cast<const char*>(&attr), 2);
  }
  return p;
}

std::string write_obj(const std::string& name, const TriangleMesh& m) {
  const std::string p = path_of(name);
  std::FILE* f = std::fopen(p.c_str(), "w");
  std::fprintf(f, "# written by the turbid unit tests\no body\n");
  for (const auto& v : m.vertices) std::fprintf(f, "v %.9g %.9g %.9g\n", v[0], v[1], v[2]);
  for (const auto& t : m.triangles) std::fprintf(f, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  std::fclose(f);
  return p;
}

// Box [-a/2, a/2] x [-b/2, b/2] x [-c/2, c/2] with six quad faces (assimp triangulates them).
std::string write_ply_box(const std::string& name, double a, double b, double c) {
  const std::string p = path_of(name);
  std::FILE* f = std::fopen(p.c_str(), "w");
  std::fprintf(f, "ply\nformat ascii 1.0\ncomment turbid unit tests\nelement vertex 8\n"
                  "property float x\nproperty float y\nproperty float z\nelement face 6\n"
                  "property list uchar int vertex_indices\nend_header\n");
  for (int v = 0; v < 8; ++v)
    std::fprintf(f, "%.9g %.9g %.9g\n", (v & 1 ? 0.5 : -0.5) * a, (v & 2 ? 0.5 : -0.5) * b, (v & 4 ? 0.5 : -0.5) * c);
  // Counter-clockwise seen from outside.
  std::fprintf(f, "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
  std::fclose(f);
  return p;
}

// ---- checks ---------------------------------------------------------------------------------

void expect_consistent(const SampledBody& b, double dx, int layers) {
  const std::size_t n = b.points.size();
  ASSERT_GT(n, 0u);
  ASSERT_EQ(b.normals.size(), n);
  ASSERT_EQ(b.volumes.size(), n);
  ASSERT_EQ(b.layer.size(), n);
  ASSERT_EQ(b.depth.size(), n);
  ASSERT_EQ(b.surface_share.size(), n);
  double v = 0, s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_NEAR(norm(b.normals[i]), 1.0, 1e-12);
    EXPECT_GT(b.volumes[i], 0.0);
    EXPECT_GE(b.depth[i], 0.0);
    EXPECT_EQ(b.layer[i], int(b.depth[i] / dx));
    if (layers > 0) {
      EXPECT_LT(b.depth[i], layers * dx);
    }
    if (b.layer[i] != 0) {
      EXPECT_EQ(b.surface_share[i], 0.0);
    }
    v += b.volumes[i];
    s += b.surface_share[i];
  }
  EXPECT_NEAR(b.surface_area, s, 1e-12 * s);
  if (layers <= 0) {
    EXPECT_NEAR(b.volume, v, 1e-12 * v);  // filled: the particle volumes are the solid's
  } else {
    EXPECT_LT(v, b.volume);  // a shell: less than the solid
  }
}

std::string error_of(const std::string& path) {
  try {
    load_mesh(path);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "(no MeshError)";
}

// ---- tests ----------------------------------------------------------------------------------

TEST(MeshLoad, FormatsReproduceTheMeshWritten) {
  const TriangleMesh sphere = uv_sphere(kR, 48, 96);
  // The tessellation is fine enough for the 1 % checks below: within 0.2 % of the analytic sphere.
  EXPECT_LT(rel(sphere.area(), 4 * kPi * kR * kR), 0.002);
  EXPECT_LT(rel(sphere.volume(), 4.0 / 3.0 * kPi * kR * kR * kR), 0.002);
  for (const std::string& p : {write_ascii_stl("sphere_ascii.stl", sphere), write_binary_stl("sphere_binary.stl", sphere)}) {
    const TriangleMesh m = load_mesh(p);
    EXPECT_EQ(m.vertices.size(), sphere.vertices.size()) << p;  // STL corners merged back
    EXPECT_EQ(m.triangles.size(), sphere.triangles.size()) << p;
    EXPECT_LT(rel(m.area(), sphere.area()), 1e-6) << p;
    EXPECT_LT(rel(m.volume(), sphere.volume()), 1e-6) << p;
  }
  const TriangleMesh cyl = cylinder_mesh(kR, kL, 128);
  EXPECT_LT(rel(cyl.area(), 2 * kPi * kR * kL + 2 * kPi * kR * kR), 0.002);
  EXPECT_LT(rel(cyl.volume(), kPi * kR * kR * kL), 0.002);
  const TriangleMesh c = load_mesh(write_obj("cylinder.obj", cyl));
  EXPECT_EQ(c.vertices.size(), cyl.vertices.size());
  EXPECT_EQ(c.triangles.size(), cyl.triangles.size());
  EXPECT_LT(rel(c.volume(), cyl.volume()), 1e-6);
  const TriangleMesh b = load_mesh(write_ply_box("box.ply", 0.2, 0.1, 0.06));
  EXPECT_EQ(b.vertices.size(), 8u);
  EXPECT_EQ(b.triangles.size(), 12u);  // six quads, triangulated
  EXPECT_LT(rel(b.volume(), 0.2 * 0.1 * 0.06), 1e-6);
  EXPECT_LT(rel(b.area(), 2 * (0.2 * 0.1 + 0.1 * 0.06 + 0.06 * 0.2)), 1e-6);
  // Two objects in one OBJ file (two assimp meshes): merged into one mesh of both volumes.
  {
    const TriangleMesh unit = box_mesh(1, 1, 1);
    std::ofstream f(path_of("two_objects.obj"));
    for (int o = 0; o < 2; ++o) {
      f << "o part" << o << "\n";
      for (const auto& v : unit.vertices) f << "v " << v[0] + 3 * o << " " << v[1] << " " << v[2] << "\n";
      for (const auto& t : unit.triangles)
        f << "f " << t[0] + 1 + 8 * o << " " << t[1] + 1 + 8 * o << " " << t[2] + 1 + 8 * o << "\n";
    }
  }
  const TriangleMesh two = load_mesh(path_of("two_objects.obj"));
  EXPECT_EQ(two.vertices.size(), 16u);
  EXPECT_EQ(two.triangles.size(), 24u);
  EXPECT_NEAR(two.volume(), 2.0, 1e-12);
}

TEST(MeshSample3D, SphereAreaVolumeNormalsDepth) {
  const TriangleMesh mesh = load_mesh(write_binary_stl("sphere3d.stl", uv_sphere(kR, 48, 96)));
  // Sagitta of the tessellation: the mesh lies between these radii.
  double r_min = kR;
  for (const auto& t : mesh.triangles) {
    const Point n = face_normal(mesh, t);
    r_min = std::min(r_min, dot(n, mesh.vertices[t[0]]));
  }
  for (const double dx : {0.01, 0.005}) {
    const SampledBody b = sample_mesh(mesh, dx, 0, 3);
    expect_consistent(b, dx, 0);
    const double area_err = rel(b.surface_area, 4 * kPi * kR * kR);
    const double vol_err = rel(b.volume, 4.0 / 3.0 * kPi * kR * kR * kR);
    EXPECT_LT(area_err, 0.01) << "dx " << dx;
    EXPECT_LT(vol_err, 0.01) << "dx " << dx;
    RecordProperty(dx == 0.01 ? "sphere3d_dx0.01" : "sphere3d_dx0.005",
                   "area " + std::to_string(area_err) + " volume " + std::to_string(vol_err) + " (vs the mesh: area " +
                       std::to_string(rel(b.surface_area, mesh.area())) + " volume " +
                       std::to_string(rel(b.volume, mesh.volume())) + ")");
    double worst_angle = 0;
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point& x = b.points[i];
      EXPECT_LT(norm(x), kR);
      const double r = norm(x);
      const double c = dot(b.normals[i], x) / r;
      worst_angle = std::max(worst_angle, std::acos(std::min(1.0, c)) * 180 / kPi);
      const double rs = norm(surface_point(b, i));
      EXPECT_GT(rs, r_min - 0.05 * dx);
      EXPECT_LT(rs, kR + 0.05 * dx);
    }
    EXPECT_LT(worst_angle, 10.0) << "dx " << dx;
  }
}

TEST(MeshSample3D, CylinderAreaVolume) {
  const TriangleMesh mesh = load_mesh(write_obj("cylinder3d.obj", cylinder_mesh(kR, kL, 128)));
  for (const double dx : {0.01, 0.005}) {
    const SampledBody b = sample_mesh(mesh, dx, 0, 3);
    expect_consistent(b, dx, 0);
    const double area_err = rel(b.surface_area, 2 * kPi * kR * kL + 2 * kPi * kR * kR);
    const double vol_err = rel(b.volume, kPi * kR * kR * kL);
    EXPECT_LT(area_err, 0.01) << "dx " << dx;
    EXPECT_LT(vol_err, 0.01) << "dx " << dx;
    RecordProperty(dx == 0.01 ? "cylinder3d_dx0.01" : "cylinder3d_dx0.005",
                   "area " + std::to_string(area_err) + " volume " + std::to_string(vol_err) + " (vs the mesh: area " +
                       std::to_string(rel(b.surface_area, mesh.area())) + " volume " +
                       std::to_string(rel(b.volume, mesh.volume())) + ")");
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point& x = b.points[i];
      // Outward: radial part away from the axis, axial part away from the mid-plane.
      // (1e-9: rounding of the side normals' axial component, the vertices are floats)
      EXPECT_GE(b.normals[i][0] * x[0] + b.normals[i][1] * x[1], -1e-9 * norm(x));
      EXPECT_GE(b.normals[i][2] * x[2], -1e-9 * norm(x));
      const Point s = surface_point(b, i);  // on the side or on a cap
      const double side = std::abs(std::hypot(s[0], s[1]) - kR), cap = std::abs(std::abs(s[2]) - 0.5 * kL);
      EXPECT_LT(std::min(side, cap), 0.05 * dx);
    }
  }
}

TEST(MeshSample2D, SectionsAreCircles) {
  // The sphere's equator is a ring of vertices on z = 0 (a cut through vertices); the cylinder is cut
  // through the middle of its side triangles.
  const TriangleMesh sphere = load_mesh(write_ascii_stl("sphere2d.stl", uv_sphere(kR, 48, 96)));
  const TriangleMesh cyl = load_mesh(write_obj("cylinder2d.obj", cylinder_mesh(kR, kL, 128)));
  for (const TriangleMesh* mesh : {&sphere, &cyl})
    for (const double dx : {0.01, 0.005}) {
      const SampledBody b = sample_mesh(*mesh, dx, 0, 2);
      expect_consistent(b, dx, 0);
      const double per_err = rel(b.surface_area, 2 * kPi * kR), area_err = rel(b.volume, kPi * kR * kR);
      EXPECT_LT(per_err, 0.01) << "dx " << dx;
      EXPECT_LT(area_err, 0.01) << "dx " << dx;
      RecordProperty(std::string(mesh == &sphere ? "sphere2d" : "cylinder2d") + (dx == 0.01 ? "_dx0.01" : "_dx0.005"),
                     "perimeter " + std::to_string(per_err) + " area " + std::to_string(area_err));
      for (std::size_t i = 0; i < b.points.size(); ++i) {
        const Point& x = b.points[i];
        EXPECT_EQ(x[2], 0.0);
        EXPECT_EQ(b.normals[i][2], 0.0);
        EXPECT_GT(dot(b.normals[i], x) / norm(x), std::cos(10 * kPi / 180));  // radial, outward
        EXPECT_NEAR(norm(surface_point(b, i)), kR, 0.001 * kR + 0.05 * dx);     // 96-gon sagitta 5e-4 R
      }
    }
}

TEST(MeshSample3D, ConcavePrismExactVolumeAndDepth) {
  // L-shaped section (2a x 2a minus an a x a quadrant), z in [-hz, hz], with a = 4 dx and hz = 2 dx
  // (binary fractions: exact as the floats assimp reads): every face lies on a lattice plane, so the
  // sampled volume is exact and so is each depth (to rounding).
  const double dx = 1.0 / 64, a = 4 * dx, hz = 2 * dx;
  const std::vector<std::array<double, 2>> L = {{0, 0}, {2 * a, 0}, {2 * a, a}, {a, a}, {a, 2 * a}, {0, 2 * a}};
  const TriangleMesh mesh = load_mesh(write_obj("lprism.obj", prism(L, -hz, hz, 3)));
  EXPECT_LT(rel(mesh.volume(), 3 * a * a * 2 * hz), 1e-12);
  auto dist2d = [&](double x, double y) {  // distance to the L's boundary
    double best = 1e300;
    for (std::size_t i = 0; i < L.size(); ++i) {
      const auto& p = L[i];
      const auto& q = L[(i + 1) % L.size()];
      const double ux = q[0] - p[0], uy = q[1] - p[1];
      const double t = std::clamp(((x - p[0]) * ux + (y - p[1]) * uy) / (ux * ux + uy * uy), 0.0, 1.0);
      best = std::min(best, std::hypot(x - p[0] - t * ux, y - p[1] - t * uy));
    }
    return best;
  };
  // A placement that moves the body off the world lattice changes nothing relative to the body.
  Placement pl;
  pl.translation = {0.1234, -0.0567, 0.0089};
  for (const Placement& where : {Placement{}, pl}) {
    const SampledBody b = sample_mesh(mesh, dx, 0, 3, where);
    expect_consistent(b, dx, 0);
    EXPECT_LT(rel(b.volume, 3 * a * a * 2 * hz), 1e-9);
    EXPECT_EQ(b.points.size(), 3u * 16u * 4u);
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point x = sub(b.points[i], where.translation);
      const double want = std::min(dist2d(x[0], x[1]), hz - std::abs(x[2]));
      EXPECT_NEAR(b.depth[i], want, 1e-9);
      EXPECT_NEAR(b.volumes[i], dx * dx * dx, 1e-9 * dx * dx * dx);
      const Point s = sub(surface_point(b, i), where.translation);
      EXPECT_NEAR(std::min(dist2d(s[0], s[1]), hz - std::abs(s[2])), 0.0, 1e-9);  // on the surface
    }
  }
  // 2D: the L itself, area 3 a^2, perimeter 8 a.
  const SampledBody s = sample_mesh(mesh, dx, 0, 2);
  expect_consistent(s, dx, 0);
  EXPECT_LT(rel(s.volume, 3 * a * a), 1e-9);
  EXPECT_LT(rel(s.surface_area, 8 * a), 1e-9);
  for (std::size_t i = 0; i < s.points.size(); ++i) EXPECT_NEAR(s.depth[i], dist2d(s.points[i][0], s.points[i][1]), 1e-9);
}

TEST(MeshRobustness, LinesThroughVerticesAndEdges) {
  // Octahedron |x| + |y| + |z| <= r with r = 2.5 dx: the lattice line through the centre row passes
  // exactly through two vertices, and the lines in the coordinate planes run along edges. Reference:
  // the analytic inside test and depth (r - |x| - |y| - |z|) / sqrt(3) (1e-12 m); lattice points on
  // the surface itself are skipped. Volume 4/3 r^3 and area 4 sqrt(3) r^2 within 1 %.
  const double dx = 1.0 / 64, r = 2.5 * dx;  // binary fractions: exact as floats
  TriangleMesh oct;
  for (int k = 0; k < 3; ++k)
    for (int sgn : {1, -1}) {
      Point v{0, 0, 0};
      v[k] = sgn * r;
      oct.vertices.push_back(v);  // index 2k (+) and 2k + 1 (-)
    }
  for (int sx : {0, 1})
    for (int sy : {0, 1})
      for (int sz : {0, 1}) {
        const int X = sx, Y = 2 + sy, Z = 4 + sz;
        const bool odd = (sx + sy + sz) % 2 == 1;  // an odd number of minus signs reverses the order
        oct.triangles.push_back(odd ? std::array<int, 3>{X, Z, Y} : std::array<int, 3>{X, Y, Z});
      }
  const TriangleMesh mesh = load_mesh(write_ascii_stl("octahedron.stl", oct));
  for (const int dims : {3, 2}) {
    const SampledBody b = sample_mesh(mesh, dx, 0, dims);
    expect_consistent(b, dx, 0);
    // The lattice: origin at the bounding-box minimum (-r, -r, -r), cell-centred.
    std::size_t inside = 0;
    const int n = 5, nz = dims == 3 ? 5 : 1;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const double x = -r + (i + 0.5) * dx, y = -r + (j + 0.5) * dx, z = dims == 3 ? -r + (k + 0.5) * dx : 0.0;
          const double m = std::abs(x) + std::abs(y) + std::abs(z);
          if (m < r - 1e-12) ++inside;
        }
    std::size_t strictly_inside = 0;
    for (std::size_t i = 0; i < b.points.size(); ++i) {
      const Point& p = b.points[i];
      const double m = std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]);
      EXPECT_LE(m, r + 1e-12);
      if (m > r - 1e-12) continue;  // on the surface: either answer is right
      ++strictly_inside;
      EXPECT_NEAR(b.depth[i], (r - m) / (dims == 3 ? std::sqrt(3.0) : std::sqrt(2.0)), 1e-12);
    }
    EXPECT_EQ(strictly_inside, inside) << "dims " << dims;
    if (dims == 3) {
      EXPECT_LT(rel(b.volume, 4.0 / 3.0 * r * r * r), 0.01);
      EXPECT_LT(rel(b.surface_area, 4 * std::sqrt(3.0) * r * r), 1e-9);
    } else {
      EXPECT_LT(rel(b.volume, 2 * r * r), 0.01);                   // the diamond's area
      EXPECT_LT(rel(b.surface_area, 4 * std::sqrt(2.0) * r), 1e-9);  // and perimeter
    }
  }
}

TEST(MeshLayers, TwoLayersKeepTheShellAndTheSolidVolume) {
  const TriangleMesh mesh = load_mesh(write_binary_stl("sphere_layers.stl", uv_sphere(kR, 48, 96)));
  const double dx = 0.01;
  const SampledBody full = sample_mesh(mesh, dx, 0, 3);
  const SampledBody shell = sample_mesh(mesh, dx, 2, 3);
  expect_consistent(shell, dx, 2);
  EXPECT_LT(shell.points.size(), full.points.size());
  for (std::size_t i = 0; i < shell.points.size(); ++i) {
    EXPECT_LT(shell.depth[i], 2 * dx);
    EXPECT_TRUE(shell.layer[i] == 0 || shell.layer[i] == 1);
  }
  // volume is the whole solid's (1e-12: the same cells summed), surface_area the mesh's.
  EXPECT_NEAR(shell.volume, full.volume, 1e-12 * full.volume);
  EXPECT_NEAR(shell.surface_area, full.surface_area, 1e-12 * full.surface_area);
  // Lattice points: no two closer than dx (brute force).
  double closest = 1e300;
  for (std::size_t i = 0; i < shell.points.size(); ++i)
    for (std::size_t j = i + 1; j < shell.points.size(); ++j) closest = std::min(closest, norm(sub(shell.points[i], shell.points[j])));
  EXPECT_GE(closest, dx * (1 - 1e-9));
  // More layers than the body holds: the whole solid.
  EXPECT_EQ(sample_mesh(mesh, dx, 50, 3).points.size(), full.points.size());
}

TEST(MeshPlacement, ScaledRotatedTranslatedBox) {
  // Box 0.25 x 0.125 x 0.0625 at dx = 1/64 (binary fractions: exact as floats, faces on lattice
  // planes), scaled to 0.5 x 0.25 x 0.125.
  const TriangleMesh mesh = load_mesh(write_ply_box("box_placed.ply", 0.25, 0.125, 0.0625));
  Placement pl;
  pl.scale = 2.0;
  pl.rotation_deg = {0, 0, 90};
  pl.translation = {1.0, -2.0, 0.5};
  const double dx = 1.0 / 64;
  const SampledBody b = sample_mesh(mesh, dx, 0, 3, pl);
  expect_consistent(b, dx, 0);
  EXPECT_LT(rel(b.volume, 0.5 * 0.25 * 0.125), 1e-9);  // abc s^3
  EXPECT_LT(rel(b.surface_area, 2 * (0.5 * 0.25 + 0.25 * 0.125 + 0.125 * 0.5)), 1e-9);
  EXPECT_EQ(b.points.size(), 16u * 32u * 8u);
  // The rotated box: x extent 0.25 (was y), y extent 0.5 (was x), z 0.125; the particles' bounding
  // box is that box shrunk by dx/2.
  const Point half{0.125, 0.25, 0.0625};
  for (int k = 0; k < 3; ++k) {
    double lo = 1e300, hi = -1e300;
    for (const auto& p : b.points) {
      lo = std::min(lo, p[k]);
      hi = std::max(hi, p[k]);
    }
    EXPECT_NEAR(lo, pl.translation[k] - half[k] + 0.5 * dx, 1e-9) << "axis " << k;
    EXPECT_NEAR(hi, pl.translation[k] + half[k] - 0.5 * dx, 1e-9) << "axis " << k;
  }
  // Same volume and area as the primitive box with the same placement.
  const SampledBody prim = turbid::geometry::sample_box({0.25, 0.125, 0.0625}, dx, 0, 3, pl);
  EXPECT_LT(rel(b.volume, prim.volume), 1e-9);
  EXPECT_LT(rel(b.surface_area, prim.surface_area), 1e-9);
  // Normals follow the rotation: the particles next to the rotated +x face (local +y), away from its
  // edges, point along +x, dx/2 deep.
  int on_face = 0;
  for (std::size_t i = 0; i < b.points.size(); ++i) {
    const Point r = sub(b.points[i], pl.translation);
    if (r[0] > half[0] - dx && std::abs(r[1]) < half[1] - dx && std::abs(r[2]) < half[2] - dx) {
      EXPECT_NEAR(b.normals[i][0], 1.0, 1e-9);
      EXPECT_NEAR(b.depth[i], 0.5 * dx, 1e-9);
      ++on_face;
    }
  }
  EXPECT_EQ(on_face, 30 * 6);
}

TEST(MeshErrors, EveryDefectIsNamed) {
  const TriangleMesh sphere = uv_sphere(kR, 16, 32);
  struct Case {
    std::string path, word;
  };
  TriangleMesh open = sphere;
  open.triangles.pop_back();
  // Two boxes sharing the edge x = y = 0.5, z in [-0.5, 0.5]: four triangles on that edge.
  TriangleMesh two = box_mesh(1, 1, 1);
  const TriangleMesh other = box_mesh(1, 1, 1);
  const int base = int(two.vertices.size());
  for (const auto& v : other.vertices) two.vertices.push_back({v[0] + 1, v[1] + 1, v[2]});
  for (const auto& t : other.triangles) two.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  TriangleMesh misoriented = box_mesh(1, 1, 1);
  std::swap(misoriented.triangles[3][1], misoriented.triangles[3][2]);
  {
    std::ofstream(path_of("empty.stl"));  // 0 bytes
    std::ofstream(path_of("garbage.xyz")) << "this is not a mesh\n";
    std::ofstream(path_of("no_faces.obj")) << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  }
  const Case cases[] = {
      {path_of("missing.stl"), "not found"},
      {path_of("empty.stl"), "empty"},
      {path_of("garbage.xyz"), "could not be read"},
      {write_ascii_stl("open.stl", open), "open: 3 boundary edges, e.g. the edge from ("},
      {write_ascii_stl("nonmanifold.stl", two), "non-manifold"},
      {write_obj("misoriented.obj", misoriented), "orientation"},
      {write_binary_stl("inside_out.stl", flipped(sphere)), "inside-out"},
  };
  for (const auto& c : cases) {
    const std::string msg = error_of(c.path);
    EXPECT_NE(msg.find(c.path), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.word), std::string::npos) << msg;
    EXPECT_EQ(msg.back(), '.') << msg;  // a complete sentence
  }
  // A file with vertices but no faces: either assimp refuses it or it has no triangles.
  const std::string nf = error_of(path_of("no_faces.obj"));
  EXPECT_NE(nf.find(path_of("no_faces.obj")), std::string::npos) << nf;
  EXPECT_TRUE(nf.find("empty") != std::string::npos || nf.find("could not be read") != std::string::npos) << nf;
  // The inside-out message says what to do.
  EXPECT_NE(error_of(path_of("inside_out.stl")).find("flip the faces"), std::string::npos);
  // Sampling a mesh built in code checks it too; a 2D cut that misses the mesh is named.
  EXPECT_THROW(sample_mesh(open, 0.01, 0, 3), MeshError);
  Placement away;
  away.translation = {0, 0, 1.0};
  try {
    sample_mesh(sphere, 0.01, 0, 2, away);
    ADD_FAILURE() << "no MeshError for a missed cut";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("does not cut the mesh"), std::string::npos) << e.what();
  }
  EXPECT_THROW(sample_mesh(sphere, 0.0, 0, 3), std::invalid_argument);
  EXPECT_THROW(sample_mesh(sphere, 0.01, 0, 4), std::invalid_argument);
}

}  // namespace
