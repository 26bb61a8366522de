// Hard case of the materials issue (docs/validation.md, H2): a dense Herschel-Bulkley column
// (1800 kg/m^3, tau_y = 50 Pa) collapses into still water in a closed tank
// (scenes/wet_dam_break_hb_2d.yaml). No reference solution; what must hold (conservation and
// robustness):
//   - the run reaches its end time with no blow-up (the engine stops at a NaN or a density more than
//     50% off its rest value, naming the particle);
//   - every material keeps its particle count exactly and its mass to rounding (relative 1e-12 in
//     the double sum of float masses: nothing is created or removed);
//   - the walls hold the fluid by their pressure (issue #47 item 2): with DBC walls the
//     impermeable-wall pass puts fluid back on a surface in fewer than 1e-5 of the fluid
//     particle-steps (the goal; measured 0). With mDBC walls that rate is printed, not
//     asserted: 9.5e-6 measured (2026-12-07), at the goal's edge in a chaotic surge; a water film
//     running up a wall has dry ghost nodes, whose walls take rest density and do not repel it.
//     How far fluid centres lie beyond the interior is printed too: with the pass on it is within
//     the first wall layer's half cell by construction (before the pass the mDBC film reached
//     0.78 dx, 2026-12-03).
// Quick mode (CI): dx = 0.01 m (1800 fluid particles, about a minute on one core); full mode
// (TURBID_FULL=1): the scene's dx = 0.005 m. Measured at 0.01 m: completed, 0 removed, debris
// front at 0.88 m at t = 1.5 s.
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "tests/validation/validation_support.hpp"
#include "tools/scene_reader.hpp"

namespace {

using turbid::fsi::Scene;
using turbid::fsi::Simulation;

struct Totals {
  std::vector<std::size_t> count;
  std::vector<double> mass;
};

Totals totals(const Simulation& sim) {
  const auto& st = sim.store();
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  const auto* mat = st.data<std::uint8_t>(sim.fields().material);
  const auto* m = st.data<float>(sim.fields().mass);
  Totals t{std::vector<std::size_t>(sim.scene().materials.size(), 0), std::vector<double>(sim.scene().materials.size(), 0)};
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    ++t.count[mat[i]];
    t.mass[mat[i]] += m[i];
  }
  return t;
}

}  // namespace

static void check_wet_dam_break(turbid::fsi::BoundaryKind boundary) {
  Scene s = turbid::tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/wet_dam_break_hb_2d.yaml");
  if (!turbid::validation::full_mode()) s.particle_spacing = 0.01;
  s.numerics.boundary = boundary;
  // mDBC with the velocity the docs pair with laminar viscosity: no-slip (docs/choices.md, "Walls").
  s.numerics.no_slip = boundary == turbid::fsi::BoundaryKind::mdbc;
  s.output.vtk = false;
  const double dx = s.particle_spacing;
  const auto& tank = s.walls.at(0).box;
  Simulation sim(s, {"cpu", 0});
  sim.start();
  const Totals start = totals(sim);
  ASSERT_EQ(start.count.size(), 2u);
  ASSERT_GT(start.count[0], 0u);
  ASSERT_GT(start.count[1], 0u);
  double deepest = 0;  // the largest distance of a fluid centre beyond the interior [dx]
  double next_check = 0;
  while (sim.time() < s.end_time - 1e-12) {
    ASSERT_NO_THROW(sim.step()) << "blow-up at t = " << sim.time() << " s";
    if (sim.time() < next_check) continue;
    next_check += s.output.every;
    const auto& st = sim.store();
    const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (kind[i] != 0) continue;
      for (int k = 0; k < 2; ++k) {
        const double beyond = std::max(tank.min[k] - x[2 * i + k], x[2 * i + k] - tank.max[k]) / dx;
        deepest = std::max(deepest, beyond);
      }
    }
  }
  const double put_backs = double(sim.wall_put_backs()) / double(sim.fluid_particle_steps());
  std::printf("[ measured ] wall pass: %llu put-backs, %.3g per fluid particle-step\n",
              static_cast<unsigned long long>(sim.wall_put_backs()), put_backs);
  const Totals end = totals(sim);
  for (std::size_t m = 0; m < 2; ++m) {
    EXPECT_EQ(end.count[m], start.count[m]) << "particles of material " << s.materials[m].name;
    EXPECT_NEAR(end.mass[m], start.mass[m], 1e-12 * start.mass[m]) << "mass of material " << s.materials[m].name;
  }
  EXPECT_EQ(sim.removed(), 0u);
  if (boundary == turbid::fsi::BoundaryKind::dbc)
    EXPECT_LT(put_backs, 1e-5) << "the walls let fluid through; the wall pass caught it";
  std::printf("wet dam break, %s walls, dx = %g m: t = %.3f s, %llu steps, debris front %.3f m, deepest fluid "
              "centre %.2f dx beyond the interior\n",
              boundary == turbid::fsi::BoundaryKind::mdbc ? "mDBC" : "DBC", dx, sim.time(),
              static_cast<unsigned long long>(sim.steps()), sim.probe_values()[0], deepest);
}

TEST(ValidationWetDamBreak, HerschelBulkleyColumnIntoWaterConservesAndStaysInside) {
  check_wet_dam_break(turbid::fsi::BoundaryKind::dbc);
}

// The same with no-slip mDBC walls and the same bounds (issue #20 item 3): the walls' ghost nodes
// extrapolate the debris' pressure (before: its density read as water's at 1.8 rho0_w, a blow-up).
// Measured at dx = 0.01 m: no fluid centre more than 0.39 dx behind a wall surface. With mDBC's
// default wall velocity (free slip for the viscous terms) one film particle running down the left
// wall reached 0.53 dx behind it at t = 1.45 s: mDBC has no repulsion for a film whose ghost nodes
// are dry (issue #27 item 9, fluid behind walls).
TEST(ValidationWetDamBreak, HerschelBulkleyColumnIntoWaterWithMdbcWalls) {
  check_wet_dam_break(turbid::fsi::BoundaryKind::mdbc);
}
