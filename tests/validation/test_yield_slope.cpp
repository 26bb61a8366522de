// Validation D10 (docs/validation.md, issue #20): a Bingham layer on a slope, the material's yield
// stress independent of the spacing.
//
// An infinite layer (periodic along the slope) of depth H = 0.1 m on a rough (no-slip mDBC) bed
// tilted by theta = 10 degrees (gravity rotated), density 1800 kg/m^3, plastic viscosity
// mu_p = 10 Pa s, Papanastasiou exponent m = 100 s. The driving stress at the bed is
// tau_b = rho g sin(theta) H = 306.6 Pa.
//
//  - Below yield (tau_y = 600 Pa): an ideal Bingham layer does not move; the regularised material
//    creeps where tau = tau_y (1 - exp(-m gamma_dot)) + mu_p gamma_dot, at the bed gamma_dot =
//    7.2e-3 1/s: a mean speed over the depth of u_c = 2.16e-4 m/s (regularised_creep_mean), the
//    same at every spacing, 1.1e-4 m (0.01 dx at H/dx = 10) in 0.5 s.
//    Bounds: the layer's mean speed, averaged over 0.25-0.5 s, within 10% of u_c at each of three
//    spacings in full mode, two in CI (measured -5.4%, -1.5%, -1.7% at H/dx = 5, 10, 15), and within
//    10% of each other.
//    (Before issue #20 the automatic viscosity cap followed h, 0.125 h rho c0 / CFL: 337 Pa s at
//    dx = 0.01 m, and the same layer crept at f H^2 / (3 mu_cap) = 0.03 m/s, 140 times the
//    material's rate, twice that at half the spacing.)
//  - Above yield (tau_y = 150 Pa): the layer slides as a plug over a sheared base; the steady
//    plug speed is u_p = f y_p^2 / (2 mu_p), y_p = H - tau_y / f, f = rho g sin(theta):
//    u_p = 0.400 m/s. Bound: the plug (the top quarter) moves at more than half of u_p after 1 s
//    (the approach to steady state has the time scale rho y_p^2 / mu_p = 0.47 s), and not faster
//    than u_p.
// Quick mode (CI): H/dx = 5, 10 below yield and H/dx = 10 above (H/dx = 15 below yield cost 3/4 of
// the test's 430 s in CI); full mode (TURBID_FULL=1): H/dx = 10, 20, 40 for both.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "tests/validation/validation_support.hpp"
#include "tools/scene_reader.hpp"

namespace {

using turbid::fsi::Simulation;

constexpr double kDepth = 0.1;    // H [m]
constexpr double kLength = 0.32;  // period along the slope [m]: three kernel supports at H/dx = 5
constexpr double kRho = 1800;     // [kg/m^3]
constexpr double kMuP = 10;       // plastic viscosity [Pa s]
constexpr double kM = 100;        // Papanastasiou exponent [s]
constexpr double kG = 9.81;
constexpr double kTheta = 10.0 * 3.14159265358979323846 / 180.0;

std::string layer_scene(double dx, double tau_y, double end) {
  std::ostringstream os;
  os << "name: yield_slope\n"
     << "dimensions: 2\n"
     << "resolution: {particle_spacing: " << dx << ", smoothing_ratio: 2.0}\n"
     << "time: {end: " << end << ", cfl: 0.2}\n"
     << "gravity: [" << kG * std::sin(kTheta) << ", " << -kG * std::cos(kTheta) << "]\n"
     << "numerics:\n"
     << "  density_diffusion: {type: fourtakas, delta: 0.1}\n"
     << "  viscosity: {type: laminar}\n"
     << "  boundary: {type: mdbc, velocity: no_slip}\n"
     << "materials:\n"
     << "  mud: {model: bingham, density: " << kRho << ", viscosity: " << kMuP << ", yield_stress: " << tau_y
     << ", papanastasiou_exponent: " << kM << ", sound_speed: 15}\n"
     << "domain: {min: [0, -0.05], max: [" << kLength << ", 0.2], periodic: [x]}\n"
     << "walls:\n"
     << "  - {box: {min: [0, 0], max: [" << kLength << ", 0.15]}, open: [-x, +x, +y]}\n"
     << "fluids:\n"
     << "  - {material: mud, box: {min: [0, 0], max: [" << kLength << ", " << kDepth << "]}}\n"
     << "output: {every: 1.0, vtk: false}\n";
  return os.str();
}

struct LayerRun {
  double mean_speed_late = 0;  // mean over fluid particles of u_x, averaged over the second half [m/s]
  double plug_speed_end = 0;   // mean u_x of the top quarter at the end [m/s]
  bool implicit = false;
  double wall_seconds = 0;
  unsigned long long steps = 0;
};

LayerRun run_layer(double dx, double tau_y, double end) {
  const std::string path = ::testing::TempDir() + "yield_slope.yaml";
  {
    std::ofstream(path) << layer_scene(dx, tau_y, end);
  }
  Simulation sim(turbid::tools::read_scene_file(path), {"cpu", 0});
  LayerRun r;
  r.implicit = sim.params().implicit_viscosity;
  const auto start = std::chrono::steady_clock::now();
  sim.start();
  double integral = 0, span = 0;
  const auto mean_ux = [&](double y_min) {
    const auto& st = sim.store();
    const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
    const auto* v = static_cast<const float*>(st.raw(sim.fields().velocity));
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    double s = 0;
    int n = 0;
    for (std::size_t i = 0; i < st.size(); ++i)
      if (kind[i] == 0 && x[2 * i + 1] >= y_min) {
        s += v[2 * i];
        ++n;
      }
    return n > 0 ? s / n : 0.0;
  };
  while (sim.time() < end - 1e-12) {
    sim.step();
    if (sim.time() >= 0.5 * end) {
      integral += mean_ux(0.0) * sim.last_time_step();
      span += sim.last_time_step();
    }
  }
  r.mean_speed_late = span > 0 ? integral / span : 0.0;
  r.plug_speed_end = mean_ux(0.75 * kDepth);
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.steps = sim.steps();
  return r;
}

}  // namespace

// The regularised layer's steady creep, exactly: the shear stress f (H - y) equals
// tau_y (1 - exp(-m gamma_dot)) + mu_p gamma_dot (solved for gamma_dot by bisection), u(y) is its
// integral from the bed, and the result is the mean of u over the depth [m/s].
double regularised_creep_mean(double tau_y, double f) {
  constexpr int kN = 4000;
  double u = 0, sum = 0;
  for (int k = 0; k < kN; ++k) {
    const double y = kDepth * (k + 0.5) / kN, tau = f * (kDepth - y);
    double lo = 0, hi = 10;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (tau_y * -std::expm1(-kM * mid) + kMuP * mid < tau ? lo : hi) = mid;
    }
    u += lo * kDepth / kN;
    sum += u;
  }
  return sum / kN;
}

TEST(ValidationYieldSlope, LayerBelowYieldCreepsAtTheMaterialsRateAtEverySpacing) {
  const double tau_y = 600, f = kRho * kG * std::sin(kTheta);
  ASSERT_LT(f * kDepth, tau_y) << "the case must be below yield";
  const double creep = regularised_creep_mean(tau_y, f);
  const auto ratios = turbid::validation::full_mode() ? std::vector<double>{10, 20, 40} : std::vector<double>{5, 10};
  double lo = 1e300, hi = 0;
  for (double ratio : ratios) {
    const double dx = kDepth / ratio;
    const LayerRun r = run_layer(dx, tau_y, 0.5);
    EXPECT_TRUE(r.implicit) << "m tau_y = 6e4 Pa s is integrated implicitly";
    std::printf("[ measured ] below yield, H/dx = %g: mean speed over 0.25-0.5 s %.4e m/s (regularised material %.4e m/s, "
                "%+.1f%%), %llu steps, %.1f s wall\n",
                ratio, r.mean_speed_late, creep, 100 * (r.mean_speed_late / creep - 1), r.steps, r.wall_seconds);
    EXPECT_NEAR(r.mean_speed_late, creep, 0.1 * creep) << "H/dx = " << ratio;
    lo = std::min(lo, r.mean_speed_late);
    hi = std::max(hi, r.mean_speed_late);
  }
  EXPECT_LT(hi / lo, 1.1) << "the same material at every spacing: creep speeds " << lo << " to " << hi << " m/s";
}

TEST(ValidationYieldSlope, LayerAboveYieldSlides) {
  const double tau_y = 150, f = kRho * kG * std::sin(kTheta);
  const double yp = kDepth - tau_y / f;
  const double plug = f * yp * yp / (2 * kMuP);
  for (double ratio : {10.0, 20.0, 40.0}) {
    if (ratio > 10 && !turbid::validation::full_mode()) continue;
    const LayerRun r = run_layer(kDepth / ratio, tau_y, 1.0);
    std::printf("[ measured ] above yield, H/dx = %g: plug speed at 1 s %.4f m/s (steady analytic %.4f m/s), "
                "%llu steps, %.1f s wall\n",
                ratio, r.plug_speed_end, plug, r.steps, r.wall_seconds);
    EXPECT_GT(r.plug_speed_end, 0.5 * plug) << "H/dx = " << ratio;
    EXPECT_LT(r.plug_speed_end, 1.05 * plug) << "H/dx = " << ratio << ": faster than the steady state";
  }
}
