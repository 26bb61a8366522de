// Validation D5/D6 (docs/validation.md): plane Poiseuille flow in a channel of width 2H = 0.02 m,
// periodic along x, no-slip mDBC plates, driven by a body force g_x (scenes/poiseuille_*_2d.yaml).
//
// References:
//   - Newtonian, from rest: the series solution of Morris, Fox & Zhu (1997), physics.md D5;
//   - Bingham and Herschel-Bulkley (n = 0.5, 1.5), steady: the analytic profiles of physics.md D6,
//     with the plug half-width y0 = tau_y / (rho g_x).
// Measured quantity: the fluid particles' mean u_x in bins of one spacing across the channel;
// L2 error = sqrt(sum (u - u_exact)^2 / sum u_exact^2) over the bins; the plug half-width from a
// line fitted to the shear rate (plug_half_width below).
// Tolerances: what the CI spacing H/dx = 10 earns (h = 1.5 dx is 0.15 H, so the kernel-smoothed
// shear rate rounds the profile near the walls and the plug edge): each case's measured figure with
// a margin, stated per case below. The bounds (L2 <= 2%, plug within 5%) apply at the finest
// documented spacing; docs/validation.md has the convergence.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ostream>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"
#include "tests/validation/validation_support.hpp"

namespace {

using turbid::fsi::Scene;
using turbid::fsi::Simulation;

constexpr double kHalfWidth = 0.01;  // H [m], as in the scenes
constexpr double kPi = 3.14159265358979323846;

Scene poiseuille_scene(const std::string& name, double dx) {
  Scene s = turbid::tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/" + name + ".yaml");
  s.particle_spacing = dx;
  s.output.vtk = false;
  return s;
}

struct Profile {
  std::vector<double> y, u, shear_rate;  // bin centre [m], mean u_x [m/s], mean shear rate [1/s]
};

// Fluid particles binned by y in bins of dx over [0, 2H].
Profile binned(Simulation& sim, double dx) {
  sim.sync_to_host();
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const auto* x = static_cast<const float*>(st.raw(ids.position));
  const auto* v = static_cast<const float*>(st.raw(ids.velocity));
  const auto* kind = st.data<std::uint8_t>(ids.kind);
  const float* rate = ids.shear_rate >= 0 ? st.data<float>(ids.shear_rate) : nullptr;
  const int bins = int(std::lround(2 * kHalfWidth / dx));
  std::vector<double> su(bins, 0), ss(bins, 0), n(bins, 0);
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    const int b = int(std::floor(x[2 * i + 1] / dx));
    if (b < 0 || b >= bins) continue;
    su[b] += v[2 * i];
    if (rate) ss[b] += rate[i];
    n[b] += 1;
  }
  Profile p;
  for (int b = 0; b < bins; ++b) {
    if (n[b] == 0) continue;
    p.y.push_back((b + 0.5) * dx);
    p.u.push_back(su[b] / n[b]);
    p.shear_rate.push_back(ss[b] / n[b]);
  }
  return p;
}

template <class Exact>
double l2_error(const Profile& p, Exact exact) {
  double num = 0, den = 0;
  for (std::size_t k = 0; k < p.y.size(); ++k) {
    const double ue = exact(p.y[k]);
    num += (p.u[k] - ue) * (p.u[k] - ue);
    den += ue * ue;
  }
  return std::sqrt(num / den);
}

// Plug half-width from the shear rate: in the yielded layer gamma_dot^n = (G |y - H| - tau_y) / K
// is linear in |y - H| and vanishes at y0 (physics.md D6). A straight line is fitted to the bins'
// mean gamma_dot^n where it exceeds 30% of its largest value (away from the plug edge, which the
// kernel rounds off) and extrapolated to zero.
double plug_half_width(const Profile& p, double n) {
  double gmax = 0;
  for (double g : p.shear_rate) gmax = std::max(gmax, std::pow(g, n));
  double s1 = 0, se = 0, sg = 0, see = 0, seg = 0;
  for (std::size_t k = 0; k < p.y.size(); ++k) {
    const double g = std::pow(p.shear_rate[k], n);
    if (g <= 0.3 * gmax) continue;
    const double e = std::abs(p.y[k] - kHalfWidth);
    s1 += 1;
    se += e;
    sg += g;
    see += e * e;
    seg += e * g;
  }
  const double slope = (s1 * seg - se * sg) / (s1 * see - se * se);
  const double intercept = (sg - slope * se) / s1;
  return -intercept / slope;
}

void run_to(Simulation& sim, double t) {
  while (sim.time() < t - 1e-12) sim.step();
}

}  // namespace

// Newtonian, from rest (Morris et al. 1997): the profile at four times against the series.
// dx = 0.5 mm (H/dx = 20; it costs a few seconds). Measured: 1.2%, 1.4%, 1.5%, 1.7% at
// t = 0.2, 0.5, 1, 2 s (the near-wall bins lag: the no-slip plane of mDBC); tolerance 2%.
TEST(ValidationPoiseuille, NewtonianTransientMatchesSeriesSolution) {
  Scene s = poiseuille_scene("poiseuille_newtonian_2d", 0.0005);
  const double L = 2 * kHalfWidth;
  const double nu = s.materials[0].viscosity / s.materials[0].density;
  const double F = s.gravity[0];
  Simulation sim(s, {"cpu", 0});
  sim.start();
  for (double t : {0.2, 0.5, 1.0, 2.0}) {
    run_to(sim, t);
    const double time = sim.time();
    const auto exact = [&](double y) {
      double u = F / (2 * nu) * y * (L - y);
      for (int n = 0; n < 200; ++n) {
        const double k = 2 * n + 1;
        u -= 4 * F * L * L / (nu * kPi * kPi * kPi * k * k * k) * std::sin(k * kPi * y / L) *
             std::exp(-k * k * kPi * kPi * nu * time / (L * L));
      }
      return u;
    };
    const double err = l2_error(binned(sim, s.particle_spacing), exact);
    EXPECT_LT(err, 0.02) << "L2 error of the profile at t = " << time << " s";
    std::printf("Newtonian Poiseuille, H/dx = %.0f: t = %.2f s, L2 error %.2f%%\n", kHalfWidth / s.particle_spacing,
                time, 100 * err);
  }
}

struct SteadyCase {
  const char* scene;
  double dx;              // [m]
  double end;             // [s]: steady by then (L2 error changes by < 0.5% over the last second)
  double tolerance;       // L2 error bound at this spacing
  double plug_tolerance;  // relative bound on the plug half-width; < 0: not asserted at this spacing
  const char* measured;
};

void PrintTo(const SteadyCase& c, std::ostream* os) { *os << c.scene; }

class ValidationPoiseuilleSteady : public ::testing::TestWithParam<SteadyCase> {};

// Steady yield-stress profiles (physics.md D6) at H/dx = 10; with TURBID_FULL=1 at H/dx = 20, where
// the full stress measured L2 2.16% / 1.50% / 1.89% and plug +5.4% / +6.0% / +5.2% (Bingham, n = 0.5,
// n = 1.5): bounds 2.5% and 7%. The rheology issue's bounds (L2 2%, plug 5%) hold at H/dx = 40
// (TURBID_POISEUILLE_REFINE=4; Bingham 1.49%, +2.6%), docs/validation.md D6.
TEST_P(ValidationPoiseuilleSteady, ProfileAndPlugMatchAnalyticSolution) {
  SteadyCase c = GetParam();
  if (turbid::validation::full_mode()) {
    // TURBID_POISEUILLE_REFINE=4 runs H/dx = 40 (the convergence table of docs/validation.md D6).
    const char* refine = std::getenv("TURBID_POISEUILLE_REFINE");
    c.dx /= refine ? std::max(1, std::atoi(refine)) : 2;
    c.tolerance = c.dx < 0.0004 ? 0.02 : 0.025;
    if (c.plug_tolerance > 0) c.plug_tolerance = c.dx < 0.0004 ? 0.05 : 0.07;
  }
  SCOPED_TRACE(std::string(c.scene) + ", measured " + c.measured);
  Scene s = poiseuille_scene(c.scene, c.dx);
  s.end_time = c.end;
  const auto& m = s.materials[0];
  const double H = kHalfWidth;
  const double G = m.density * s.gravity[0];  // driving gradient [Pa/m]
  const double y0 = m.yield_stress / G;       // plug half-width [m]
  const bool bingham = m.model == "bingham";
  const double K = bingham ? m.viscosity : m.consistency;
  const double n = bingham ? 1.0 : m.flow_index;
  const auto exact = [&](double y) {
    const double eta = std::max(std::abs(y - H), y0);
    const double e = (n + 1) / n;
    return n / (n + 1) * std::pow(G / K, 1 / n) * (std::pow(H - y0, e) - std::pow(eta - y0, e));
  };
  Simulation sim(s, {"cpu", 0});
  sim.start();
  run_to(sim, c.end);
  const Profile p = binned(sim, c.dx);
  const double err = l2_error(p, exact);
  EXPECT_LT(err, c.tolerance) << "L2 error of the steady profile";
  const double plug = plug_half_width(p, n);
  if (c.plug_tolerance > 0) {
    EXPECT_NEAR(plug, y0, c.plug_tolerance * y0) << "plug half-width [m]";
  }
  std::printf("%s, H/dx = %.0f: L2 error %.2f%%, plug half-width %.4g m (exact %.4g m, %+.1f%%)\n", c.scene,
              H / c.dx, 100 * err, plug, y0, 100 * (plug / y0 - 1));
}

INSTANTIATE_TEST_SUITE_P(
    Rheology, ValidationPoiseuilleSteady,
    // Measured at H/dx = 10 with the scenes' h = 1.5 dx and the full stress (the default for these
    // implicit materials, docs/validation.md D6): Bingham (2 s) L2 3.11%, plug +11.1%; n = 1.5 (3 s;
    // at 2 s it is still 1% off its steady profile) L2 3.11%, plug +15.0%; n = 0.5 (slowest to
    // settle, 4 s) L2 1.94%, plug +4.9%. Bounds: these with a margin. (With the Laplacian form, until
    // 2026-12-03: 4.19% / -10.6%, 2.65% / +1.5%, 7.75% / -46%.)
    ::testing::Values(SteadyCase{"poiseuille_bingham_2d", 0.001, 2.0, 0.04, 0.15, "L2 3.11%, plug +11.1%"},
                      SteadyCase{"poiseuille_hb_thinning_2d", 0.001, 4.0, 0.03, 0.10, "L2 1.94%, plug +4.9%"},
                      SteadyCase{"poiseuille_hb_thickening_2d", 0.001, 3.0, 0.04, 0.20, "L2 3.11%, plug +15.0%"}),
    [](const ::testing::TestParamInfo<SteadyCase>& info) {
      const std::string name = info.param.scene;
      return name.substr(11, name.size() - 14);  // poiseuille_<case>_2d -> <case>
    });
