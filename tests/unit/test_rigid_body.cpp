// The built-in rigid-body integrator (fsi/rigid_body.hpp), stepped kick(dt/2) - drift(dt) -
// kick(dt/2) as the coupled step will do, against:
//  (a) free fall: x = x0 + v0 t + g t^2 / 2 and v = v0 + g t, which the scheme integrates exactly,
//      so to rounding (relative 1e-12 after 1000 steps);
//  (b) torque-free rotation of an asymmetric body (I = diag(1, 2, 3) kg m^2, also rotated so that
//      I0 is not diagonal, w not along a principal axis): world-frame angular momentum conserved to
//      rounding (relative 1e-12) and kinetic energy within 1e-5 relative over 10^4 steps of
//      dt = 1e-4 * 2 pi / |w|; the orientation converges at second order (error ratio 4 +- 0.5 when
//      dt halves, against a run at dt/16);
//  (c) locked degrees of freedom: a locked coordinate and the locked components of the orientation
//      do not change at all (exact equality) under forces and torques on every axis, while the free
//      ones follow the analytic constant-load motion (relative 1e-12); with two free rotation axes
//      the locked component of w stays exactly 0 and the energy (conserved: the reaction torque does
//      no work) within 1e-6;
//  (d) the planar body (dims 2) keeps z, and rotates about z only.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <Eigen/Geometry>

#include "fsi/rigid_body.hpp"

namespace {

using namespace turbid;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;

fsi::MassProperties properties(double mass, const Matrix3d& inertia, const Vector3d& centre = Vector3d::Zero(),
                               int dims = 3) {
  fsi::MassProperties mp;
  mp.dims = dims;
  mp.mass = mass;
  mp.inertia = inertia;
  mp.centre_of_mass = centre;
  return mp;
}

// One kick-drift-kick step with a load that depends only on the time (here: constant).
void step(fsi::RigidBody& body, double dt, const fsi::Wrench& load) {
  body.kick(0.5 * dt, load);
  body.drift(dt);
  body.kick(0.5 * dt, load);
}

TEST(RigidBody, FreeFallIsExactToRounding) {
  const double m = 3.5;
  fsi::RigidBody body(properties(m, Vector3d(1, 2, 3).asDiagonal(), Vector3d(0.4, -1.2, 2.0)));
  const Vector3d x0 = body.position(), v0(0.8, 0.3, 2.5), g(0.5, -1.0, -9.81);
  body.set_velocity(v0);
  fsi::Wrench gravity;
  gravity.force = m * g;
  const double dt = 1e-3;
  const int n = 1000;
  double worst_x = 0, worst_v = 0;
  for (int i = 1; i <= n; ++i) {
    step(body, dt, gravity);
    const double t = i * dt;
    const Vector3d x = x0 + v0 * t + 0.5 * g * t * t, v = v0 + g * t;
    worst_x = std::max(worst_x, (body.position() - x).norm() / x.norm());
    worst_v = std::max(worst_v, (body.velocity() - v).norm() / v.norm());
  }
  std::printf("  free fall over %d steps: position error %.2e, velocity error %.2e (relative)\n", n, worst_x, worst_v);
  EXPECT_LT(worst_x, 1e-12);
  EXPECT_LT(worst_v, 1e-12);
  // No torque: no rotation at all.
  EXPECT_EQ(body.orientation().coeffs(), Quaterniond::Identity().coeffs());
}

struct RotationRun {
  double momentum_error = 0;  // max |L - L0| / |L0|
  double energy_error = 0;    // max |E - E0| / E0
  Quaterniond orientation;
};

RotationRun spin(const Matrix3d& inertia, const Vector3d& w0, double dt, int steps) {
  fsi::RigidBody body(properties(1.0, inertia));
  body.set_angular_velocity(w0);
  const Vector3d L0 = body.angular_momentum();
  const double E0 = body.kinetic_energy();
  RotationRun r;
  for (int i = 0; i < steps; ++i) {
    step(body, dt, fsi::Wrench{});
    r.momentum_error = std::max(r.momentum_error, (body.angular_momentum() - L0).norm() / L0.norm());
    r.energy_error = std::max(r.energy_error, std::abs(body.kinetic_energy() - E0) / E0);
  }
  r.orientation = body.orientation();
  return r;
}

// Rotation angle between two orientations [rad].
double angle_between(const Quaterniond& a, const Quaterniond& b) { return a.angularDistance(b); }

TEST(RigidBody, TorqueFreeAsymmetricBodyKeepsMomentumAndEnergy) {
  const Matrix3d principal = Vector3d(1, 2, 3).asDiagonal();
  const Matrix3d Q = Eigen::AngleAxisd(0.7, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  // w close to the intermediate axis, where the motion is least forgiving (it tumbles).
  const Vector3d w0(0.3, 1.0, 0.4);
  const double dt = 1e-4 * 2 * kPi / w0.norm();
  for (const Matrix3d& I : {principal, Matrix3d(Q * principal * Q.transpose())}) {
    const RotationRun r = spin(I, w0, dt, 10000);
    std::printf("  torque-free, 1e4 steps: |dL|/|L| = %.2e, |dE|/E = %.2e\n", r.momentum_error, r.energy_error);
    EXPECT_LT(r.momentum_error, 1e-12);
    EXPECT_LT(r.energy_error, 1e-5);
  }
}

TEST(RigidBody, TorqueFreeRotationConvergesAtSecondOrder) {
  const Matrix3d I = Vector3d(1, 2, 3).asDiagonal();
  const Vector3d w0(0.3, 1.0, 0.4);
  const double T = 4 * 2 * kPi / w0.norm();  // four turns, through the tumbling
  const int n = 400;
  const Quaterniond reference = spin(I, w0, T / (16 * n), 16 * n).orientation;
  const double e1 = angle_between(spin(I, w0, T / n, n).orientation, reference);
  const double e2 = angle_between(spin(I, w0, T / (2 * n), 2 * n).orientation, reference);
  // Richardson: against a reference at dt/16 the ratio of O(dt^2) errors is (1 - 1/256)/(1/4 - 1/256) ~ 4.06.
  std::printf("  orientation error after 4 turns: %.3e rad (dt), %.3e rad (dt/2), ratio %.3f\n", e1, e2, e1 / e2);
  EXPECT_NEAR(e1 / e2, 4.0, 0.5);
  EXPECT_LT(e1, 1e-2);
}

TEST(RigidBody, LockedAxesStayExactlyFixed) {
  const double m = 2.0;
  fsi::DofMask mask;
  mask.translation = {true, false, true};
  mask.rotation = {false, false, true};
  const Matrix3d Q = Eigen::AngleAxisd(0.4, Vector3d(1, 1, 1).normalized()).toRotationMatrix();
  const Matrix3d I = Q * Vector3d(1, 2, 3).asDiagonal() * Q.transpose();  // couples z to x and y
  fsi::RigidBody body(properties(m, I, Vector3d(0.1, 0.2, 0.3)), mask);
  body.set_velocity(Vector3d(1, 2, 3));
  body.set_angular_velocity(Vector3d(0.5, -0.5, 0.25));
  EXPECT_EQ(body.velocity().y(), 0.0);
  EXPECT_EQ(body.angular_velocity().x(), 0.0);
  EXPECT_EQ(body.angular_velocity().y(), 0.0);
  const Vector3d x0 = body.position(), v0 = body.velocity();
  const double wz0 = body.angular_velocity().z();
  fsi::Wrench load;
  load.force = Vector3d(3, -7, 1);
  load.torque = Vector3d(0.3, -0.2, 0.1);
  const double dt = 1e-3;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    step(body, dt, load);
    ASSERT_EQ(body.position().y(), x0.y());
    ASSERT_EQ(body.orientation().x(), 0.0);
    ASSERT_EQ(body.orientation().y(), 0.0);
    ASSERT_EQ(body.angular_velocity().x(), 0.0);
    ASSERT_EQ(body.angular_velocity().y(), 0.0);
  }
  // The free axes follow the constant-load motion: x, z uniformly accelerated; the angle about z
  // uniformly accelerated by torque_z / I_zz (I_zz of the world tensor, unchanged by turning about z).
  const double t = n * dt;
  const Vector3d a = load.force / m;
  EXPECT_NEAR(body.position().x(), x0.x() + v0.x() * t + 0.5 * a.x() * t * t, 1e-12 * std::abs(body.position().x()));
  EXPECT_NEAR(body.position().z(), x0.z() + v0.z() * t + 0.5 * a.z() * t * t, 1e-12 * std::abs(body.position().z()));
  const double angle = 2 * std::atan2(body.orientation().z(), body.orientation().w());
  const double expected = wz0 * t + 0.5 * load.torque.z() / I(2, 2) * t * t;
  std::printf("  locked: angle about z %.15f rad, analytic %.15f rad\n", angle, expected);
  EXPECT_NEAR(angle, expected, 1e-12 * std::abs(expected));
}

TEST(RigidBody, TwoFreeRotationAxesKeepTheLockedOneAtRestAndConserveEnergy) {
  fsi::DofMask mask;
  mask.rotation = {false, true, true};
  fsi::RigidBody body(properties(1.0, Vector3d(1, 2, 3).asDiagonal()), mask);
  body.set_angular_velocity(Vector3d(0, 1.0, 0.4));
  const double E0 = body.kinetic_energy();
  const double dt = 1e-4 * 2 * kPi / 1.08;
  double energy_error = 0;
  for (int i = 0; i < 10000; ++i) {
    step(body, dt, fsi::Wrench{});
    ASSERT_EQ(body.angular_velocity().x(), 0.0);
    energy_error = std::max(energy_error, std::abs(body.kinetic_energy() - E0) / E0);
  }
  std::printf("  two free rotation axes, 1e4 steps: |dE|/E = %.2e\n", energy_error);
  EXPECT_LT(energy_error, 1e-6);
}

TEST(RigidBody, PlanarBodyMovesInItsPlane) {
  Matrix3d lamina = Matrix3d::Zero();
  lamina(0, 0) = 0.2;
  lamina(1, 1) = 0.3;
  lamina(2, 2) = 0.5;
  lamina(0, 1) = lamina(1, 0) = -0.05;
  fsi::RigidBody body(properties(4.0, lamina, Vector3d(1, 2, 0), 2));
  EXPECT_FALSE(body.mask().translation[2]);
  EXPECT_FALSE(body.mask().rotation[0]);
  EXPECT_FALSE(body.mask().rotation[1]);
  body.set_velocity(Vector3d(1, -1, 5));
  body.set_angular_velocity(Vector3d(2, 3, 1.5));
  fsi::Wrench load;
  load.force = Vector3d(0, -39.24, 10);
  load.torque = Vector3d(1, 1, 0.2);
  for (int i = 0; i < 500; ++i) step(body, 1e-3, load);
  EXPECT_EQ(body.position().z(), 0.0);
  EXPECT_EQ(body.velocity().z(), 0.0);
  EXPECT_EQ(body.orientation().x(), 0.0);
  EXPECT_EQ(body.orientation().y(), 0.0);
  // I_zz alone governs the spin: w_z = 1.5 + 0.2 / 0.5 * 0.5 s.
  EXPECT_NEAR(body.angular_velocity().z(), 1.5 + 0.2 / 0.5 * 0.5, 1e-12);
}

TEST(RigidBody, RejectsBadMassProperties) {
  EXPECT_THROW(fsi::RigidBody(properties(0, Matrix3d::Identity())), std::invalid_argument);
  EXPECT_THROW(fsi::RigidBody(properties(1, Vector3d(1, 0, 1).asDiagonal())), std::invalid_argument);
  Matrix3d asymmetric = Matrix3d::Identity();
  asymmetric(0, 1) = 0.5;
  EXPECT_THROW(fsi::RigidBody(properties(1, asymmetric)), std::invalid_argument);
  // A 2D body needs only I_zz.
  Matrix3d zz = Matrix3d::Zero();
  zz(2, 2) = 1;
  EXPECT_NO_THROW(fsi::RigidBody(properties(1, zz, Vector3d::Zero(), 2)));
}

}  // namespace
