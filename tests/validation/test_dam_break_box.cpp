// Validation W (docs/validation.md, issue #27 item 9): scenes/dam_break_box_3d.yaml, the 3D dam
// break against a box on the floor (the SPHERIC benchmark 2 layout, mDBC walls). The surge hits the
// box at t ~ 0.4 s and the near end wall at ~ 0.6 s, runs up and falls back over the box.
//
// A hard case for stability: the run reaches t = 1.5 s without a blow-up and loses no particle
// (the fluid's mass, constant by construction when none is lost, is not asserted). The walls'
// impermeability is printed, not asserted: "no fluid behind the walls" holds by construction while
// the impermeable-wall pass is on (before the pass 100 particles were behind at t = 1.5 s,
// dx = 0.03 m, deepest 3.1 dx), and the pass's put-back rate misses the goal of issue #47 item 2
// (1e-5 per fluid particle-step): 3.1e-3 at the CI spacing, where the box is 3.2 dx thick,
// thinner than the kernel's support (4 dx), and the surge climbs it and the end wall
// (docs/validation.md, L, known misses).
// Quick mode (CI): dx = 0.05 m (H/dx = 11, about 2 minutes on 2 cores); full mode (TURBID_FULL=1):
// the scene's dx = 0.03 m (11-13 minutes). Both to t = 1.5 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "validation_support.hpp"

TEST(ValidationDamBreakBox, SurgeAroundTheBoxRunsToTheEndWithoutLosingFluid3D) {
  const bool full = turbid::validation::full_mode();
  const double dx = full ? 0.03 : 0.05;
  const auto run = turbid::validation::run_scene_file("dam_break_box_3d", dx, 1.5);
  const auto& r = run.report;
  ASSERT_EQ(r.at("status").get<std::string>(), "completed") << r.dump(2);
  std::printf("[dam break box dx=%g] fluid behind walls: most at an output %llu, at the end %llu; fluid put back "
              "on a surface %llu times (%.2e of the fluid particle-steps; goal 1e-5); wall %.0f s, %llu steps\n",
              dx, (unsigned long long)r.at("fluid_behind_walls_max").get<std::uint64_t>(),
              (unsigned long long)r.at("fluid_behind_walls").get<std::uint64_t>(),
              (unsigned long long)r.at("fluid_put_back_on_walls").get<std::uint64_t>(),
              double(r.at("fluid_put_back_on_walls").get<std::uint64_t>()) /
                  (double(r.at("fluid_particles").get<std::uint64_t>()) * double(r.at("steps").get<std::uint64_t>())),
              r.at("wall_seconds").get<double>(), (unsigned long long)r.at("steps").get<std::uint64_t>());
  EXPECT_EQ(r.at("removed_particles").get<std::uint64_t>(), 0u);
}
