// Fluid regions and the initial state of several materials (fsi/simulation.cpp): polygon blocks,
// "earlier blocks win" where regions overlap, and the layered hydrostatic start.
// References: lattice counting (a block of area A holds A / dx^2 particles, to the points the
// boundary cuts), and two-layer hydrostatics p = sum rho_k g (thickness of layer k above).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

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

TEST(FluidRegions, LayeredStartCarriesTheWeightOfAllFluidAbove) {
  fsi::Simulation sim(slide_in_water(), {"cpu", 1});
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* rho = st.data<float>(sim.fields().density);
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  const auto* mat = st.data<std::uint8_t>(sim.fields().material);
  const auto& eos_water = sim.params().materials[1].eos;
  int checked = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0 || mat[i] != 1) continue;
    const double px = x[2 * i], py = x[2 * i + 1];
    if (std::abs(px - 0.505) > 1e-4 || py > 0.2) continue;  // water under the slide, column x = 0.505
    // Above it: water up to the slide's hypotenuse y = 0.8 - x (from (0.2, 0.6) to (0.6, 0.2)), the
    // slide up to y = 0.6, water again up to y = 1.
    const double slide_bottom = 0.8 - px;
    const double slide_thickness = 0.6 - slide_bottom;
    const double water_thickness = (1.0 - py) - slide_thickness;
    const double p = 9.81 * (1000.0 * water_thickness + 1950.0 * slide_thickness);
    const double expected = eos_water.density_at_gauge(p);
    // dx / 8 integration steps: within rho g dx / 8 of the exact weight.
    EXPECT_NEAR(rho[i], expected, (1950.0 * 9.81 * kDx / 8) / (double(eos_water.stiffness) * 7) * 1000.0 + 1e-3)
        << "water particle at y = " << py;
    ++checked;
  }
  EXPECT_EQ(checked, 20) << "the column below the slide";
}

}  // namespace
