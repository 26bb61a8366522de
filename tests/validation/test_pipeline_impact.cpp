// Validation P (docs/validation.md, issue #21): the default scene, scenes/pipeline_impact_2d.yaml: a
// Herschel-Bulkley debris flow runs down a slope under water, sheds a turbidity current and
// strikes a pipeline (D = 0.1 m, gap D/2 above the bed).
//
// There is no measured drag for this layout (the scene's values are assumptions; the drag study is
// tools/pipeline_study). What the run must satisfy, each against a reference:
//  1. Archimedes: before the debris arrives the pipe sits in still water and feels rho_w g pi R^2 =
//     77.05 N/m upward. Bound: the mean lift over 0.3-1.2 s within kBuoyancyTolerance of it
//     (measured -8.6% at D/dx = 4, the CI spacing, where the gap under the pipe is two particle
//     rows; +2.5% at D/dx = 6, full mode).
//  2. Causality: the drag peak comes after the debris front (probe debris_front + dx/2) has reached
//     the pipe's upstream face, and it stands above the still-water noise (the RMS over 0.3-1.2 s)
//     by more than a factor of 5. The drag is the 0.05 s centred moving mean of Fx, what a force
//     transducer with that window reads and what tools/pipeline_study reports: since the
//     impermeable-wall pass's impulse is booked on the pipe (issue #47 item 1) a put-back reaches
//     the load as one step's J/dt, and a 100 Hz sample that holds one reads it as a spike (raw
//     samples: 340 N/m at 1.84 s against a filtered peak of 102 N/m at 2.43 s). Measured on the
//     filtered drag at D/dx = 4: 17.9 x the noise (5.7 N/m); since the daughters take their own h
//     with walls (fewer put-backs, issue #47 item 2) 8.4 x (51.8 N/m at 2.64 s, the debris at the
//     pipe at 2.30 s, 38.7% of the soil turbidity). Before the booking, on raw samples: 13.4 at
//     D/dx = 4, 12.5 at D/dx = 6.
//  3. Mass: splitting conserves mass (each daughter m/4): debris + turbidity mass (probes) constant
//     to 1e-9 of it at every output. (The fluid's total mass is not asserted: with nothing removed
//     it is constant by construction.)
//  4. The transition happens: some of the debris has become turbidity by the end.
//  5. The wall pass's put-back rate and impulse, printed (the scene misses the 1e-5 goal).
// Quick mode (CI): the scene's spacing 0.025 m (D/dx = 4, about 2.5 minutes on 2 cores); full mode
// (TURBID_FULL=1): 0.0166667 m (D/dx = 6, 7 minutes).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "validation_support.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadius = 0.05;       // m, as in the scene
constexpr double kPipeX = 1.7;         // m
constexpr double kRhoWater = 1000.0;   // kg/m^3
constexpr double kGravity = 9.81;      // m/s^2
constexpr double kStillFrom = 0.3, kStillTo = 1.2;  // s: the pipe in still water

}  // namespace

TEST(ValidationPipelineImpact, DebrisFlowOnASuspendedPipeline2D) {
  const bool full = turbid::validation::full_mode();
  const double dx = full ? 0.1 / 6 : 0.025;
  const double buoyancy_tolerance = full ? 0.05 : 0.12;
  const auto run = turbid::validation::run_scene_file("pipeline_impact_2d", dx);
  ASSERT_EQ(run.report.at("status").get<std::string>(), "completed") << run.report.dump(2);

  auto forces = turbid::validation::read_csv(run.out / "forces.csv");
  auto probes = turbid::validation::read_csv(run.out / "probes.csv");
  const auto& t = forces["time [s]"];
  const auto& fx = forces["pipe.Fx [N/m]"];
  const auto& fy = forces["pipe.Fy [N/m]"];
  ASSERT_GT(t.size(), 100u);
  ASSERT_EQ(fx.size(), t.size());
  ASSERT_EQ(fy.size(), t.size());

  // The drag over a centred 0.05 s window (see 2. above).
  std::vector<double> drag(t.size());
  for (std::size_t k = 0, lo = 0, hi = 0; k < t.size(); ++k) {
    while (lo < t.size() && t[lo] < t[k] - 0.025) ++lo;
    while (hi < t.size() && t[hi] <= t[k] + 0.025) ++hi;
    double sum = 0;
    for (std::size_t j = lo; j < hi; ++j) sum += fx[j];
    drag[k] = sum / double(hi - lo);
  }

  // 1. Archimedes in still water.
  double lift = 0, noise = 0;
  int n = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] < kStillFrom || t[k] > kStillTo) continue;
    lift += fy[k];
    noise += drag[k] * drag[k];
    ++n;
  }
  ASSERT_GT(n, 10);
  lift /= n;
  noise = std::sqrt(noise / n);
  const double archimedes = kRhoWater * kGravity * kPi * kRadius * kRadius;
  std::printf("[ measured ] dx = %g m: lift in still water %.2f N/m (Archimedes %.2f N/m, %+.1f%%), drag noise %.2f N/m\n",
              dx, lift, archimedes, 100 * (lift / archimedes - 1), noise);
  EXPECT_NEAR(lift, archimedes, buoyancy_tolerance * archimedes);

  // 2. The drag peak after the debris arrives, well above the noise.
  const auto peak = std::max_element(drag.begin(), drag.end()) - drag.begin();
  const auto& pt = probes["time"];
  const auto& front = probes["debris_front"];
  double arrival = NAN;
  for (std::size_t k = 0; k < pt.size(); ++k)
    if (front[k] + 0.5 * dx >= kPipeX - kRadius) {
      arrival = pt[k];
      break;
    }
  std::printf("[ measured ] debris reaches the pipe at %.2f s; peak drag (0.05 s mean) %.1f N/m at %.2f s (%.1f x the "
              "noise); largest raw sample %.1f N/m\n",
              arrival, drag[peak], t[peak], drag[peak] / noise, *std::max_element(fx.begin(), fx.end()));
  ASSERT_TRUE(std::isfinite(arrival)) << "the debris never reached the pipe";
  EXPECT_GE(t[peak], arrival - 0.05) << "the largest drag comes before the debris";
  EXPECT_GT(drag[peak], 5 * noise);

  // 3. Mass through the transition.
  const auto& md = probes["debris_mass"];
  const auto& mt = probes["turbidity_mass"];
  ASSERT_EQ(md.size(), pt.size());
  const double soil = md.front() + mt.front();
  double worst = 0;
  for (std::size_t k = 0; k < pt.size(); ++k) worst = std::max(worst, std::abs(md[k] + mt[k] - soil) / soil);
  EXPECT_LT(worst, 1e-9) << "debris + turbidity mass";

  // 4. Some debris became turbidity.
  std::printf("[ measured ] turbidity at the end: %.1f%% of the soil; %s splits\n", 100 * mt.back() / soil,
              run.report.at("splits").dump().c_str());
  EXPECT_GT(mt.back(), 0.01 * soil);

  // 5. The wall pass as a safety net (issue #47 item 2): printed, not asserted. The goal is below
  // 1e-5 put-backs per fluid particle-step; this scene misses it (docs/validation.md, L: water
  // beside the turbidity daughters on the bed, the mean-h pair kernel's inconsistency), and "no
  // fluid behind the walls" would hold by construction while the pass is on.
  std::printf("[ measured ] wall pass: %.3g put-backs per fluid particle-step (goal 1e-5), impulse %s N s/m\n",
              run.report.at("fluid_put_backs_per_particle_step").get<double>(),
              run.report.at("wall_constraint_impulse").dump().c_str());
  std::filesystem::remove_all(run.out);
}
