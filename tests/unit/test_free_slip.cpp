// Free-slip walls (`walls: - {box: ..., slip: free}`): a Bingham block sliding at a uniform speed
// along the floor of a tank, without gravity, at rest density (no pressure anywhere). Reference:
// a uniform flow along a free-slip wall carries no shear, so every fluid particle's shear rate and
// acceleration are zero, exactly (the difference-form gradient and the viscous pair terms vanish
// for equal velocities, and the wall is left out of both). Along a no-slip wall the same block is
// sheared: its first row sees a shear rate and decelerates.
#include <gtest/gtest.h>

#include <cstdint>

#include "fsi/scene.hpp"
#include "fsi/simulation.hpp"

namespace {

using namespace turbid;

fsi::Scene sliding_block(bool free_slip) {
  fsi::Scene s;
  s.name = "unit_free_slip";
  s.dimensions = 2;
  s.particle_spacing = 0.01;
  s.smoothing_ratio = 2.0;
  s.gravity = {0, 0, 0};
  s.numerics.viscosity = fsi::ViscosityKind::laminar;
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

FirstRow measure(bool free_slip) {
  fsi::Simulation sim(sliding_block(free_slip), {"cpu", 1});
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

}  // namespace
