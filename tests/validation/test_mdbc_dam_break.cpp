// Stability H3 (docs/validation.md, issue #20 item 5): a 2D dam break with mDBC walls through its
// first wall impact. Column 0.6 m long and H = 0.3 m high at the left end of a closed tank
// 1.61 m long, H/dx = 60, the docs' default numerics (Wendland C2, h = 2 dx, Fourtakas delta = 0.1,
// alpha = 0.02, c0 = 10 sqrt(2 g H)). Before the fix this run blew up at t = 0.444 s, when the
// one-particle-thick surge tip reached the far wall's corner: the ghost nodes there extrapolated a
// density gradient across a single row of fluid (the first-order system's gradient block has a
// smallest singular value of 0.003-0.008 there, an amplification of 100-300), the wall density ran
// to 1520 kg/m^3 within 40 steps. mDBC now keeps the Shepard value where that gain is below 0.1
// (sph/boundary_passes.hpp, docs/choices.md).
//
// What must hold (no reference solution; robustness and the physics of a closed tank):
//   - the run reaches t = 0.7 s (the impact at 0.44 s and the run-up of the far wall);
//   - (printed, not asserted) fluid centres more than dx/2 outside the tank's interior at the checks
//     every 0.01 s: 0 by construction while the impermeable-wall pass is on; what that pass did is
//     the measure, put-backs per fluid particle-step, 2.3e-5 here against the goal of 1e-5 (issue
//     #47 item 2; docs/validation.md L lists the known misses: the surge tip, one particle thick,
//     whose mDBC ghost nodes are dry);
//   - the largest fluid density stays below 1.15 rho0: the impact is the water hammer of the
//     artificial sound speed, drho / rho = u / c0 with u about 2.7 m/s and c0 = 24.3 m/s, 0.11
//     (measured 1.104 rho0 at t = 0.446 s; issue #25 is about that peak). The largest wall density
//     is reported, not bounded: it occurs in the far corner's deepest layer (1.3 rho0 for a few
//     steps), whose ghost nodes lie 6 dx into the fluid and which no fluid particle reaches;
//   - fluid mass and particle count are exact (nothing created or removed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"

namespace {

const char* kScene = R"(name: dam_break_mdbc_2d
dimensions: 2
resolution: {particle_spacing: 0.005, smoothing_ratio: 2.0}
time: {end: 0.7, cfl: 0.2}
gravity: [0, -9.81]
numerics:
  kernel: wendland_c2
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: artificial, alpha: 0.02}
  boundary: {type: mdbc}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 24.26}
walls:
  - box: {min: [0, 0], max: [1.61, 0.8]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.6, 0.3]}}
output: {every: 0.1, vtk: false}
)";

}  // namespace

TEST(ValidationMdbcDamBreak, RunsThroughTheFirstWallImpact) {
  const std::string path = ::testing::TempDir() + "dam_break_mdbc_2d.yaml";
  std::ofstream(path) << kScene;
  const auto scene = turbid::tools::read_scene_file(path);
  turbid::fsi::Simulation sim(scene, {"cpu", 0});
  sim.start();
  const double dx = scene.particle_spacing;
  const auto& st = sim.store();
  const auto count_and_mass = [&](double& mass) {
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    const auto* m = st.data<float>(sim.fields().mass);
    std::size_t n = 0;
    mass = 0;
    for (std::size_t i = 0; i < st.size(); ++i)
      if (kind[i] == 0) {
        ++n;
        mass += m[i];
      }
    return n;
  };
  double mass0 = 0;
  const std::size_t n0 = count_and_mass(mass0);
  std::size_t outside = 0;
  double rho_max = 0, t_rho_max = 0, wall_rho_max = 0;
  double next_check = 0;
  while (sim.time() < scene.end_time - 1e-12) {
    ASSERT_NO_THROW(sim.step()) << "blow-up at t = " << sim.time() << " s";
    const auto* rho = st.data<float>(sim.fields().density);
    const auto* kinds = st.data<std::uint8_t>(sim.fields().kind);
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (kinds[i] != 0) {
        wall_rho_max = std::max(wall_rho_max, double(rho[i]));
      } else if (rho[i] > rho_max) {
        rho_max = rho[i];
        t_rho_max = sim.time();
      }
    }
    if (sim.time() < next_check) continue;
    next_check += 0.01;
    const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (kind[i] != 0) continue;
      if (x[2 * i] < -0.5 * dx || x[2 * i] > 1.61 + 0.5 * dx || x[2 * i + 1] < -0.5 * dx) ++outside;
    }
  }
  double mass1 = 0;
  const std::size_t n1 = count_and_mass(mass1);
  std::printf("[ measured ] mDBC dam break, H/dx = 60: t = %.3f s, %llu steps, largest fluid density %.1f kg/m^3 at "
              "t = %.3f s, largest wall density %.1f kg/m^3, %zu fluid positions outside\n",
              sim.time(), static_cast<unsigned long long>(sim.steps()), rho_max, t_rho_max, wall_rho_max, outside);
  const double put_backs = double(sim.wall_put_backs()) / double(sim.fluid_particle_steps());
  std::printf("[ measured ] wall pass: %llu put-backs, %.3g per fluid particle-step\n",
              static_cast<unsigned long long>(sim.wall_put_backs()), put_backs);
  EXPECT_GE(sim.time(), scene.end_time - 1e-9);
  EXPECT_LT(rho_max, 1150.0) << "largest fluid density [kg/m^3]";
  EXPECT_EQ(n1, n0);
  EXPECT_NEAR(mass1, mass0, 1e-12 * mass0);
  EXPECT_EQ(sim.removed(), 0u);
}
