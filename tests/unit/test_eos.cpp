// Tait (Cole) equation of state (sph/eos.hpp, physics.md C2 and D8). References: the analytic
// inverse p(rho(p)) = p, the analytic rest state p(rho0) = p_b, and the hydrostatic density
// rho_h = rho0 (1 + rho0 g d / B)^(1/gamma), which inverts the Tait law exactly, so that
// p(rho_h) - p_b = rho0 g d is exact up to rounding.
#include <gtest/gtest.h>

#include <cmath>

#include "sph/eos.hpp"

namespace {

using turbid::sph::Real;
using turbid::sph::TaitEos;

struct EosCase {
  double rho0, c0, gamma, pb;
};
constexpr EosCase kCases[] = {
    {1000.0, 30.0, 7.0, 0.0},      // water, dam-break scale
    {1950.0, 45.0, 7.0, 1.0e4},    // saturated sand with a background pressure (physics.md A3)
    {1000.0, 10.0, 1.0, 500.0},    // linear law (gamma = 1)
};

TEST(EosTait, StiffnessFromSoundSpeed) {
  for (const auto& c : kCases) {
    const TaitEos e = TaitEos::make(c.rho0, c.c0, c.gamma, c.pb);
    // Analytic: B = c0^2 rho0 / gamma (physics.md C2), float storage: rel 1e-7.
    EXPECT_NEAR(e.stiffness, c.c0 * c.c0 * c.rho0 / c.gamma, 1e-7 * c.c0 * c.c0 * c.rho0 / c.gamma);
    EXPECT_EQ(e.rest_density, Real(c.rho0));
    EXPECT_EQ(e.background_pressure, Real(c.pb));
  }
}

TEST(EosTait, RestDensityGivesBackgroundPressure) {
  for (const auto& c : kCases) {
    const TaitEos e = TaitEos::make(c.rho0, c.c0, c.gamma, c.pb);
    // Analytic: (rho0/rho0)^gamma - 1 = 0 exactly (pow(1, y) == 1 in IEEE arithmetic), so the
    // pressure is exactly p_b and the inverse gives exactly rho0.
    EXPECT_EQ(e.pressure(e.rest_density), e.background_pressure) << "rho0 = " << c.rho0;
    EXPECT_EQ(e.density(e.background_pressure), e.rest_density) << "rho0 = " << c.rho0;
  }
}

TEST(EosTait, PressureInvertsDensity) {
  for (const auto& c : kCases) {
    const TaitEos e = TaitEos::make(c.rho0, c.c0, c.gamma, c.pb);
    const double B = e.stiffness;
    // Reference: analytic inverse. The float round trip loses about gamma * eps * B (the rounding of
    // rho, amplified by rho^gamma), so the relative tolerance 1e-5 holds where |p - p_b| >= 0.1 B
    // ...
    for (double s : {-0.9, -0.5, -0.1, 0.1, 0.5, 1.0, 3.0, 10.0}) {
      const Real p = Real(c.pb + s * B);
      const Real rho = e.density(p);
      EXPECT_NEAR(e.pressure(rho), p, 1e-5 * std::abs(double(p))) << "p - p_b = " << s << " B, rho0 = " << c.rho0;
    }
    // ... and near the rest state the error is absolute, below 1e-6 B (16 eps B).
    for (double s : {-1e-2, -1e-4, 1e-6, 1e-4, 1e-2}) {
      const Real p = Real(c.pb + s * B);
      EXPECT_NEAR(e.pressure(e.density(p)), p, 1e-6 * B) << "p - p_b = " << s << " B, rho0 = " << c.rho0;
    }
  }
}

TEST(EosTait, DensityIncreasesWithPressure) {
  const TaitEos e = TaitEos::make(1000.0, 30.0, 7.0, 0.0);
  // Analytic: dp/drho = c0^2 (rho/rho0)^(gamma-1) > 0; at rho0 the slope is c0^2 (finite
  // difference over +-0.1 kg/m^3, float rounding ~ 1e-2 Pa / 0.2 -> rel 1e-4; tolerance rel 1e-3).
  const Real hi = Real(1000.1), lo = Real(999.9);
  const double slope = (double(e.pressure(hi)) - double(e.pressure(lo))) / (double(hi) - double(lo));
  EXPECT_NEAR(slope, 900.0, 0.9) << "dp/drho at rho0 = c0^2";
  EXPECT_GT(e.density(Real(1e5)), e.density(Real(1e4)));
}

TEST(EosTait, HydrostaticDensityGivesHydrostaticPressure) {
  const double g = 9.81;
  for (const auto& c : kCases) {
    const TaitEos e = TaitEos::make(c.rho0, c.c0, c.gamma, c.pb);
    const double B = e.stiffness, rho0 = e.rest_density, gamma = e.gamma;
    EXPECT_EQ(e.hydrostatic_density(g, 0.0), rho0) << "zero depth gives rho0";
    for (double depth : {0.5, 1.0, 1.6, 5.0}) {
      const double rho = e.hydrostatic_density(g, depth);
      const double target = rho0 * g * depth;
      // Tait is inverted exactly by construction: in double the law gives rho0 g d to round-off.
      const double p_double = B * (std::pow(rho / rho0, gamma) - 1.0);
      EXPECT_NEAR(p_double, target, 1e-12 * target) << "double Tait at depth " << depth;
      // The engine's float pressure of the float density: rounding of rho (rel 6e-8) times gamma
      // B / (rho0 g d) stays below 2e-5 for d >= 0.5 m with these materials, hence 1e-4.
      const double p_float = double(e.pressure(Real(rho))) - double(e.background_pressure);
      EXPECT_NEAR(p_float, target, 1e-4 * target) << "float pressure at depth " << depth << ", rho0 = " << c.rho0;
    }
  }
}

}  // namespace

// The walls' lower bound (sph/eos.hpp, no_tension_density): zero absolute pressure. Reference: the
// analytic inverse, p(rho_min) = 0; without background pressure it is rest density exactly (so
// scenes without one keep the clamp at rho0 bit for bit), with one it lies below rho0.
TEST(EosTait, NoTensionDensityIsZeroAbsolutePressure) {
  for (const auto& c : kCases) {
    const TaitEos e = TaitEos::make(c.rho0, c.c0, c.gamma, c.pb);
    const Real rho_min = e.no_tension_density();
    EXPECT_NEAR(e.pressure(rho_min), 0.0, 1e-5 * e.stiffness) << "p_b = " << c.pb;
    if (c.pb == 0.0) {
      EXPECT_EQ(rho_min, e.rest_density);
    } else {
      EXPECT_LT(rho_min, e.rest_density);
    }
  }
}
