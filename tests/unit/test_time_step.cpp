// Stable time step (sph/solver.hpp `stable_time_step`): the acoustic limit cfl h / (c_max + v_max),
// the force limit cfl sqrt(h / a_max) and the viscous limit factor h^2 / nu_max for laminar
// viscosity (Monaghan 1992; Morris et al. 1997). Reference: the formulas evaluated here in double
// from the same float parameters; the smallest limit must be returned exactly (rel 1e-12).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sph/physics_params.hpp"
#include "sph/solver.hpp"

namespace {

using namespace turbid::sph;

PhysicsParams params(Viscosity visc, double mu, double c0 = 30.0, double h = 0.013) {
  PhysicsParams p;
  p.dimensions = 2;
  p.viscosity = visc;
  p.smoothing_length = Real(h);
  p.material_count = 1;
  p.materials[0].eos = TaitEos::make(1000.0, c0, 7.0, 0.0);
  p.materials[0].sound_speed = Real(c0);
  p.materials[0].dynamic_viscosity = Real(mu);
  return p;
}

double acoustic(const PhysicsParams& p, const TimeStepParams& t, double c, double v) {
  return t.cfl * double(p.smoothing_length) / (c + v);
}
double force(const PhysicsParams& p, const TimeStepParams& t, double a) {
  return t.cfl * std::sqrt(double(p.smoothing_length) / a);
}
double viscous(const PhysicsParams& p, const TimeStepParams& t, double nu) {
  const double h = p.smoothing_length;
  return t.viscous_factor * h * h / nu;
}

TEST(TimeStep, AcousticLimit) {
  const PhysicsParams p = params(Viscosity::artificial, 1e-3);
  TimeStepParams t;
  t.cfl = 0.2;
  const double v = 1.5, a = 9.81;
  const double expected = acoustic(p, t, 30.0, v);
  ASSERT_LT(expected, force(p, t, a)) << "test setup: the acoustic limit must be the smallest";
  EXPECT_NEAR(stable_time_step(p, t, v, a), expected, 1e-12 * expected) << "cfl h / (c + v)";
  // No acceleration at all (fluid at rest, no gravity): only the acoustic limit applies.
  EXPECT_NEAR(stable_time_step(p, t, 0.0, 0.0), acoustic(p, t, 30.0, 0.0), 1e-12 * acoustic(p, t, 30.0, 0.0));
}

TEST(TimeStep, ForceLimit) {
  const PhysicsParams p = params(Viscosity::artificial, 1e-3);
  TimeStepParams t;
  t.cfl = 0.25;
  const double v = 0.5, a = 1.0e6;
  const double expected = force(p, t, a);
  ASSERT_LT(expected, acoustic(p, t, 30.0, v)) << "test setup: the force limit must be the smallest";
  EXPECT_NEAR(stable_time_step(p, t, v, a), expected, 1e-12 * expected) << "cfl sqrt(h / a)";
}

TEST(TimeStep, LaminarViscousLimit) {
  // mu = 1000 Pa s, rho0 = 1000 kg/m^3: nu = 1 m^2/s, 0.125 h^2 / nu = 2.1e-5 s < acoustic 8.4e-5 s.
  const PhysicsParams p = params(Viscosity::laminar, 1000.0);
  TimeStepParams t;
  t.viscous_factor = 0.125;
  const double v = 1.0, a = 9.81;
  const double nu = double(p.materials[0].dynamic_viscosity) / double(p.materials[0].eos.rest_density);
  const double expected = viscous(p, t, nu);
  ASSERT_LT(expected, std::min(acoustic(p, t, 30.0, v), force(p, t, a))) << "test setup";
  EXPECT_NEAR(stable_time_step(p, t, v, a), expected, 1e-12 * expected) << "0.125 h^2 / nu";
}

TEST(TimeStep, ArtificialViscosityHasNoViscousLimit) {
  // Same very viscous material, but with artificial viscosity the Morris limit does not apply.
  const PhysicsParams p = params(Viscosity::artificial, 1000.0);
  TimeStepParams t;
  const double expected = acoustic(p, t, 30.0, 1.0);
  EXPECT_NEAR(stable_time_step(p, t, 1.0, 9.81), expected, 1e-12 * expected) << "cfl h / (c + v)";
}

TEST(TimeStep, LargestSoundSpeedAndViscosityOverMaterials) {
  PhysicsParams p = params(Viscosity::laminar, 1e-3, 30.0);
  p.material_count = 2;
  p.materials[1].eos = TaitEos::make(1950.0, 45.0, 7.0, 0.0);
  p.materials[1].sound_speed = Real(45.0);
  p.materials[1].dynamic_viscosity = Real(1e-3);
  TimeStepParams t;
  const double expected = acoustic(p, t, 45.0, 0.3);
  EXPECT_NEAR(stable_time_step(p, t, 0.3, 1.0), expected, 1e-12 * expected) << "c_max = 45 m/s";
  // A very viscous second material sets nu_max = mu / rho0 of that material.
  p.materials[1].dynamic_viscosity = Real(3900.0);
  const double nu = 3900.0 / 1950.0;
  const double ev = viscous(p, t, nu);
  ASSERT_LT(ev, expected);
  EXPECT_NEAR(stable_time_step(p, t, 0.3, 1.0), ev, 1e-12 * ev) << "nu_max = 2 m^2/s";
}

}  // namespace
