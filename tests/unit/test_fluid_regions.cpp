// Fluid regions and the initial state of several materials (fsi/simulation.cpp): polygon blocks,
// "earlier blocks win" where regions overlap, the layered hydrostatic start, and their 3D form:
// polygons and polyline walls given as x-z cross-sections extruded across y over a span.
// References: lattice counting (a block of area A holds A / dx^2 particles, to the points the
// boundary cuts; an extrusion of width W holds A W / dx^3), and two-layer hydrostatics
// p = sum rho_k g (thickness of layer k above).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>

#include "fsi/simulation.hpp"

namespace {

using namespace turbid;

constexpr double kDx = 0.01;

fsi::Scene slide_in_water() {
  fsi::Scene s;
  s.name = "slide";
  s.dimensions = 2;
  s.particle_spacing = kDx;
  s.gravity = {0, -9.81, 0};
  for (auto [name, rho] : {std::pair<const char*, double>{"slide", 1950.0}, {"water", 1000.0}}) {
    fsi::MaterialSpec m;
    m.name = name;
    m.density = rho;
    m.sound_speed = 30;
    s.materials.push_back(m);
  }
  // A right triangle with legs 0.4 m (vertices on lattice lines), listed first, inside a water box.
  fsi::FluidBlock slide;
  slide.material = "slide";
  slide.polygon = {{0.2, 0.6, 0}, {0.6, 0.6, 0}, {0.6, 0.2, 0}};
  slide.box = {{0.2, 0.2, 0}, {0.6, 0.6, 0}};
  fsi::FluidBlock water;
  water.material = "water";
  water.box = {{0, 0, 0}, {1, 1, 0}};
  s.fluids = {slide, water};
  return s;
}

TEST(FluidRegions, PolygonBlockCutOutOfTheWaterAroundIt) {
  fsi::Simulation sim(slide_in_water(), {"cpu", 1});
  const auto& per = sim.summary().particles_per_material;
  // Lattice points strictly inside the triangle: 40 * 39 / 2 = 780 (the diagonal's cells are cut in
  // half), against area / dx^2 = 800; within 3%.
  EXPECT_NEAR(double(per[0]), 0.08 / (kDx * kDx), 0.03 * 800) << "slide particles against area / dx^2";
  // No double particles where the regions overlap: the box holds exactly its lattice.
  EXPECT_EQ(per[0] + per[1], std::size_t(10000)) << "earlier block wins; every lattice point once";
}

// Water particles of the column x = 0.505 below the slide (height <= 0.2 m along the vertical,
// the last axis): each must start at the density of the weight of all fluid above it, water up to
// the slide's hypotenuse (height 0.8 - x), the slide up to 0.6 m, water again up to 1 m; dx / 8
// integration steps put it within rho g dx / 8 of that weight. Returns how many were checked.
int check_weight_above_column(const fsi::Simulation& sim) {
  const int d = sim.scene().dimensions;
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* rho = st.data<float>(sim.fields().density);
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  const auto* mat = st.data<std::uint8_t>(sim.fields().material);
  const auto& eos_water = sim.params().materials[1].eos;
  int checked = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0 || mat[i] != 1) continue;
    const double px = x[std::size_t(d) * i], height = x[std::size_t(d) * i + std::size_t(d - 1)];
    if (std::abs(px - 0.505) > 1e-4 || height > 0.2) continue;
    const double slide_bottom = 0.8 - px;
    const double slide_thickness = 0.6 - slide_bottom;
    const double water_thickness = (1.0 - height) - slide_thickness;
    const double p = 9.81 * (1000.0 * water_thickness + 1950.0 * slide_thickness);
    EXPECT_NEAR(rho[i], eos_water.density_at_gauge(p),
                (1950.0 * 9.81 * kDx / 8) / (double(eos_water.stiffness) * 7) * 1000.0 + 1e-3)
        << "water particle at height " << height;
    ++checked;
  }
  return checked;
}

TEST(FluidRegions, LayeredStartCarriesTheWeightOfAllFluidAbove) {
  fsi::Simulation sim(slide_in_water(), {"cpu", 1});
  EXPECT_EQ(check_weight_above_column(sim), 20) << "the column below the slide";
}

// The slide-in-water scene of the 2D tests, extruded: the same x-z cross-section (the triangle in the
// x-z plane, the water box 1 m x 1 m) across y from 0 to `width`, gravity along -z.
fsi::Scene slide_in_water_3d(double width) {
  fsi::Scene s = slide_in_water();
  s.dimensions = 3;
  s.gravity = {0, 0, -9.81};
  s.fluids[0].span = {0, width};
  s.fluids[0].box = {{0.2, 0, 0.2}, {0.6, width, 0.6}};  // the reader's bounding box: y from the span
  s.fluids[1].box = {{0, 0, 0}, {1, width, 1}};
  return s;
}

TEST(FluidRegions, ExtrudedPolygonBlockHoldsTheSectionOnEveryRowAcrossItsSpan) {
  constexpr double kWidth = 0.05;  // 5 rows of dx = 0.01
  const fsi::Simulation flat(slide_in_water(), {"cpu", 1});
  const fsi::Simulation sim(slide_in_water_3d(kWidth), {"cpu", 1});
  const auto& per = sim.summary().particles_per_material;
  // Reference: area x width / dx^3 = 0.08 x 0.05 / 1e-6 = 4000 for the triangle; the cells its
  // hypotenuse cuts in half are lost as in 2D (780 of 800 per row), so within 3%.
  EXPECT_NEAR(double(per[0]), 0.08 * kWidth / std::pow(kDx, 3), 0.03 * 4000) << "slide particles against A W / dx^3";
  // The fluid volume the particles stand for (dx^3 each on the lattice) against A W, same 3%.
  EXPECT_NEAR(double(per[0]) * std::pow(kDx, 3), 0.08 * kWidth, 0.03 * 0.08 * kWidth) << "slide volume [m^3]";
  // The extrusion repeats the 2D section exactly: 5 rows of the 2D block's lattice points, and the
  // water box's lattice holds every point once (earlier block wins in 3D too).
  EXPECT_EQ(per[0], 5 * flat.summary().particles_per_material[0]) << "2D section times the rows across y";
  EXPECT_EQ(per[0] + per[1], std::size_t(100 * 5 * 100)) << "every lattice point of the 1 x 0.05 x 1 m box once";
  // The rows across y are the box's lattice: y = (k + 1/2) dx, k = 0..4.
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* mat = st.data<std::uint8_t>(sim.fields().material);
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  std::set<long> rows;
  for (std::size_t i = 0; i < st.size(); ++i)
    if (kind[i] == 0 && mat[i] == 0) {
      const double y = x[3 * i + 1];
      const long k = std::lround(y / kDx - 0.5);
      EXPECT_NEAR(y, (double(k) + 0.5) * kDx, 1e-6) << "a slide particle off the y rows (float rounding 1e-6 m)";
      rows.insert(k);
    }
  EXPECT_EQ(rows, (std::set<long>{0, 1, 2, 3, 4}));
}

TEST(FluidRegions, ExtrudedLayeredStartCarriesTheWeightOfAllFluidAbove) {
  // The 2D layered-start test in 3D: the height axis is z (gravity's), the layers those of the
  // extruded section, so every row across y has the 2D column's densities.
  fsi::Simulation sim(slide_in_water_3d(0.05), {"cpu", 1});
  EXPECT_EQ(check_weight_above_column(sim), 20 * 5) << "the column below the slide on each of the 5 rows";
}

TEST(FluidRegions, ExtrudedPolylineWallRepeatsItsLayersAcrossTheSpan) {
  // A 45-degree slope z = 0.5 - x from (0, 0.5) to (0.5, 0) in the x-z plane, layers below it
  // (side right), across y from 0 to 0.15, mDBC so that the ghost offsets are stored.
  constexpr double kWidth = 0.15;
  fsi::Scene s;
  s.name = "slope";
  s.dimensions = 3;
  s.particle_spacing = kDx;
  s.gravity = {0, 0, -9.81};
  s.numerics.boundary = fsi::BoundaryKind::mdbc;
  fsi::MaterialSpec water;
  water.name = "water";
  water.sound_speed = 30;
  s.materials = {water};
  fsi::FluidBlock block;  // a little water above the slope, so that the scene has fluid
  block.material = "water";
  block.box = {{0.3, 0, 0.3}, {0.5, kWidth, 0.5}};
  s.fluids = {block};
  fsi::WallSpec slope;
  slope.kind = fsi::WallSpec::Kind::polyline;
  slope.points = {{0, 0.5, 0}, {0.5, 0, 0}};  // (x, z)
  slope.side = -1;
  slope.span = {0, kWidth};
  s.walls = {slope};
  const fsi::Simulation sim(s, {"cpu", 1});
  const int layers = fsi::wall_layers(s, slope);
  const double length = 0.5 * std::sqrt(2.0);
  // Reference: the wall band's volume length x layers dx x width over dx^3 (0.7071 x 0.04 x 0.15 /
  // 1e-6 = 4243 for 4 layers); the segment holds a whole number of spacings (71 of 0.00996 m), so
  // within dx / 2 of its length: 0.5 / 70.7 = 0.7%, asserted to 1%.
  const double expected = length * layers * kDx * kWidth / std::pow(kDx, 3);
  EXPECT_NEAR(double(sim.summary().wall_particles), expected, 0.01 * expected) << layers << " layers";
  // Every wall particle: on a y row of the span's lattice, below the slope at (l + 1/2) dx, and its
  // mDBC ghost mirrors it across the slope in the x-z plane (offset normal to the slope, no y part).
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* g = static_cast<const float*>(st.raw(sim.fields().boundary_normal));
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  std::set<long> rows;
  std::size_t walls = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != std::uint8_t(sph::Kind::wall)) continue;
    ++walls;
    const double px = x[3 * i], py = x[3 * i + 1], pz = x[3 * i + 2];
    const long k = std::lround(py / kDx - 0.5);
    rows.insert(k);
    ASSERT_NEAR(py, (double(k) + 0.5) * kDx, 1e-6) << "y rows at (k + 1/2) dx (float rounding 1e-6 m)";
    const double below = (0.5 - px - pz) / std::sqrt(2.0);  // distance below the slope line
    const long layer = std::lround(below / kDx - 0.5);
    ASSERT_NEAR(below, (double(layer) + 0.5) * kDx, 1e-6) << "layers at (l + 1/2) dx below the slope";
    ASSERT_EQ(g[3 * i + 1], 0.0f) << "the ghost offset has no y component";
    // Ghost offset 2 x distance along the slope's upward normal (1, 1) / sqrt(2), to float rounding.
    ASSERT_NEAR(g[3 * i], 2 * below / std::sqrt(2.0), 1e-6);
    ASSERT_NEAR(g[3 * i + 2], 2 * below / std::sqrt(2.0), 1e-6);
  }
  EXPECT_EQ(walls, sim.summary().wall_particles);
  EXPECT_EQ(rows.size(), std::size_t(15)) << "0.15 m / dx rows across y";
}

}  // namespace
