// Validation D9 (docs/validation.md): lock-exchange gravity current, a full-depth lock of water 5% or
// 10% denser than the water around it released in a closed channel 1.5 m long and H = 0.2 m deep
// (scenes/lock_exchange_{5,10}pct_2d.yaml).
//
// Reference: after the start-up the front moves at a constant speed U = 1/2 sqrt(g' H),
// g' = g (rho_1 - rho_0) / rho_0 (energy-conserving theory, Benjamin 1968; the experiments of Shin,
// Dalziel & Linden 2004 ran a few percent slower). Measured: U / sqrt(g' H), with U the
// least-squares slope of the probe 'front' (largest x of the dense fluid, written every 0.1 s) while
// it lies between x = 0.5 and 1.1 m; the same metric as tools/validation_metrics.py (keep the two
// in step).
// Tolerances:
//   - full mode (TURBID_FULL=1, H/dx = 80): the materials issue's goal, 0.43 <= U / sqrt(g' H) <= 0.52;
//   - quick mode (CI, H/dx = 20, where the head is ten particles high and numerical dissipation
//     slows the current): measured 0.394 (5%) and 0.426 (10%); bounds 0.37 (the measured speed less
//     6%) to 0.52 (nothing faster than the theory allows).
// Both modes also check that the denser lock runs faster in absolute terms, U ~ sqrt(g'): the ratio
// U(10%) / U(5%) within 15% of sqrt(2).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/validation/validation_support.hpp"

namespace {

constexpr double kG = 9.81, kDepth = 0.2, kFrom = 0.5, kTo = 1.1;

// U / sqrt(g' H) of a run of scenes/lock_exchange_<percent>pct_2d.yaml at spacing dx.
double front_speed(int percent, double dx, double end) {
  const std::string scene = "lock_exchange_" + std::to_string(percent) + "pct_2d";
  const auto run = turbid::validation::run_scene_file(scene, dx, end);
  EXPECT_EQ(run.report.at("status"), "completed") << scene;
  const auto probes = turbid::validation::read_csv(run.out / "probes.csv");
  const auto& t = probes.at("time");
  const auto& x = probes.at("front");
  std::vector<double> ts, xs;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (x[k] >= kFrom && x[k] <= kTo) ts.push_back(t[k]), xs.push_back(x[k]);
  std::filesystem::remove_all(run.out);
  if (ts.size() < 3) {
    ADD_FAILURE() << scene << ": the front never crosses " << kFrom << "-" << kTo << " m by t = " << end << " s";
    return 0;
  }
  double mt = 0, mx = 0;
  for (std::size_t k = 0; k < ts.size(); ++k) mt += ts[k], mx += xs[k];
  mt /= double(ts.size());
  mx /= double(ts.size());
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < ts.size(); ++k) sxy += (ts[k] - mt) * (xs[k] - mx), sxx += (ts[k] - mt) * (ts[k] - mt);
  const double ratio = sxy / sxx / std::sqrt(kG * 0.01 * percent * kDepth);
  std::printf("  %d%% denser lock, H/dx = %.0f: U / sqrt(g' H) = %.3f over %zu samples (theory 0.5)\n", percent,
              kDepth / dx, ratio, ts.size());
  return ratio;
}

}  // namespace

TEST(ValidationLockExchange, FrontSpeedMatchesBenjaminsTheory) {
  const bool full = turbid::validation::full_mode();
  const double dx = full ? 0.0025 : 0.01;
  const double low = full ? 0.43 : 0.37, high = 0.52;
  // End times: the front passes 1.1 m at about 7.3 s (5%) and 5.2 s (10%) at the coarser spacing.
  const double five = front_speed(5, dx, full ? 7.5 : 8.0);
  const double ten = front_speed(10, dx, full ? 5.5 : 6.0);
  EXPECT_GE(five, low) << "5% denser lock";
  EXPECT_LE(five, high) << "5% denser lock";
  EXPECT_GE(ten, low) << "10% denser lock";
  EXPECT_LE(ten, high) << "10% denser lock";
  // U = ratio * sqrt(g' H): U(10%) / U(5%) = (ten / five) * sqrt(2).
  EXPECT_NEAR(ten / five * std::sqrt(2.0), std::sqrt(2.0), 0.15 * std::sqrt(2.0)) << "U ~ sqrt(g')";
}
