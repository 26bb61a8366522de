// Validation D2 (docs/validation.md): the default scene, scenes/dam_break_2d.yaml, against the
// surge front measured by Martin & Moyce (1952), Table 2, n^2 = 2
// (scenes/reference/martin_moyce1952_surge_front_n2eq2_Ocellaris.csv).
//
// Metric: Z = x_front / a and T = t sqrt(2 g / a) with a = 0.05715 m. The simulated front is the
// `front` probe (centre of the leading fluid particle) plus dx/2, the half cell that particle
// stands for (so Z = 1 at T = 0, as in the experiment). It is interpolated linearly in time at
// every experimental T <= 3 (13 points), and the error is the RMS of the relative error
// (Z_sim - Z_exp) / Z_exp.
//
// Tolerance: 10% (foundation issue), in both modes. Quick mode (default, CI): dx = 0.003 m
// (a / dx = 19), measured 5.9%. Full mode (TURBID_FULL=1): the scene's own dx = 0.0015 m, measured
// 9.7%: the error grows as dx shrinks (11.1% at dx = 0.001 m), because the model's front runs ahead
// of the experiment by a nearly constant start-up offset of about 0.2 in T (docs/validation.md).
// Second check, both modes: shifted later by the best offset dT in [0, 0.4], the simulated front is
// within 5% RMS of the experiment (measured 2.3-2.7%), i.e. the front speed is right. Both runs stop
// at t = 0.17 s (T = 3.15).
#include <gtest/gtest.h>

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

constexpr double kGravity = 9.81;       // m/s^2, as in the scene
constexpr double kColumnWidth = 0.05715;  // a [m]
constexpr double kMaxT = 3.0;           // compare for T <= 3
constexpr double kEndTime = 0.17;       // s; T = 3.15
constexpr double kQuickSpacing = 0.003;  // m
constexpr double kTolerance = 0.10;      // RMS relative error, T <= 3
constexpr double kShiftedTolerance = 0.05;  // the same after the best start-up offset

// Linear interpolation of ys(xs) at x (xs increasing); NaN outside the range.
double interpolate(double x, const std::vector<double>& xs, const std::vector<double>& ys) {
  if (xs.empty() || x < xs.front() || x > xs.back()) return std::nan("");
  std::size_t hi = 1;
  while (hi < xs.size() - 1 && xs[hi] < x) ++hi;
  const std::size_t lo = hi - 1;
  if (xs[hi] == xs[lo]) return ys[lo];
  const double w = (x - xs[lo]) / (xs[hi] - xs[lo]);
  return ys[lo] + w * (ys[hi] - ys[lo]);
}

}  // namespace

TEST(ValidationDamBreak, SurgeFrontMatchesMartinMoyce1952) {
  const bool full = full_mode();
  const fs::path out = fs::temp_directory_path() / ("turbid_validation_dam_break_" + std::to_string(::getpid()));
  fs::remove_all(out);

  turbid::tools::RunRequest request;
  request.scene_file = fs::path(TURBID_SOURCE_DIR) / "scenes" / "dam_break_2d.yaml";
  request.out = out;
  if (!full) request.spacing = kQuickSpacing;
  request.end_time = kEndTime;
  request.progress = false;
  const auto report = turbid::tools::run_scene(request);
  ASSERT_EQ(report.at("status").get<std::string>(), "completed") << report.dump(2);
  const double dx = report.at("particle_spacing").get<double>();

  auto probes = read_csv(out / "probes.csv");
  const auto& time = probes["time"];
  const auto& front = probes["front"];
  ASSERT_GE(time.size(), 2u);
  ASSERT_EQ(time.size(), front.size());
  std::vector<double> T_sim, Z_sim;
  const double time_scale = std::sqrt(2.0 * kGravity / kColumnWidth);
  for (std::size_t i = 0; i < time.size(); ++i) {
    T_sim.push_back(time[i] * time_scale);
    Z_sim.push_back((front[i] + 0.5 * dx) / kColumnWidth);
  }
  // The lattice fills the column with whole cells of width dx, so its edge starts within dx of a.
  EXPECT_NEAR(Z_sim.front(), 1.0, dx / kColumnWidth) << "the column should start with its edge at x = a";

  auto reference = read_csv(fs::path(TURBID_REFERENCE_DIR) / "martin_moyce1952_surge_front_n2eq2_Ocellaris.csv");
  const auto& T_exp = reference["T"];
  const auto& Z_exp = reference["Z"];
  ASSERT_EQ(T_exp.size(), 15u) << "Martin & Moyce Table 2 has 15 points";

  // RMS relative error of the simulated front shifted later by dT (Z_sim(T - dT) against Z_exp(T)).
  auto rms_error = [&](double dT, bool print) {
    double sum2 = 0;
    int count = 0;
    for (std::size_t k = 0; k < T_exp.size(); ++k) {
      if (T_exp[k] > kMaxT) continue;
      const double z = interpolate(T_exp[k] - dT, T_sim, Z_sim);
      if (std::isnan(z)) return std::nan("");
      const double rel = (z - Z_exp[k]) / Z_exp[k];
      if (print)
        std::cout << "[dam break dx=" << dx << "] T = " << T_exp[k] << ": Z_exp = " << Z_exp[k] << ", Z_sim = " << z
                  << " (" << 100 * rel << "%)\n";
      sum2 += rel * rel;
      ++count;
    }
    return count == 13 ? std::sqrt(sum2 / count) : std::nan("");
  };

  const double rms = rms_error(0.0, true);
  ASSERT_FALSE(std::isnan(rms)) << "the run does not reach T = 3 (13 experimental points with T <= 3)";
  std::cout << "[dam break dx=" << dx << "] RMS relative front error for T <= 3: " << 100 * rms << "% (tolerance "
            << 100 * kTolerance << "%); wall " << report.at("wall_seconds").get<double>() << " s, "
            << report.at("steps").get<std::uint64_t>() << " steps, " << report.at("particles").get<std::uint64_t>()
            << " particles\n";
  RecordProperty("rms_relative_front_error", std::to_string(rms));
  EXPECT_LT(rms, kTolerance) << "surge front vs Martin & Moyce (1952)";
  // The walls hold the surge by their pressure (issue #47 item 2): the impermeable-wall pass, a
  // safety net, puts fluid back on a wall surface in fewer than 1e-5 of the fluid particle-steps
  // (the goal). ("No fluid behind the walls" would hold by construction while the pass is
  // on.) Measured: 0 put-backs at dx = 0.003 m.
  const double put_backs = report.at("fluid_put_backs_per_particle_step").get<double>();
  std::cout << "[dam break dx=" << dx << "] put-backs per fluid particle-step " << put_backs << " ("
            << report.at("fluid_put_back_on_walls").get<std::uint64_t>() << ")\n";
  EXPECT_LT(put_backs, 1e-5) << "the walls let fluid through; the wall pass caught it";

  double best_shift = 0, best_rms = rms;
  for (int k = 1; k <= 80; ++k) {
    const double dT = 0.005 * k;
    const double e = rms_error(dT, false);
    if (!std::isnan(e) && e < best_rms) {
      best_rms = e;
      best_shift = dT;
    }
  }
  std::cout << "[dam break dx=" << dx << "] best time offset dT = " << best_shift << " (t = "
            << 1000 * best_shift / time_scale << " ms): RMS relative error " << 100 * best_rms << "% (tolerance "
            << 100 * kShiftedTolerance << "%)\n";
  RecordProperty("best_time_offset", std::to_string(best_shift));
  RecordProperty("rms_relative_front_error_shifted", std::to_string(best_rms));
  EXPECT_LT(best_rms, kShiftedTolerance) << "front speed vs Martin & Moyce (1952) after the best start-up offset";

  fs::remove_all(out);
}
