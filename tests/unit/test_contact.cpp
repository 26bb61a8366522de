// DEM contact law (fsi/contact.hpp), alone and driving a rigid body (fsi/rigid_body.hpp) stepped
// kick-drift-kick at the contact time step t_c / 50, no fluid:
//  (a) Hertz: the normal force of a static contact equals (4/3) E* sqrt(R*) delta^(3/2), with E*
//      and R* written out by hand for three pairs (sphere-sphere, sphere-rigid plane, unlike
//      materials), relative 1e-12;
//  (b) the damping factor found for a restitution e gives back e through the dimensionless contact
//      (within 1e-6, the integration's own accuracy), and alpha(1) = 0;
//  (c) a sphere dropped on a rigid plane under gravity rebounds with the chosen restitution
//      (e = 0.3, 0.6, 0.9): exit speed / impact speed within 5% (the reference neglects gravity
//      during the ~3 ms contact, about -1.5% at e = 0.3), and the force acts for 0.7 to 1.02 t_c;
//  (c') the time-step rule t_c / 50 alone: without gravity, over ten phases of the first touch
//      within a step (the dashpot's delta^(1/4) switches on steeply, so the phase matters), the
//      rebound gives e within 2% for e = 0.3, 0.6, 0.9;
//  (d) a sphere that cannot roll (rotation locked) on an incline: slides with a = g (sin theta -
//      mu cos theta) within 2% when tan theta > mu; when tan theta < mu it moves less than twice
//      the static elongation of the tangential spring, m g sin theta / k_t (the overshoot bound of
//      a suddenly loaded undamped spring; damping only lowers it), over 0.5 s in which sliding
//      would cover metres;
//  (e) the tangential force never exceeds mu F_n;
//  (f) contact torque: a sphere launched sliding without spin on a level floor rolls after
//      t = 2 v0 / (7 mu g) at v = 5/7 v0 (Coulomb friction decelerates it by mu g and spins it up
//      by 5 mu g / (2 R)); the final speed within 1% and the contact point at rest (|v - w (R -
//      delta/2)| below 1e-3 v0) after three times that.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "fsi/contact.hpp"

namespace {

using namespace turbid;
using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kG = 9.81;

TEST(Contact, HertzForceMatchesTheFormula) {
  struct Case {
    fsi::ContactSide a, b;
    double E_star, R_star, overlap;
  };
  const double E1 = 2e9, E2 = 7e10, nu1 = 0.3, nu2 = 0.25;
  const Case cases[] = {
      // Equal spheres, nu = 0: E* = E/2, R* = R/2.
      {{2e9, 0, 0.02, 1}, {2e9, 0, 0.02, 1}, 1e9, 0.01, 1e-4},
      // A sphere on a rigid, fixed plane: E* = E / (1 - nu^2), R* = R.
      {{E1, nu1, 0.05, 1.3}, {kInf, 0, kInf, kInf}, E1 / (1 - nu1 * nu1), 0.05, 2e-5},
      // Unlike materials and radii.
      {{E1, nu1, 0.03, 0.2}, {E2, nu2, 0.08, 0.9},
       1 / ((1 - nu1 * nu1) / E1 + (1 - nu2 * nu2) / E2), 1 / (1 / 0.03 + 1 / 0.08), 3e-6},
  };
  for (const Case& c : cases) {
    const fsi::ContactLaw law = fsi::make_contact_law(c.a, c.b, 0.7, 0.4);
    const double expected = 4.0 / 3.0 * c.E_star * std::sqrt(c.R_star) * std::pow(c.overlap, 1.5);
    fsi::TangentialSpring spring;
    const fsi::ContactForce f = fsi::contact_force(law, c.overlap, Vector3d::UnitZ(), Vector3d::Zero(), spring, 1e-5);
    std::printf("  Hertz: F = %.15g N, formula %.15g N\n", f.normal_force, expected);
    EXPECT_NEAR(f.normal_force, expected, 1e-12 * expected);
    EXPECT_NEAR(f.force.z(), expected, 1e-12 * expected);
    EXPECT_NEAR(fsi::hertz_normal_force(law.effective_modulus, law.effective_radius, c.overlap), expected,
                1e-12 * expected);
  }
  EXPECT_EQ(fsi::hertz_normal_force(1e9, 0.01, 0.0), 0.0);
  EXPECT_EQ(fsi::hertz_normal_force(1e9, 0.01, -1e-4), 0.0);
}

TEST(Contact, DampingFactorReproducesTheRestitution) {
  EXPECT_EQ(fsi::damping_of_restitution(1.0), 0.0);
  EXPECT_NEAR(fsi::restitution_of_damping(0.0), 1.0, 1e-6);
  double previous = 0;
  for (double e : {0.9, 0.6, 0.3, 0.1}) {
    const double alpha = fsi::damping_of_restitution(e);
    std::printf("  restitution %.2f: damping factor alpha = %.6f\n", e, alpha);
    EXPECT_NEAR(fsi::restitution_of_damping(alpha), e, 1e-6);
    EXPECT_GT(alpha, previous);  // less restitution takes more damping
    previous = alpha;
  }
  EXPECT_THROW(fsi::damping_of_restitution(0.0), std::invalid_argument);
  EXPECT_THROW(fsi::damping_of_restitution(1.1), std::invalid_argument);
}

// A rubber-hard sphere (E = 1e8 Pa) of radius 5 cm and density 2500 kg/m^3 on a rigid floor.
constexpr double kRadius = 0.05, kDensity = 2500, kYoung = 1e8, kPoisson = 0.3;

fsi::MassProperties sphere_properties(const Vector3d& centre) {
  fsi::MassProperties mp;
  mp.mass = kDensity * 4.0 / 3.0 * kPi * std::pow(kRadius, 3);
  mp.inertia = 0.4 * mp.mass * kRadius * kRadius * Eigen::Matrix3d::Identity();
  mp.centre_of_mass = centre;
  return mp;
}

fsi::ContactLaw floor_law(double mass, double restitution, double friction) {
  return fsi::make_contact_law({kYoung, kPoisson, kRadius, mass}, {kInf, 0, kInf, kInf}, restitution, friction);
}

TEST(Contact, DroppedSphereReboundsWithTheChosenRestitution) {
  const double drop = 0.5;  // fall height of the lowest point [m]
  const double impact = std::sqrt(2 * kG * drop);
  for (double e : {0.3, 0.6, 0.9}) {
    fsi::RigidBody body(sphere_properties(Vector3d(0, 0, kRadius + drop)));
    const fsi::ContactLaw law = floor_law(body.mass(), e, 0.5);
    const double dt = fsi::contact_time_step(law, impact);
    fsi::TangentialSpring spring;
    int pushing_steps = 0;  // steps whose contact force is not zero
    const auto load = [&] {
      fsi::Wrench w;
      w.force = body.mass() * Vector3d(0, 0, -kG);
      const fsi::ContactGeometry g = fsi::sphere_plane(body.position(), kRadius, Vector3d::Zero(), Vector3d::UnitZ());
      const fsi::ContactForce f = fsi::contact_force(law, g.overlap, g.normal, body.velocity_at(g.point), spring, dt);
      if (f.normal_force > 0) ++pushing_steps;
      w += fsi::contact_wrench(f.force, g.point, &body, nullptr).on_a;
      return w;
    };
    // Impact speed: the last step before the overlap, rebound speed: the first step after it (both
    // off by at most g dt ~ 1e-3 m/s from the speeds at the instants of touching and leaving).
    double v_in = 0, v_out = 0, t = 0;
    bool touched = false, left = false;
    fsi::Wrench w = load();
    while (t < 1.0 && !left) {
      const double v_before = body.velocity().z();
      body.kick(0.5 * dt, w);
      body.drift(dt);
      t += dt;
      w = load();
      body.kick(0.5 * dt, w);
      const double overlap = kRadius - body.position().z();
      if (!touched && overlap > 0) {
        touched = true;
        v_in = -v_before;
      } else if (touched && overlap <= 0) {
        left = true;
        v_out = body.velocity().z();
      }
    }
    ASSERT_TRUE(left) << "the sphere never left the floor";
    const double measured = v_out / v_in;
    const double t_c = fsi::hertz_contact_duration(law, v_in);
    const double pushing = pushing_steps * dt;
    std::printf("  drop, e = %.2f: impact %.4f m/s, rebound %.4f m/s, e measured %.4f (error %.2f%%), "
                "force on for %.3e s (%d steps), undamped Hertz t_c %.3e s\n",
                e, v_in, v_out, measured, 100 * std::abs(measured - e) / e, pushing, pushing_steps, t_c);
    EXPECT_NEAR(measured, e, 0.05 * e);
    EXPECT_NEAR(v_in, impact, 1e-3 * impact);  // the free fall before is right too
    // Damping shortens the time the force acts (dimensionless solution: 0.98 t_c at e = 0.9, 0.80
    // t_c at e = 0.3); the overlap then lasts a little longer, the sphere coasting out force-free.
    EXPECT_LT(pushing, 1.02 * t_c);
    EXPECT_GT(pushing, 0.7 * t_c);
  }
}

TEST(Contact, FiftyStepsPerContactResolveTheRebound) {
  const double approach = 2.0;
  for (double e : {0.3, 0.6, 0.9}) {
    double lo = 1, hi = 0;
    for (int phase = 0; phase < 10; ++phase) {
      fsi::RigidBody body(sphere_properties(Vector3d::Zero()));
      const fsi::ContactLaw law = floor_law(body.mass(), e, 0.5);
      const double dt = fsi::contact_time_step(law, approach, 50);
      // The first step that overlaps ends (phase + 0.5) / 10 of a step after the touch.
      body.set_position(Vector3d(0, 0, kRadius + (1 - (phase + 0.5) / 10) * approach * dt));
      body.set_velocity(Vector3d(0, 0, -approach));
      fsi::TangentialSpring spring;
      const auto load = [&] {
        const fsi::ContactGeometry g = fsi::sphere_plane(body.position(), kRadius, Vector3d::Zero(), Vector3d::UnitZ());
        return fsi::contact_wrench(
                   fsi::contact_force(law, g.overlap, g.normal, body.velocity_at(g.point), spring, dt).force, g.point,
                   &body, nullptr)
            .on_a;
      };
      fsi::Wrench w = load();
      bool touched = false;
      for (int i = 0; i < 1000; ++i) {
        body.kick(0.5 * dt, w);
        body.drift(dt);
        w = load();
        body.kick(0.5 * dt, w);
        const double overlap = kRadius - body.position().z();
        touched = touched || overlap > 0;
        if (touched && overlap <= 0) break;
      }
      const double measured = body.velocity().z() / approach;
      lo = std::min(lo, measured);
      hi = std::max(hi, measured);
    }
    std::printf("  50 steps per contact, e = %.1f: measured %.4f .. %.4f over ten entry phases\n", e, lo, hi);
    EXPECT_GT(lo, 0.98 * e);
    EXPECT_LT(hi, 1.02 * e);
  }
}

struct InclineRun {
  double displacement = 0;      // along the slope, downhill positive [m]
  double acceleration = 0;      // downhill, fitted over the second half [m/s^2]
  double static_elongation = 0; // m g sin theta / k_t [m]
  double max_friction_ratio = 0;  // max |F_t| / (mu F_n)
};

InclineRun slide(double theta, double mu, double duration) {
  const Vector3d n(-std::sin(theta), 0, std::cos(theta));  // floor normal
  const Vector3d downhill(-std::cos(theta), 0, -std::sin(theta));
  fsi::DofMask no_rolling;
  no_rolling.rotation = {false, false, false};
  fsi::RigidBody body(sphere_properties(Vector3d::Zero()), no_rolling);
  const double m = body.mass();
  const fsi::ContactLaw law = floor_law(m, 0.5, mu);
  // Start at the static normal overlap, at rest, so the normal direction starts in equilibrium.
  const double k_n = 4.0 / 3.0 * law.effective_modulus * std::sqrt(law.effective_radius);
  const double overlap = std::pow(m * kG * std::cos(theta) / k_n, 2.0 / 3.0);
  body.set_position((kRadius - overlap) * n);
  const Vector3d x0 = body.position();
  // A resting contact has no impact speed: the floor is the speed of a fall through its own overlap.
  const double dt = fsi::contact_time_step(law, std::sqrt(2 * kG * overlap));
  InclineRun r;
  r.static_elongation = m * kG * std::sin(theta) / (8 * law.effective_shear_modulus * std::sqrt(law.effective_radius * overlap));
  fsi::TangentialSpring spring;
  const auto load = [&] {
    fsi::Wrench w;
    w.force = m * Vector3d(0, 0, -kG);
    const fsi::ContactGeometry g = fsi::sphere_plane(body.position(), kRadius, Vector3d::Zero(), n);
    const fsi::ContactForce f = fsi::contact_force(law, g.overlap, g.normal, body.velocity_at(g.point), spring, dt);
    const Vector3d f_t = f.force - f.force.dot(n) * n;
    if (f.normal_force > 0) r.max_friction_ratio = std::max(r.max_friction_ratio, f_t.norm() / (mu * f.normal_force));
    w += fsi::contact_wrench(f.force, g.point, &body, nullptr).on_a;
    return w;
  };
  fsi::Wrench w = load();
  const int steps = int(std::ceil(duration / dt));
  double t1 = 0, v1 = 0;
  for (int i = 1; i <= steps; ++i) {
    body.kick(0.5 * dt, w);
    body.drift(dt);
    w = load();
    body.kick(0.5 * dt, w);
    if (i == steps / 2) {
      t1 = i * dt;
      v1 = body.velocity().dot(downhill);
    }
  }
  r.displacement = (body.position() - x0).dot(downhill);
  r.acceleration = (body.velocity().dot(downhill) - v1) / (steps * dt - t1);
  return r;
}

TEST(Contact, SphereWithoutRollingSlidesDownASteepIncline) {
  const double theta = 30 * kPi / 180, mu = 0.3;
  ASSERT_GT(std::tan(theta), mu);
  const InclineRun r = slide(theta, mu, 0.5);
  const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
  std::printf("  incline 30 deg, mu 0.3: a = %.5f m/s^2, g (sin - mu cos) = %.5f m/s^2, error %.2e; "
              "max |F_t| / (mu F_n) = %.15f\n",
              r.acceleration, expected, std::abs(r.acceleration - expected) / expected, r.max_friction_ratio);
  EXPECT_NEAR(r.acceleration, expected, 0.02 * expected);
  EXPECT_LE(r.max_friction_ratio, 1 + 1e-12);
}

TEST(Contact, SphereWithoutRollingStaysPutOnAGentleIncline) {
  const double theta = 10 * kPi / 180, mu = 0.5;
  ASSERT_LT(std::tan(theta), mu);
  const InclineRun r = slide(theta, mu, 0.5);
  // Frictionless sliding for 0.5 s would cover g sin(theta) t^2 / 2 = 0.21 m.
  std::printf("  incline 10 deg, mu 0.5: displacement %.3e m, bound 2 m g sin / k_t = %.3e m\n", r.displacement,
              2 * r.static_elongation);
  EXPECT_LT(std::abs(r.displacement), 2 * r.static_elongation);
  EXPECT_LT(r.max_friction_ratio, 1.0);  // it never slipped
}

TEST(Contact, SlidingSphereStartsRollingAtFiveSevenths) {
  const double mu = 0.3, v0 = 1.0;
  fsi::RigidBody body(sphere_properties(Vector3d::Zero()));
  const double m = body.mass();
  const fsi::ContactLaw law = floor_law(m, 0.5, mu);
  const double k_n = 4.0 / 3.0 * law.effective_modulus * std::sqrt(law.effective_radius);
  const double overlap = std::pow(m * kG / k_n, 2.0 / 3.0);
  body.set_position(Vector3d(0, 0, kRadius - overlap));
  body.set_velocity(Vector3d(v0, 0, 0));
  const double dt = fsi::contact_time_step(law, std::sqrt(2 * kG * overlap));
  fsi::TangentialSpring spring;
  const auto load = [&] {
    fsi::Wrench w;
    w.force = m * Vector3d(0, 0, -kG);
    const fsi::ContactGeometry g = fsi::sphere_plane(body.position(), kRadius, Vector3d::Zero(), Vector3d::UnitZ());
    w += fsi::contact_wrench(fsi::contact_force(law, g.overlap, g.normal, body.velocity_at(g.point), spring, dt).force,
                             g.point, &body, nullptr)
             .on_a;
    return w;
  };
  const double t_roll = 2 * v0 / (7 * mu * kG);
  fsi::Wrench w = load();
  for (int i = 0; i < int(3 * t_roll / dt); ++i) {
    body.kick(0.5 * dt, w);
    body.drift(dt);
    w = load();
    body.kick(0.5 * dt, w);
  }
  // The contact point lies R - delta/2 below the centre (the middle of the overlap).
  const double lever = kRadius - 0.5 * (kRadius - body.position().z());
  const double v = body.velocity().x(), wR = body.angular_velocity().y() * lever;
  std::printf("  sliding sphere: v = %.5f m/s (5/7 v0 = %.5f), w R = %.5f m/s after %.3f s\n", v, 5.0 / 7.0 * v0, wR,
              3 * t_roll);
  EXPECT_NEAR(v, 5.0 / 7.0 * v0, 0.01 * 5.0 / 7.0 * v0);
  EXPECT_NEAR(v, wR, 1e-3 * v0);
}

TEST(Contact, ContactTimeStepFollowsHertzDuration) {
  const fsi::ContactLaw law = floor_law(1.0, 0.5, 0.3);
  // t_c ~ v^(-1/5): 32 times the speed, half the duration.
  EXPECT_NEAR(fsi::hertz_contact_duration(law, 32.0) / fsi::hertz_contact_duration(law, 1.0), 0.5, 1e-12);
  // Johnson's closed form 2.868 (m*^2 / (E*^2 R* v))^(1/5) to the four digits it is usually quoted with.
  const double johnson = 2.868 * std::pow(1.0 / (law.effective_modulus * law.effective_modulus * kRadius * 1.0), 0.2);
  EXPECT_NEAR(fsi::hertz_contact_duration(law, 1.0), johnson, 2e-4 * johnson);
  EXPECT_DOUBLE_EQ(fsi::contact_time_step(law, 1.0, 50), fsi::hertz_contact_duration(law, 1.0) / 50);
}

}  // namespace
