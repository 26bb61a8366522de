// Free structures (motion: free) coupled to the fluid's kick-drift-kick step (fsi/body_coupling.hpp,
// issue #8). References and tolerances, per test:
//  - Newton's third law: a block of water moving at 1 m/s against a free box, no gravity, no walls.
//    Per step, the body's momentum change equals its impulse from the fluid, dt/2 (F(n) + F(n+1)),
//    to double rounding (1e-12 relative: the body is integrated in double); the fluid's momentum
//    change is minus that impulse to the single-precision rounding of the fluid's own sums
//    (1e-6 of sum m|dv| + |J|, the bound test_physics_passes uses for pair sums in float) and of
//    its velocities, stored in float (2 x 2^-24 of sum m|v|: two half-kicks per step).
//  - Free fall far from the fluid: the kick-drift-kick map is exact for a constant force, so
//    y = y0 - g t^2 / 2 and v = -g t to double rounding (1e-12 m, 1e-12 m/s); x and the orientation
//    do not change at all; every body particle sits at its analytic place to float rounding
//    (4 ulp of the coordinate); a locked y keeps y0 bit for bit.
//  - Mass properties of a sampled box (mass_properties.hpp: exact for a box of square cells):
//    m = rho a b and I_zz = m (a^2 + b^2) / 12 to 1e-12 relative; a given mass and centre.
//  - A scene whose structures are all fixed registers no body field and builds no coupling.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "tests/unit/body_test_support.hpp"
#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;
using test::cpu;
using test::scene_of;
using test::replace;





struct Momentum {
  double fluid[2] = {0, 0};
  double fluid_abs = 0;  // sum m |v| per component, for the scale of the rounding
};

class NewtonThirdLaw : public ::testing::TestWithParam<const char*> {};

TEST_P(NewtonThirdLaw, FluidMomentumChangeIsMinusTheBodyImpulse) {
  fsi::Simulation sim(scene_of(test::push_scene("free", GetParam())), cpu());
  sim.start();
  ASSERT_NE(sim.bodies(), nullptr);
  const auto& store = sim.store();
  const auto& ids = sim.fields();
  auto fluid_state = [&](std::vector<double>& v_out) {
    const auto* m = store.data<float>(ids.mass);
    const auto* v = store.data<float>(ids.velocity);
    const auto* kind = store.data<std::uint8_t>(ids.kind);
    const auto* id = store.data<std::uint32_t>(ids.id);
    Momentum p;
    v_out.assign(2 * store.size() + 2, 0.0);
    for (std::size_t i = 0; i < store.size(); ++i) {
      if (kind[i] != 0) continue;
      for (int a = 0; a < 2; ++a) {
        p.fluid[a] += double(m[i]) * double(v[2 * i + a]);
        p.fluid_abs += double(m[i]) * std::abs(double(v[2 * i + a]));
        v_out[2 * id[i] + a] = double(m[i]) * double(v[2 * i + a]);
      }
    }
    return p;
  };
  double worst_fluid = 0, worst_body = 0, largest_impulse = 0;
  for (int step = 0; step < 30; ++step) {
    std::vector<double> mv0, mv1;
    const Momentum p0 = fluid_state(mv0);
    const fsi::RigidBody& b = sim.bodies()->body(0);
    const Eigen::Vector3d F0 = sim.bodies()->fluid_load(0).force;
    const Eigen::Vector3d P0 = b.linear_momentum();
    sim.step();
    const double dt = sim.last_time_step();
    const Eigen::Vector3d F1 = sim.bodies()->fluid_load(0).force;
    const Eigen::Vector3d J = 0.5 * dt * (F0 + F1);
    const Eigen::Vector3d dP = b.linear_momentum() - P0;
    const Momentum p1 = fluid_state(mv1);
    double scale = J.norm();
    for (std::size_t k = 0; k < mv0.size(); ++k) scale += std::abs(mv1[k] - mv0[k]);
    for (int a = 0; a < 2; ++a) {
      const double fluid_residual = (p1.fluid[a] - p0.fluid[a]) + J[a];
      worst_fluid = std::max(worst_fluid, std::abs(fluid_residual) / scale);
      worst_body = std::max(worst_body, std::abs(dP[a] - J[a]) / std::max(J.norm(), 1e-300));
      // Plus the storage of every velocity in float: each of the step's two half-kicks rounds it by
      // at most half an ulp, 2^-24 of |v| (the block moves at 1 m/s while a step changes it by 1e-3).
      const double stored = 2 * std::ldexp(1.0, -24) * p1.fluid_abs;
      EXPECT_LE(std::abs(fluid_residual), 1e-6 * scale + stored) << "step " << step << " axis " << a;
      EXPECT_LE(std::abs(dP[a] - J[a]), 1e-12 * J.norm()) << "step " << step << " axis " << a;
    }
    largest_impulse = std::max(largest_impulse, J.norm());
  }
  // The fluid does push: the test would pass trivially with no contact.
  EXPECT_GT(largest_impulse, 1e-4);
  EXPECT_GT(sim.bodies()->body(0).velocity().x(), 0.0);
  std::printf("[ measured ] %s: largest body impulse per step %.3e N s/m; |dP_fluid + J| / scale up to %.2e; "
              "|dP_body - J| / |J| up to %.2e\n",
              GetParam(), largest_impulse, worst_fluid, worst_body);
}

INSTANTIATE_TEST_SUITE_P(Boundaries, NewtonThirdLaw, ::testing::Values("dbc", "mdbc"));

TEST(BodyCoupling, ParticlesAreTheRigidImageOfTheBody) {
  fsi::Simulation sim(scene_of(test::push_scene("free", "mdbc")), cpu());
  sim.start();
  for (int step = 0; step < 20; ++step) sim.step();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  ASSERT_GT(b.angular_velocity().norm(), 0.0) << "the push should turn the tilted box";
  const auto& s = sim.store();
  const auto& ids = sim.fields();
  const auto* x = s.data<float>(ids.position);
  const auto* v = s.data<float>(ids.velocity);
  const auto* r0 = s.data<float>(ids.body_offset);
  const auto* n = s.data<float>(ids.boundary_normal);
  const auto* n0 = s.data<float>(ids.body_normal);
  const auto* kind = s.data<std::uint8_t>(ids.kind);
  const Eigen::Matrix3d R = b.orientation().toRotationMatrix();
  const Eigen::Vector3d w = b.angular_velocity();
  std::size_t count = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != 2) continue;
    ++count;
    const Eigen::Vector3d r = R * Eigen::Vector3d(r0[2 * i], r0[2 * i + 1], 0);
    const Eigen::Vector3d xe = b.position() + r, ve = b.velocity() + w.cross(r);
    const Eigen::Vector3d ne = R * Eigen::Vector3d(n0[2 * i], n0[2 * i + 1], 0);
    for (int a = 0; a < 2; ++a) {
      // One rounding to float of the double value (half an ulp, 6e-8 relative).
      EXPECT_LE(std::abs(x[2 * i + a] - xe[a]), 6e-8 * std::abs(xe[a]) + 1e-12);
      EXPECT_LE(std::abs(v[2 * i + a] - ve[a]), 6e-8 * std::abs(ve[a]) + 1e-12);
      EXPECT_LE(std::abs(n[2 * i + a] - ne[a]), 6e-8 * std::abs(ne[a]) + 1e-12);
    }
  }
  EXPECT_EQ(count, sim.summary().structure_particles);
}


TEST(BodyCoupling, FreeFallFarFromTheFluidIsExact) {
  fsi::Simulation sim(scene_of(test::fall_scene("free")), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const Eigen::Vector3d x0 = b.position();
  const auto& s = sim.store();
  const auto& ids = sim.fields();
  // Each body particle's start, by id.
  const std::vector<double> start = test::positions_by_id_2d(sim);
  const double g = 9.81;
  while (sim.time() < 0.3) sim.step();
  const double t = sim.time();
  const double y = x0.y() - 0.5 * g * t * t;
  std::printf("[ measured ] free fall to t = %.6f s in %llu steps: y - y_exact = %.3e m, v - v_exact = %.3e m/s\n", t,
              static_cast<unsigned long long>(sim.steps()), b.position().y() - y, b.velocity().y() + g * t);
  EXPECT_LE(std::abs(b.position().y() - y), 1e-12);
  EXPECT_LE(std::abs(b.velocity().y() + g * t), 1e-12);
  EXPECT_EQ(b.position().x(), x0.x());
  EXPECT_EQ(b.velocity().x(), 0.0);
  EXPECT_EQ(b.orientation().w(), 1.0);
  EXPECT_EQ(b.angular_momentum().norm(), 0.0);
  const auto* x = s.data<float>(ids.position);
  const auto* kind = s.data<std::uint8_t>(ids.kind);
  const auto* id = s.data<std::uint32_t>(ids.id);
  std::size_t body_particles = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != 2) continue;
    ++body_particles;
    const double xe = start[2 * id[i]], ye = start[2 * id[i] + 1] - 0.5 * g * t * t;
    EXPECT_LE(std::abs(x[2 * i] - xe), 4 * 1.2e-7 * std::abs(xe));
    EXPECT_LE(std::abs(x[2 * i + 1] - ye), 4 * 1.2e-7 * std::abs(ye));
  }
  EXPECT_EQ(body_particles, sim.summary().structure_particles);
}

TEST(BodyCoupling, LockedAxisDoesNotMove) {
  fsi::Simulation sim(scene_of(test::fall_scene("free", ", lock: [y]")), cpu());
  sim.start();
  const Eigen::Vector3d x0 = sim.bodies()->body(0).position();
  for (int i = 0; i < 50; ++i) sim.step();
  EXPECT_EQ(sim.bodies()->body(0).position(), x0);
  EXPECT_EQ(sim.bodies()->body(0).velocity().norm(), 0.0);
}

TEST(BodyCoupling, MassPropertiesOfASampledBox) {
  // A 0.2 x 0.1 m box of density 500 kg/m^3: 10 kg/m, I_zz = m (a^2 + b^2) / 12.
  fsi::Simulation sim(scene_of(replace(test::fall_scene("free"), "size: [0.1, 0.1]", "size: [0.2, 0.1]")), cpu());
  ASSERT_EQ(sim.summary().free_bodies.size(), 1u);
  const auto& mp = sim.summary().free_bodies[0].mass_properties;
  const double m = 500 * 0.2 * 0.1;
  EXPECT_NEAR(mp.mass, m, 1e-12 * m);
  EXPECT_NEAR(mp.inertia(2, 2), m * (0.04 + 0.01) / 12, 1e-12 * m * 0.05 / 12);
  EXPECT_NEAR(mp.centre_of_mass.x(), 1.0, 1e-12);
  EXPECT_NEAR(mp.centre_of_mass.y(), 1.0, 1e-12);
  // Given mass and centre: the inertia of the uniform shape moved to the given centre.
  fsi::Simulation given(scene_of(replace(test::fall_scene("free"), "density: 500", "mass: 3, centre_of_mass: [1.0, 0.99]")), cpu());
  const auto& g = given.summary().free_bodies[0].mass_properties;
  EXPECT_EQ(g.mass, 3.0);
  EXPECT_EQ(g.centre_of_mass.y(), 0.99);
  EXPECT_NEAR(g.inertia(2, 2), 3 * 0.02 / 12 + 3 * 0.01 * 0.01, 1e-12);
}

TEST(BodyCoupling, FixedStructuresPayNothing) {
  fsi::Simulation sim(scene_of(replace(test::fall_scene("free"), "motion: free, density: 500", "motion: fixed")), cpu());
  EXPECT_EQ(sim.bodies(), nullptr);
  EXPECT_EQ(sim.fields().body_offset, -1);
  EXPECT_EQ(sim.fields().body_normal, -1);
  EXPECT_FALSE(sim.store().find("body_offset").has_value());
}

}  // namespace
