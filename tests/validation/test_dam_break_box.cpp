// Validation W (docs/validation.md, issue #27 item 9): scenes/dam_break_box_3d.yaml, the 3D dam
// break against a box on the floor (the SPHERIC benchmark 2 layout, mDBC walls). The surge hits the
// box at t ~ 0.4 s and the near end wall at ~ 0.6 s, runs up and falls back over the box.
//
// Reference: the walls' geometry. No fluid particle may stand more than dx/4 behind the surface of
// the tank's walls or the box at any output (fsi/wall_penetration.hpp defines behind and the dx/4);
// before impermeable walls 100 did at t = 1.5 s at dx = 0.03 m (deepest 3.1 dx). Mass: particles
// keep their mass and none leaves the closed tank, so the fluid's mass is constant to rounding.
// Quick mode (CI): dx = 0.05 m (H/dx = 11, about 2 minutes on 2 cores); full mode (TURBID_FULL=1):
// the scene's dx = 0.03 m (11-13 minutes). Both to t = 1.5 s.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "validation_support.hpp"

TEST(ValidationDamBreakBox, NoFluidBehindTheWallsOrTheBox3D) {
  const bool full = turbid::validation::full_mode();
  const double dx = full ? 0.03 : 0.05;
  const auto run = turbid::validation::run_scene_file("dam_break_box_3d", dx, 1.5);
  const auto& r = run.report;
  ASSERT_EQ(r.at("status").get<std::string>(), "completed") << r.dump(2);
  std::printf("[dam break box dx=%g] fluid behind walls: most at an output %llu, at the end %llu; fluid put back "
              "on a surface %llu times (%.2e of the fluid particle-steps); wall %.0f s, %llu steps\n",
              dx, (unsigned long long)r.at("fluid_behind_walls_max").get<std::uint64_t>(),
              (unsigned long long)r.at("fluid_behind_walls").get<std::uint64_t>(),
              (unsigned long long)r.at("fluid_put_back_on_walls").get<std::uint64_t>(),
              double(r.at("fluid_put_back_on_walls").get<std::uint64_t>()) /
                  (double(r.at("fluid_particles").get<std::uint64_t>()) * double(r.at("steps").get<std::uint64_t>())),
              r.at("wall_seconds").get<double>(), (unsigned long long)r.at("steps").get<std::uint64_t>());
  EXPECT_EQ(r.at("fluid_behind_walls_max").get<std::uint64_t>(), 0u)
      << "deepest at the end " << r.at("fluid_behind_walls_deepest_m").get<double>() << " m";
  EXPECT_EQ(r.at("removed_particles").get<std::uint64_t>(), 0u);
  EXPECT_LT(std::abs(r.at("fluid_mass_relative_change").get<double>()), 1e-12);
}
