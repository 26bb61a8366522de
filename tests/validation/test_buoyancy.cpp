// Validation S1 (docs/validation.md): buoyancy on fixed, fully submerged structures in water at
// rest (scenes/buoyancy_2d.yaml: a 0.2 m x 0.2 m box and a cylinder of radius 0.1 m, mDBC walls).
//
// Reference: Archimedes, F_y = rho0 g V per metre of depth (box 392.4 N/m, cylinder 308.2 N/m);
// F_x = 0 by symmetry of the hydrostatic field.
// Tolerance (issue #4): the mean of F_y over 1.0 s <= t <= 1.5 s, after the start-up transient,
// within 2% of rho0 g V; |mean F_x| below 2% of it as well.
// Quick mode (CI): the scene's dx = 0.01 m (20 particles across the bodies; measured: box +0.42%,
// cylinder +1.34%, ~15 s on 2 cores); full mode (TURBID_FULL=1): dx = 0.005 m. Same tolerance in
// both. At dx = 0.02 m the cylinder is at +1.96%, too close to the limit for a useful test.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <unistd.h>

#include "tests/validation/validation_support.hpp"
#include "tools/runner.hpp"

namespace fs = std::filesystem;
using turbid::validation::full_mode;
using turbid::validation::read_csv;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kRhoG = 1000.0 * 9.81;  // rho0 g [N/m^3]
}  // namespace

TEST(ValidationBuoyancy, SubmergedBoxAndCylinderFeelTheWeightOfDisplacedWater2D) {
  const double dx = full_mode() ? 0.005 : 0.01;
  const fs::path out = fs::temp_directory_path() / ("turbid_validation_buoyancy_" + std::to_string(::getpid()));
  fs::remove_all(out);
  turbid::tools::RunRequest request;
  request.scene_file = fs::path(TURBID_SOURCE_DIR) / "scenes" / "buoyancy_2d.yaml";
  request.out = out;
  request.spacing = dx;
  request.progress = false;
  const auto report = turbid::tools::run_scene(request);
  ASSERT_EQ(report.at("status").get<std::string>(), "completed") << report.dump(2);

  auto forces = read_csv(out / "forces.csv");
  const auto& t = forces["time [s]"];
  ASSERT_GT(t.size(), 50u);
  const std::vector<std::pair<std::string, double>> bodies = {{"box", 0.2 * 0.2}, {"cylinder", kPi * 0.1 * 0.1}};
  for (const auto& [name, volume] : bodies) {
    const auto& fx = forces[name + ".Fx [N/m]"];
    const auto& fy = forces[name + ".Fy [N/m]"];
    ASSERT_EQ(fy.size(), t.size()) << "forces.csv has no column " << name << ".Fy [N/m]";
    double sx = 0, sy = 0;
    int n = 0;
    for (std::size_t k = 0; k < t.size(); ++k) {
      ASSERT_TRUE(std::isfinite(fx[k]) && std::isfinite(fy[k])) << name << " at t = " << t[k];
      if (t[k] < 1.0) continue;
      sx += fx[k];
      sy += fy[k];
      ++n;
    }
    ASSERT_GT(n, 10);
    const double expected = kRhoG * volume;
    const double mean_y = sy / n, mean_x = sx / n;
    const double rel = (mean_y - expected) / expected;
    std::cout << "[buoyancy dx=" << dx << "] " << name << ": mean F_y = " << mean_y << " N/m, rho0 g V = " << expected
              << " N/m, error " << 100 * rel << "%, mean F_x = " << mean_x << " N/m\n";
    RecordProperty(name + "_relative_error", std::to_string(rel));
    EXPECT_LT(std::abs(rel), 0.02) << name;
    EXPECT_LT(std::abs(mean_x), 0.02 * expected) << name;
  }
  fs::remove_all(out);
}
