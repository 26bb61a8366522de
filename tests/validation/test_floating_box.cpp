// Validation D7 (physics.md; issue #8): a 2D floating box in still water settles at the Archimedes
// draft. scenes/floating_box_2d.yaml: a 0.3 m x 0.2 m box of density 500 kg/m^3, motion: free,
// released 0.02 m below its equilibrium in a 1.2 m tank of water 0.4 m deep (mDBC).
//
// Reference: draft d = (rho_b / rho_w) H_b = 0.1 m; with the water the box displaced at the start
// missing from the tank, the still-water level at equilibrium is 0.395 m and the box's centre settles
// at y = 0.395 m (derivation in the scene file).
// Tolerance (issue #8): the mean centre height over the last second of the run within 1% of the box
// height (2 mm); the box must also have moved (its range over the run above 5 mm), so that a
// body stuck at its start would fail. Quick mode (CI): dx = 0.02 m (10 particles across the
// box's height), to 4 s; full mode (TURBID_FULL=1): the scene's dx = 0.01 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/validation/validation_support.hpp"
#include "tools/runner.hpp"

using turbid::validation::full_mode;
using turbid::validation::read_csv;

TEST(FloatingBox2d, SettlesAtTheArchimedesDraft) {
  const double dx = full_mode() ? 0.01 : 0.02;
  const auto run = turbid::validation::run_scene_file("floating_box_2d", dx);
  ASSERT_EQ(run.report.at("status").get<std::string>(), "completed") << run.report.dump(2);
  auto csv = read_csv(run.out / "forces.csv");
  const auto& t = csv["time [s]"];
  const auto& y = csv["box.y [m]"];
  ASSERT_EQ(t.size(), y.size());
  ASSERT_GT(t.size(), 100u);
  const double end = t.back();
  const double height = 0.2, expected = 0.395;
  double sum = 0, lo = 1e300, hi = -1e300, lo_all = 1e300, hi_all = -1e300;
  std::size_t n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    lo_all = std::min(lo_all, y[i]);
    hi_all = std::max(hi_all, y[i]);
    if (t[i] < end - 1.0) continue;
    sum += y[i];
    lo = std::min(lo, y[i]);
    hi = std::max(hi, y[i]);
    ++n;
  }
  const double mean = sum / double(n);
  std::printf("[ measured ] dx = %.3f m: centre y over the last second %.5f m (range %.5f..%.5f), expected %.5f m: "
              "error %.3f%% of the box height; range over the run %.5f..%.5f m\n",
              dx, mean, lo, hi, expected, 100 * (mean - expected) / height, lo_all, hi_all);
  EXPECT_GT(hi_all - lo_all, 0.005);
  EXPECT_LE(std::abs(mean - expected), 0.01 * height);
  std::filesystem::remove_all(run.out);
}
