// Validation D8 (docs/validation.md): water at rest in a 2D tank (scenes/hydrostatic_tank_2d.yaml,
// depth H = 1 m, DBC walls) must stay at rest with hydrostatic pressure.
//
// Reference: exact hydrostatics p(y) = rho0 g (H - y), rho0 = 1000 kg/m^3, g = 9.81 m/s^2.
// Tolerances (from the foundation issue):
//   - at the end (t = 2 s) the Shepard-interpolated pressure at mid-depth (y = 0.5 m) and near the
//     bottom (y = 0.1 m) is within 2% of rho0 g (H - y);
//   - the largest fluid particle speed, over every output time of the run including the start-up
//     transient, stays below 1% of sqrt(g H) = 0.0313 m/s.
// Quick mode (default, CI): dx = 0.025 m, 40 particles over the depth (measured: p_mid +0.41%,
// p_bottom +0.74%, largest speed 0.0200 m/s, at t = 0.1 s). Full mode (TURBID_FULL=1): the scene's
// own dx = 0.02 m (+0.41%, +0.71%, 0.0171 m/s). Same tolerances in both. dx = 0.04 m would be 4x
// cheaper but its start-up transient reaches 0.029 m/s, too close to the limit to be a useful test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "tests/validation/validation_support.hpp"
#include "tools/runner.hpp"

namespace fs = std::filesystem;
using turbid::validation::full_mode;
using turbid::validation::read_csv;

namespace {

constexpr double kGravity = 9.81;      // m/s^2, as in the scene
constexpr double kDensity = 1000.0;    // rho0 [kg/m^3]
constexpr double kDepth = 1.0;         // H [m]
constexpr double kEndTime = 2.0;       // s
constexpr double kQuickSpacing = 0.025;  // m

double hydrostatic_pressure(double y) { return kDensity * kGravity * (kDepth - y); }

}  // namespace

TEST(ValidationHydrostaticTank, PressureIsHydrostaticAndWaterStaysAtRest) {
  const double dx = full_mode() ? 0.02 : kQuickSpacing;
  const auto run = turbid::validation::run_scene_file("hydrostatic_tank_2d", dx, kEndTime);
  const fs::path& out = run.out;
  const auto& report = run.report;
  ASSERT_EQ(report.at("status").get<std::string>(), "completed") << report.dump(2);
  EXPECT_NEAR(report.at("simulated_time").get<double>(), kEndTime, 1e-3);

  auto probes = read_csv(out / "probes.csv");
  ASSERT_GE(probes["time"].size(), 2u);

  const std::vector<std::pair<std::string, double>> points = {{"p_mid", 0.5}, {"p_bottom", 0.1}};
  for (const auto& [name, y] : points) {
    ASSERT_FALSE(probes[name].empty()) << "probes.csv has no column " << name;
    const double p = probes[name].back();
    const double exact = hydrostatic_pressure(y);
    const double rel = std::abs(p - exact) / exact;
    std::cout << "[hydrostatic dx=" << dx << "] " << name << " at t=" << probes["time"].back() << " s: " << p
              << " Pa, exact " << exact << " Pa, relative error " << 100 * rel << "%\n";
    RecordProperty(name + "_relative_error", std::to_string(rel));
    EXPECT_LT(rel, 0.02) << name << " (y = " << y << " m): " << p << " Pa vs rho0 g (H - y) = " << exact << " Pa";
  }

  const auto& vmax = probes["vmax"];
  ASSERT_FALSE(vmax.empty());
  const double worst = *std::max_element(vmax.begin(), vmax.end());
  const double limit = 0.01 * std::sqrt(kGravity * kDepth);
  std::cout << "[hydrostatic dx=" << dx << "] max particle speed over the run: " << worst << " m/s (limit " << limit
            << " m/s = 1% of sqrt(gH)); wall " << report.at("wall_seconds").get<double>() << " s, "
            << report.at("steps").get<std::uint64_t>() << " steps, " << report.at("particles").get<std::uint64_t>()
            << " particles\n";
  RecordProperty("max_speed", std::to_string(worst));
  EXPECT_LT(worst, limit) << "spurious flow in a tank at rest";

  fs::remove_all(out);
}
