// Herschel-Bulkley-Papanastasiou rheology (sph/rheology.hpp) against its closed forms
// (physics.md C8): mu_eff = K gamma_dot^(n-1) + tau_y (1 - exp(-m gamma_dot)) / gamma_dot, the
// limit m tau_y (+ K) at vanishing shear, and the shear rate sqrt(2 D:D) of simple shear and of
// pure extension. Tolerances are float rounding (Real is float), relative 1e-6 unless stated.
#include <gtest/gtest.h>

#include <cmath>

#include "sph/rheology.hpp"

namespace {

using turbid::sph::Real;
using turbid::sph::Rheology;

Rheology bingham(double tau_y, double mu_b, double m) {
  Rheology r;
  r.yield_stress = Real(tau_y);
  r.consistency = Real(mu_b);
  r.regularisation = Real(m);
  return r;
}

TEST(Rheology, NewtonianViscosityIsConstant) {
  Rheology r;
  r.consistency = Real(1e-3);
  for (double g : {0.0, 1e-6, 1.0, 1e4}) EXPECT_EQ(r.effective_viscosity(Real(g)), Real(1e-3)) << g;
}

// Far from the yield point (m gamma_dot >> 1) Papanastasiou's term is tau_y / gamma_dot: the
// stress mu_eff gamma_dot is the Bingham law tau_y + mu_B gamma_dot.
TEST(Rheology, BinghamStressAboveYield) {
  const Rheology r = bingham(100.0, 2.0, 1000.0);
  for (double g : {0.1, 1.0, 10.0, 100.0}) {
    const double stress = double(r.effective_viscosity(Real(g))) * g;
    EXPECT_NEAR(stress, 100.0 + 2.0 * g, 1e-6 * (100.0 + 2.0 * g)) << "gamma_dot = " << g;
  }
}

// At vanishing shear mu_eff -> m tau_y + K (L'Hopital), and on the way there the float result
// keeps float accuracy against the closed form in double (1 - exp(-x) computed as -expm1(-x),
// which keeps its digits where 1 - exp(-x) would lose them; relative 1e-6).
TEST(Rheology, VanishingShearLimitKeepsItsDigits) {
  const Rheology r = bingham(50.0, 0.5, 200.0);
  EXPECT_NEAR(r.effective_viscosity(Real(0)), 200.0 * 50.0 + 0.5, 1e-6 * 10000.5);
  for (double x : {1e-8, 1e-6, 1e-4, 1e-2, 1.0}) {
    const double g = double(Real(x / 200.0));  // the float shear rate the function receives
    const double exact = 50.0 * -std::expm1(-200.0 * g) / g + 0.5;
    EXPECT_NEAR(r.effective_viscosity(Real(g)), exact, 1e-6 * exact) << "m gamma_dot = " << x;
  }
}

// Herschel-Bulkley, n = 0.5 (shear-thinning) and n = 1.5 (shear-thickening), m gamma_dot >> 1:
// stress = tau_y + K gamma_dot^n.
TEST(Rheology, HerschelBulkleyStress) {
  for (double n : {0.5, 1.5}) {
    Rheology r = bingham(30.0, 4.0, 1000.0);
    r.flow_index = Real(n);
    for (double g : {0.5, 5.0, 50.0}) {
      const double stress = double(r.effective_viscosity(Real(g))) * g;
      const double expected = 30.0 + 4.0 * std::pow(g, n);
      EXPECT_NEAR(stress, expected, 1e-6 * expected) << "n = " << n << ", gamma_dot = " << g;
    }
  }
}

// The cap bounds mu_eff where it would diverge (power law n < 1 at rest) or be huge (m tau_y).
TEST(Rheology, CapBoundsTheViscosity) {
  Rheology r = bingham(1000.0, 1.0, 100.0);  // m tau_y = 1e5 Pa s at rest
  r.max_viscosity = Real(500.0);
  EXPECT_EQ(r.effective_viscosity(Real(0)), Real(500.0));
  EXPECT_NEAR(r.effective_viscosity(Real(100.0)), 1000.0 / 100.0 + 1.0, 1e-5) << "uncapped where below the cap";
  Rheology thinning;
  thinning.consistency = Real(1.0);
  thinning.flow_index = Real(0.5);
  thinning.max_viscosity = Real(50.0);
  EXPECT_EQ(thinning.effective_viscosity(Real(0)), Real(50.0));
  EXPECT_EQ(thinning.effective_viscosity(Real(1e-8)), Real(50.0));
  EXPECT_NEAR(thinning.effective_viscosity(Real(4.0)), 0.5, 1e-6);
}

// gamma_dot = sqrt(2 D:D): simple shear v = (k y, 0, 0) gives |k|; pure extension
// v = (e x, -e y) gives 2 |e|; a rigid rotation gives 0.
TEST(Rheology, ShearRateOfSimpleFlows) {
  const Real shear[2][2] = {{0, Real(3.0)}, {0, 0}};
  EXPECT_NEAR(turbid::sph::shear_rate<2>(shear), 3.0, 1e-6);
  const Real extension[3][3] = {{Real(0.5), 0, 0}, {0, Real(-0.5), 0}, {0, 0, 0}};
  EXPECT_NEAR(turbid::sph::shear_rate<3>(extension), 1.0, 1e-6);
  const Real rotation[2][2] = {{0, Real(-2.0)}, {Real(2.0), 0}};
  EXPECT_EQ(turbid::sph::shear_rate<2>(rotation), Real(0));
}

}  // namespace
