// Free-slip walls (`walls: - {box: ..., slip: free}`): a Bingham block sliding at a uniform speed
// along the floor of a tank, without gravity, at rest density (no pressure anywhere). Reference:
// a uniform flow along a free-slip wall carries no shear, so every fluid particle's shear rate and
// acceleration are zero, exactly (the difference-form gradient and the viscous pair terms vanish
// for equal velocities, and the wall is left out of both). Along a no-slip wall the same block is
// sheared: its first row sees a shear rate and decelerates. The same with the implicit viscous update
// (sph/implicit_viscosity.hpp), whose effect shows in the velocities after a step, not in the
// acceleration: along the free-slip wall they stay at 0.1 m/s to float rounding (the update sums
// s_ij (x_i - x_j) of a solution x that is uniform to the solver's tolerance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <vector>

#include "fsi/scene.hpp"
#include "fsi/simulation.hpp"

namespace {

using namespace turbid;

fsi::Scene sliding_block(bool free_slip,
                         fsi::ViscousIntegration integration = fsi::ViscousIntegration::explicit_,
                         fsi::ViscousStress stress = fsi::ViscousStress::laplacian,
                         fsi::BoundaryKind boundary = fsi::BoundaryKind::dbc, std::optional<bool> no_slip = {}) {
  fsi::Scene s;
  s.numerics.boundary = boundary;
  s.numerics.no_slip = no_slip;
  s.name = "unit_free_slip";
  s.dimensions = 2;
  s.particle_spacing = 0.01;
  s.smoothing_ratio = 2.0;
  s.gravity = {0, 0, 0};
  s.numerics.viscosity = fsi::ViscosityKind::laminar;
  s.numerics.viscous_integration = integration;
  s.numerics.viscous_stress = stress;
  fsi::MaterialSpec mud;
  mud.name = "mud";
  mud.model = "bingham";
  mud.density = 1500;
  mud.viscosity = 1.0;
  mud.yield_stress = 10;
  mud.papanastasiou_exponent = 100;
  mud.sound_speed = 10;
  s.materials = {mud};
  fsi::WallSpec tank;
  tank.box.min = {0, 0, 0};
  tank.box.max = {1.0, 0.3, 0};
  tank.open = {false, false, false, true, false, false};
  tank.free_slip = free_slip;
  s.walls.push_back(tank);
  fsi::FluidBlock b;
  b.material = "mud";
  b.box.min = {0.3, 0, 0};
  b.box.max = {0.6, 0.1, 0};
  b.initial_velocity.given = true;
  b.initial_velocity.axis = 0;
  b.initial_velocity.mean = 0.1;  // [m/s], uniform
  s.fluids = {b};
  return s;
}

struct FirstRow {
  double max_abs_rate = 0, max_abs_ax = 0;  // over all fluid particles
  double max_row_ax = -1e9;                 // largest (least negative) a_x of the row next to the floor
  double min_row_rate = 1e9;
  int row = 0;
};

FirstRow measure(bool free_slip, fsi::BoundaryKind boundary = fsi::BoundaryKind::dbc,
                 std::optional<bool> no_slip = {}) {
  fsi::Simulation sim(
      sliding_block(free_slip, fsi::ViscousIntegration::explicit_, fsi::ViscousStress::laplacian, boundary, no_slip),
      {"cpu", 1});
  sim.start();
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const auto* x = static_cast<const float*>(st.raw(ids.position));
  const auto* a = static_cast<const float*>(st.raw(ids.acceleration));
  const auto* rate = st.data<float>(ids.shear_rate);
  const auto* kind = st.data<std::uint8_t>(ids.kind);
  FirstRow r;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    r.max_abs_rate = std::max(r.max_abs_rate, double(std::abs(rate[i])));
    r.max_abs_ax = std::max(r.max_abs_ax, double(std::abs(a[2 * i])));
    // The first row (y = dx/2), away from the block's ends (their truncated support).
    if (x[2 * i + 1] < 0.01f && x[2 * i] > 0.35f && x[2 * i] < 0.55f) {
      r.max_row_ax = std::max(r.max_row_ax, double(a[2 * i]));
      r.min_row_rate = std::min(r.min_row_rate, double(rate[i]));
      ++r.row;
    }
  }
  return r;
}

TEST(FreeSlipWalls, UniformFlowAlongAFreeSlipWallIsNotSheared) {
  const FirstRow r = measure(true);
  ASSERT_GT(r.row, 10);
  EXPECT_EQ(r.max_abs_rate, 0.0) << "shear rate of every fluid particle [1/s]";
  EXPECT_EQ(r.max_abs_ax, 0.0) << "acceleration along the wall of every fluid particle [m/s^2]";
}

TEST(FreeSlipWalls, NoSlipWallShearsTheSameFlow) {
  const FirstRow r = measure(false);
  ASSERT_GT(r.row, 10);
  // The wall holds 0 m/s a spacing below a row moving at 0.1 m/s: the kernel-smoothed rate is of
  // the order of 0.1 / (2 h) = 2.5 1/s; every first-row particle sees more than a tenth of that
  // and decelerates.
  EXPECT_GT(r.min_row_rate, 0.25) << "first-row shear rate [1/s]";
  EXPECT_LT(r.max_row_ax, 0.0) << "first-row acceleration along the wall [m/s^2]";
}

// The same with every wall treatment: DBC and mDBC, each with walls at their own velocity and with
// the no-slip mirror 2 v_wall - v~_g at the ghost node (`velocity: no_slip`), which a free-slip
// wall does not take (sph/boundary_passes.hpp MdbcPass). mDBC walls extrapolate the block's
// density (rest density here), so the pressure terms are not exactly zero there: the bound on the
// acceleration along the wall is then float rounding of p/rho with p = B ((rho/rho0)^7 - 1) at
// |rho/rho0 - 1| ~ 1e-6, i.e. 7e-6 x B / rho0 / (2 h) = 7e-6 x 100 / 0.04 ~ 2e-2 m/s^2 at most,
// against the no-slip wall's deceleration of the first row (order 1 m/s^2, asserted below).
TEST(FreeSlipWalls, EveryWallTreatmentLeavesAFreeSlipWallUnsheared) {
  struct Case {
    fsi::BoundaryKind boundary;
    bool no_slip;
    const char* name;
  };
  for (const Case c : {Case{fsi::BoundaryKind::dbc, false, "DBC, velocity: wall"},
                       Case{fsi::BoundaryKind::dbc, true, "DBC, velocity: no_slip"},
                       Case{fsi::BoundaryKind::mdbc, false, "mDBC, velocity: wall"},
                       Case{fsi::BoundaryKind::mdbc, true, "mDBC, velocity: no_slip"}}) {
    const FirstRow f = measure(true, c.boundary, c.no_slip);
    const FirstRow n = measure(false, c.boundary, c.no_slip);
    ASSERT_GT(f.row, 10) << c.name;
    std::printf("[ measured ] %s: free slip largest |shear rate| %.2e 1/s, |a_x| %.2e m/s^2; no-slip first row "
                "smallest shear rate %.3f 1/s, largest a_x %.3e m/s^2\n",
                c.name, f.max_abs_rate, f.max_abs_ax, n.min_row_rate, n.max_row_ax);
    EXPECT_EQ(f.max_abs_rate, 0.0) << c.name << ": shear rate of every fluid particle [1/s]";
    EXPECT_LT(f.max_abs_ax, 2e-2) << c.name << ": acceleration along the wall of every fluid particle [m/s^2]";
    EXPECT_GT(n.min_row_rate, 0.25) << c.name << ": first-row shear rate along a no-slip wall [1/s]";
    EXPECT_LT(n.max_row_ax, -10 * f.max_abs_ax) << c.name << ": first-row acceleration along a no-slip wall [m/s^2]";
  }
}

// x velocities of the block's particles (by id) after one step, and the ids of its first row.
struct AfterStep {
  std::vector<double> vx;  // by particle id
  std::vector<std::uint32_t> row;
};

AfterStep one_step(bool free_slip, fsi::ViscousIntegration integration,
                   fsi::ViscousStress stress = fsi::ViscousStress::laplacian) {
  fsi::Scene scene = sliding_block(free_slip, integration, stress);
  // A cap of 5 Pa s keeps the explicit viscous limit (0.015 s) above the acoustic one (4e-4 s):
  // both runs take the same dt.
  scene.materials[0].max_viscosity = 5;
  fsi::Simulation sim(scene, {"cpu", 1});
  EXPECT_EQ(sim.params().implicit_viscosity, integration == fsi::ViscousIntegration::implicit);
  sim.start();
  sim.step();
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* v = static_cast<const float*>(st.raw(sim.fields().velocity));
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  const auto* id = st.data<std::uint32_t>(sim.fields().id);
  AfterStep r;
  r.vx.assign(st.size(), 0.0);
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    r.vx[id[i]] = v[2 * i];
    if (x[2 * i + 1] < 0.01f && x[2 * i] > 0.35f && x[2 * i] < 0.55f) r.row.push_back(id[i]);
  }
  return r;
}

// Along a free-slip wall the wall shears nothing: after one step the implicit run's velocities are
// the explicit run's (whose viscous terms vanish exactly for the uniform start) but for the viscous
// smoothing, over the step's second half, of what the step's pressure kick made non-uniform: at
// most dt nu / h^2 (3e-3 here) of that deviation, plus float rounding (0.1 m/s x 2^-23 = 1.2e-8).
// A wall that sheared would slow the first row by about 5e-4 m/s (next test).
// The same for the full stress (sph/full_stress.hpp: a free-slip wall is not in the gradient's
// neighbourhood, which the renormalisation makes exact for the uniform flow).
TEST(FreeSlipWalls, ImplicitViscosityLeavesFlowAlongAFreeSlipWallUnsheared) {
  for (auto stress : {fsi::ViscousStress::laplacian, fsi::ViscousStress::full}) {
    const AfterStep e = one_step(true, fsi::ViscousIntegration::explicit_);
    const AfterStep i = one_step(true, fsi::ViscousIntegration::implicit, stress);
    ASSERT_GT(e.row.size(), 10u);
    double worst = 0, deviation = 0;
    for (std::size_t k = 0; k < e.vx.size(); ++k) {
      if (e.vx[k] == 0) continue;  // not a fluid particle
      worst = std::max(worst, std::abs(i.vx[k] - e.vx[k]));
      deviation = std::max(deviation, std::abs(e.vx[k] - 0.1));
    }
    std::printf("[ measured ] free slip, %s: largest |v_x(implicit) - v_x(explicit)| %.2e m/s, pressure-kick "
                "deviation %.2e m/s\n",
                stress == fsi::ViscousStress::full ? "full stress" : "Laplacian form", worst, deviation);
    EXPECT_LT(worst, 0.01 * deviation + 1e-7) << "largest |v_x(implicit) - v_x(explicit)| [m/s]";
  }
}

// Along a no-slip wall the first row slows down; where dt nu / h^2 is small (here about 3e-3:
// mu_eff 5 Pa s at most) backward and forward Euler agree to
// first order: the first row's loss of speed within 5% of the explicit run's.
TEST(FreeSlipWalls, ImplicitViscosityShearsTheFlowAlongANoSlipWallAsExplicitDoes) {
  const AfterStep e = one_step(false, fsi::ViscousIntegration::explicit_);
  const AfterStep i = one_step(false, fsi::ViscousIntegration::implicit);
  ASSERT_GT(e.row.size(), 10u);
  for (std::uint32_t k : e.row) {
    const double loss_e = 0.1 - e.vx[k], loss_i = 0.1 - i.vx[k];
    ASSERT_GT(loss_e, 0.0) << "the explicit run's first row decelerates";
    EXPECT_NEAR(loss_i, loss_e, 0.05 * loss_e) << "particle " << k;
  }
  std::printf("[ measured ] first-row loss of speed in one step: explicit %.4e m/s, implicit %.4e m/s\n",
              0.1 - e.vx[e.row[0]], 0.1 - i.vx[e.row[0]]);
}

}  // namespace
