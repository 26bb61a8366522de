// The debris -> turbidity transition inside a run (fsi::Simulation with a scene's transitions):
// a Bingham debris column collapsing into water in a closed tank (2D, 20 x 20 debris particles),
// splitting at the debris-water interface where sqrt(J2) > 15 Pa (below tau_y = 20 Pa, so yielded
// interface particles qualify). Checked after 60 steps, against conservation laws and the rules:
//  - splits happen, 2^D - 1 = 3 new particles each, none lost (particle count), and they stay at
//    the wet face (fewer than half the column: no cascade through the daughters);
//  - the soil's mass (debris + turbidity) equals the debris mass at the start, 1e-12 relative, in
//    the particles and in the material_mass probes;
//  - every turbidity particle has h = h0/2 and no particle has less (levels: 1);
//  - the time step follows the daughters' h (below the unsplit run's);
//  - two runs write the same bits (determinism of the insertion order);
//  - inside a run (mixed h, walls, water), the split the time loop performs (backend split, then
//    the new grid and forces, as Solver::split does) keeps the fluid's mass, linear momentum,
//    kinetic energy and centre of mass: 1e-12 relative with double accumulation (daughters'
//    m/2^D is exact, velocities are copied; only the order of the sums differs), the centre to the
//    rounding of the float positions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fsi/scene.hpp"
#include "fsi/simulation.hpp"

namespace {

using namespace turbid;

constexpr double kDx = 0.01;

fsi::Scene collapse_scene(bool with_transition) {
  fsi::Scene s;
  s.name = "unit_transition";
  s.dimensions = 2;
  s.particle_spacing = kDx;
  s.smoothing_ratio = 2.0;
  s.gravity = {0, -9.81, 0};
  s.numerics.viscosity = fsi::ViscosityKind::laminar;
  fsi::MaterialSpec water;
  water.name = "water";
  water.density = 1000;
  water.viscosity = 1e-3;
  water.sound_speed = 20;
  fsi::MaterialSpec debris;
  debris.name = "debris";
  debris.model = "bingham";
  debris.density = 1950;
  debris.viscosity = 0.1;
  debris.yield_stress = 20;
  debris.papanastasiou_exponent = 100;
  debris.sound_speed = 20;
  fsi::MaterialSpec turbidity = water;
  turbidity.name = "turbidity";
  turbidity.density = 1950;
  s.materials = {water, debris, turbidity};
  fsi::WallSpec tank;
  tank.box.min = {0, 0, 0};
  tank.box.max = {0.6, 0.3, 0};
  s.walls.push_back(tank);
  fsi::FluidBlock d;
  d.material = "debris";
  d.box.min = {0, 0, 0};
  d.box.max = {0.2, 0.2, 0};
  fsi::FluidBlock w;
  w.material = "water";
  w.box.min = {0.2, 0, 0};
  w.box.max = {0.6, 0.2, 0};
  s.fluids = {d, w};
  for (const char* m : {"debris", "turbidity"}) {
    fsi::ProbeSpec probe;
    probe.name = std::string(m) + "_mass";
    probe.type = fsi::ProbeSpec::Type::material_mass;
    probe.material = m;
    s.probes.push_back(probe);
  }
  if (with_transition) {
    fsi::TransitionSpec t;
    t.from = "debris";
    t.to = "turbidity";
    t.shear_stress_threshold = 15;
    t.interface_only = true;
    s.transitions.push_back(t);
    s.capacity.factor = 3.0;
  }
  return s;
}

struct Soil {
  double mass = 0;
  std::size_t turbidity = 0;
  double h_min = 1e9, turbidity_h_max = 0;
};

Soil soil(fsi::Simulation& sim) {
  sim.sync_to_host();
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const auto* m = st.data<float>(ids.mass);
  const auto* h = st.data<float>(ids.smoothing_length);
  const auto* mat = st.data<std::uint8_t>(ids.material);
  const auto* kind = st.data<std::uint8_t>(ids.kind);
  Soil s;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    s.h_min = std::min(s.h_min, double(h[i]));
    if (mat[i] == 0) continue;
    s.mass += m[i];
    if (mat[i] == 2) {
      ++s.turbidity;
      s.turbidity_h_max = std::max(s.turbidity_h_max, double(h[i]));
    }
  }
  return s;
}

TEST(Transition, CollapsingDebrisSplitsAtTheInterfaceConservingSoilMass) {
  fsi::Simulation sim(collapse_scene(true), {"cpu", 1});
  fsi::Simulation plain(collapse_scene(false), {"cpu", 1});
  sim.start();
  plain.start();
  const std::size_t n0 = sim.store().size();
  const Soil before = soil(sim);
  const std::vector<double> probes0 = sim.probe_values();  // debris_mass, turbidity_mass [kg/m]
  ASSERT_EQ(before.turbidity, 0u);
  EXPECT_EQ(sim.store().capacity(), std::size_t(std::ceil(3.0 * double(n0)))) << "capacity: factor 3";
  for (int k = 0; k < 60; ++k) {
    sim.step();
    plain.step();
  }
  const Soil after = soil(sim);
  const auto& c = sim.split_totals();
  ASSERT_GT(c.splits, 0u) << "the interface must have yielded within 60 steps";
  // `where: interface` looks for the water only (a third material), so the daughters do not turn
  // their debris neighbours into interface particles: the column erodes from its wet face (61 of
  // 400 in 60 steps, measured) instead of splitting whole (400 when turbidity counted as well).
  EXPECT_LT(c.splits, 200u) << "no cascade through the column";
  EXPECT_EQ(c.daughters, 3 * c.splits);
  EXPECT_EQ(c.refused, 0u);
  EXPECT_EQ(sim.removed(), 0u);
  EXPECT_EQ(sim.store().size(), n0 + c.daughters) << "particles: start + daughters";
  EXPECT_EQ(after.turbidity, 4 * c.splits) << "every daughter is turbidity";
  EXPECT_NEAR(after.mass, before.mass, 1e-12 * before.mass) << "soil mass (debris + turbidity)";
  const std::vector<double> probes = sim.probe_values();
  EXPECT_EQ(probes0[1], 0.0) << "no turbidity at the start (material_mass probe)";
  EXPECT_NEAR(probes0[0], before.mass, 1e-12 * before.mass) << "debris probe = debris mass at the start";
  EXPECT_NEAR(probes[0] + probes[1], before.mass, 1e-12 * before.mass) << "material_mass probes: soil mass kept";
  EXPECT_GT(probes[1], 0.0) << "turbidity has mass once particles split";
  const double h0 = 2.0 * kDx;
  EXPECT_FLOAT_EQ(float(after.turbidity_h_max), float(0.5 * h0)) << "daughters have h0/2";
  EXPECT_FLOAT_EQ(float(after.h_min), float(0.5 * h0)) << "one level: no particle below h0/2";
  EXPECT_LT(sim.last_time_step(), 0.75 * plain.last_time_step()) << "dt follows the smallest h";
  std::printf("transition: %zu splits in 60 steps, dt %.3g s (without: %.3g s)\n", c.splits, sim.last_time_step(),
              plain.last_time_step());
}

TEST(Transition, TwoRunsWriteTheSameBits) {
  fsi::Simulation a(collapse_scene(true), {"cpu", 2});
  fsi::Simulation b(collapse_scene(true), {"cpu", 2});
  a.start();
  b.start();
  for (int k = 0; k < 40; ++k) {
    a.step();
    b.step();
  }
  ASSERT_GT(a.split_totals().splits, 0u);
  ASSERT_EQ(a.store().size(), b.store().size());
  for (int f = 0; f < a.store().field_count(); ++f)
    EXPECT_EQ(std::memcmp(a.store().raw(f), b.store().raw(f), a.store().size() * a.store().field_bytes(f)), 0)
        << a.store().desc(f).name;
}

// Totals of the fluid in double, index order: mass [kg/m], momentum [kg m/s per m], kinetic
// energy [J/m], mass-weighted position [kg]; scales for the tolerances.
struct Totals {
  double mass = 0, px = 0, py = 0, energy = 0, mx = 0, my = 0;
  double momentum_scale = 0, max_coordinate = 0;
  std::size_t fluid = 0;
};

Totals totals(fsi::Simulation& sim) {
  sim.sync_to_host();
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const auto* m = st.data<float>(ids.mass);
  const auto* v = st.data<float>(ids.velocity);
  const auto* x = st.data<float>(ids.position);
  const auto* kind = st.data<std::uint8_t>(ids.kind);
  Totals t;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    ++t.fluid;
    const double mi = m[i], vx = v[2 * i], vy = v[2 * i + 1];
    t.mass += mi;
    t.px += mi * vx;
    t.py += mi * vy;
    t.energy += 0.5 * mi * (vx * vx + vy * vy);
    t.mx += mi * x[2 * i];
    t.my += mi * x[2 * i + 1];
    t.momentum_scale += mi * std::hypot(vx, vy);
    t.max_coordinate = std::max({t.max_coordinate, std::fabs(double(x[2 * i])), std::fabs(double(x[2 * i + 1]))});
  }
  return t;
}

TEST(Transition, SplitInsideARunConservesMassMomentumEnergyAndCentre) {
  const fsi::Scene scene = collapse_scene(true);
  fsi::Simulation sim(scene, {"cpu", 1});
  sim.start();
  for (int k = 0; k < 30; ++k) sim.step();
  ASSERT_GT(sim.split_totals().splits, 0u) << "daughters (h/2) already in the flow";
  // Every debris particle left qualifies now (threshold below zero, anywhere): a large split of a
  // moving, mixed-h state next to walls and water.
  sph::SplitParams rules = fsi::split_params(scene);
  rules.rules[0].threshold = -1;
  rules.rules[0].interface_only = false;
  const Totals before = totals(sim);
  const sph::SplitCounts c = sim.backend().split(rules);
  EXPECT_EQ(sim.backend().update_neighbours(), 0u) << "no particle lost";
  sim.backend().compute_forces();
  const Totals after = totals(sim);
  ASSERT_GT(c.splits, 100u);
  EXPECT_EQ(c.refused, 0u);
  EXPECT_EQ(after.fluid, before.fluid + 3 * c.splits);
  const double rel = 1e-12;
  EXPECT_NEAR(after.mass, before.mass, rel * before.mass) << "mass";
  EXPECT_NEAR(after.px, before.px, rel * before.momentum_scale) << "momentum x";
  EXPECT_NEAR(after.py, before.py, rel * before.momentum_scale) << "momentum y";
  EXPECT_NEAR(after.energy, before.energy, rel * before.energy) << "kinetic energy";
  // Daughters sit symmetrically about their mother, at float positions: half an ulp of the
  // largest coordinate each, times the mass.
  const double ulp = std::ldexp(before.max_coordinate, -23);
  EXPECT_NEAR(after.mx, before.mx, 0.5 * ulp * before.mass) << "centre of mass x";
  EXPECT_NEAR(after.my, before.my, 0.5 * ulp * before.mass) << "centre of mass y";
  std::printf("split in a run: %zu mothers; momentum (%.6g, %.6g) -> change (%.3g, %.3g) kg m/s per m, "
              "energy change %.3g relative\n",
              c.splits, before.px, before.py, after.px - before.px, after.py - before.py,
              (after.energy - before.energy) / before.energy);
}

}  // namespace
