// Validation B1 (docs/validation.md): buoyancy on fixed, fully submerged structures in water at
// rest, mDBC walls and structures.
//
// Reference: Archimedes, the vertical force is rho0 g V (per metre of depth in 2D); the horizontal
// forces vanish by symmetry of the hydrostatic field.
// Tolerance (issue #4): the mean vertical force over a window after the start-up transient within
// 2% of rho0 g V; the mean horizontal forces below 2% of it as well.
//  - 2D (scenes/buoyancy_2d.yaml: a 0.2 m x 0.2 m box and a cylinder of radius 0.1 m; box
//    392.4 N/m, cylinder 308.2 N/m), window 1.0-1.5 s. Quick mode (CI): the scene's dx = 0.01 m;
//    full mode (TURBID_FULL=1): dx = 0.005 m.
//  - 3D (scenes/buoyancy_3d.yaml: a 0.15 m cube, 33.11 N, and a horizontal cylinder R = 0.075 m,
//    L = 0.3 m, 52.01 N), window 0.6-1.0 s. Quick mode (CI): dx = 0.025 m (6 particles across the
//    cube, about 3 min on 2 cores); full mode: the scene's
//    dx = 0.02 m.
// Measured figures are in docs/validation.md.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>
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

namespace {

struct Body {
  std::string name;
  double volume;  // [m^3], or [m^2] in 2D
};

// Runs `scene` at spacing dx and checks the mean forces over [t_from, end] against Archimedes.
// `unit` is the force unit of the columns ("N/m" in 2D, "N" in 3D), `up` the vertical axis.
void check_buoyancy(const std::string& scene, double dx, double t_from, const std::vector<Body>& bodies,
                    const std::string& unit, const std::string& up, const std::vector<std::string>& sideways) {
  const auto run = turbid::validation::run_scene_file(scene, dx);
  const fs::path& out = run.out;
  const auto& report = run.report;
  ASSERT_EQ(report.at("status").get<std::string>(), "completed") << report.dump(2);

  auto forces = read_csv(out / "forces.csv");
  const auto& t = forces["time [s]"];
  ASSERT_GT(t.size(), 40u);
  for (const auto& body : bodies) {
    const double expected = kRhoG * body.volume;
    std::vector<std::string> axes = sideways;
    axes.push_back(up);
    for (const auto& axis : axes) {
      const std::string column = body.name + "." + axis + " [" + unit + "]";
      const auto& f = forces[column];
      ASSERT_EQ(f.size(), t.size()) << "forces.csv has no column " << column;
      double sum = 0;
      int n = 0;
      for (std::size_t k = 0; k < t.size(); ++k) {
        ASSERT_TRUE(std::isfinite(f[k])) << column << " at t = " << t[k];
        if (t[k] < t_from) continue;
        sum += f[k];
        ++n;
      }
      ASSERT_GT(n, 10);
      const double mean = sum / n;
      if (axis == up) {
        const double rel = (mean - expected) / expected;
        std::cout << "[" << scene << " dx=" << dx << "] " << body.name << ": mean " << axis << " = " << mean << " "
                  << unit << ", rho0 g V = " << expected << " " << unit << ", error " << 100 * rel << "%\n";
        ::testing::Test::RecordProperty(body.name + "_relative_error", std::to_string(rel));
        EXPECT_LT(std::abs(rel), 0.02) << body.name;
      } else {
        EXPECT_LT(std::abs(mean), 0.02 * expected) << column;
      }
    }
  }
  fs::remove_all(out);
}

}  // namespace

TEST(ValidationBuoyancy, SubmergedBoxAndCylinderFeelTheWeightOfDisplacedWater2D) {
  check_buoyancy("buoyancy_2d", full_mode() ? 0.005 : 0.01, 1.0, {{"box", 0.2 * 0.2}, {"cylinder", kPi * 0.1 * 0.1}},
                 "N/m", "Fy", {"Fx"});
}

TEST(ValidationBuoyancy, SubmergedCubeAndCylinderFeelTheWeightOfDisplacedWater3D) {
  check_buoyancy("buoyancy_3d", full_mode() ? 0.02 : 0.025, 0.6,
                 {{"cube", 0.15 * 0.15 * 0.15}, {"cylinder", kPi * 0.075 * 0.075 * 0.3}}, "N", "Fz", {"Fx", "Fy"});
}
