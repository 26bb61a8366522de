// Springs and dashpots (fsi/spring_damper.hpp) driving rigid bodies (fsi/rigid_body.hpp) stepped
// kick-drift-kick, against:
//  (a) a mass on a spring to a fixed anchor oscillates at w0 = sqrt(k/m): the period measured from
//      upward zero crossings over five periods within 0.5% of 2 pi / w0 (200 steps per period);
//  (b) with a dashpot (damping ratio 0.05) the amplitude decays as exp(-c t / (2m)): the rate from a
//      least-squares fit of log(peak) over eight periods within 1% of c / (2m);
//  (c) two bodies joined off-centre by a spring-dashpot, no other load: the forces are equal and
//      opposite and central, so total linear momentum and total angular momentum about the origin
//      (sum of x x m v + L) stay constant to rounding (relative 1e-12 over 2000 steps).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fsi/spring_damper.hpp"

namespace {

using namespace turbid;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;

fsi::MassProperties properties(double mass, const Vector3d& centre) {
  fsi::MassProperties mp;
  mp.mass = mass;
  mp.inertia = Vector3d(0.02, 0.03, 0.04).asDiagonal();
  mp.centre_of_mass = centre;
  return mp;
}

struct Oscillation {
  std::vector<double> time, displacement;
};

// A mass on a spring along x, anchored at the origin, released from rest stretched by `stretch`.
Oscillation oscillate(const fsi::SpringDamper& spring, double mass, double stretch, double dt, int steps) {
  fsi::RigidBody body(properties(mass, Vector3d(spring.rest_length + stretch, 0, 0)));
  const fsi::Attachment anchor{nullptr, Vector3d::Zero()};
  const fsi::Attachment end{&body, Vector3d::Zero()};
  fsi::Wrench load = fsi::spring_damper(spring, end, anchor).on_a;
  Oscillation o;
  for (int i = 1; i <= steps; ++i) {
    body.kick(0.5 * dt, load);
    body.drift(dt);
    load = fsi::spring_damper(spring, end, anchor).on_a;
    body.kick(0.5 * dt, load);
    o.time.push_back(i * dt);
    o.displacement.push_back(body.position().x() - spring.rest_length);
  }
  return o;
}

TEST(SpringDamper, SpringMassOscillatesAtItsNaturalFrequency) {
  const double m = 2.0, k = 50.0;
  const fsi::SpringDamper spring{k, 1.0, 0.0};
  const double period = 2 * kPi / std::sqrt(k / m);
  const double dt = period / 200;
  const Oscillation o = oscillate(spring, m, 0.1, dt, 200 * 6);
  std::vector<double> crossings;
  for (std::size_t i = 1; i < o.time.size(); ++i)
    if (o.displacement[i - 1] < 0 && o.displacement[i] >= 0)
      crossings.push_back(o.time[i - 1] + dt * o.displacement[i - 1] / (o.displacement[i - 1] - o.displacement[i]));
  ASSERT_GE(crossings.size(), 6u);
  const double measured = (crossings.back() - crossings.front()) / double(crossings.size() - 1);
  std::printf("  spring-mass: period %.6f s over %zu periods, 2 pi sqrt(m/k) = %.6f s, error %.2e\n", measured,
              crossings.size() - 1, period, std::abs(measured - period) / period);
  EXPECT_NEAR(measured, period, 0.005 * period);
}

TEST(SpringDamper, DampedOscillationDecaysAtTheAnalyticRate) {
  const double m = 2.0, k = 50.0;
  const double c = 2 * 0.05 * std::sqrt(k * m);
  const fsi::SpringDamper spring{k, 1.0, c};
  const double period = 2 * kPi / std::sqrt(k / m);
  const double dt = period / 200;
  const Oscillation o = oscillate(spring, m, 0.1, dt, 200 * 9);
  // Peaks from a parabola through each local maximum and its neighbours.
  std::vector<double> t, log_peak;
  for (std::size_t i = 1; i + 1 < o.time.size(); ++i) {
    const double a = o.displacement[i - 1], b = o.displacement[i], d = o.displacement[i + 1];
    if (b > a && b >= d && b > 0) {
      const double s = 0.5 * (a - d) / (a - 2 * b + d);  // vertex offset in steps
      t.push_back(o.time[i] + s * dt);
      log_peak.push_back(std::log(b - 0.25 * (a - d) * s));
    }
  }
  ASSERT_GE(t.size(), 8u);
  double st = 0, sy = 0, stt = 0, sty = 0;
  const double n = double(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    st += t[i];
    sy += log_peak[i];
    stt += t[i] * t[i];
    sty += t[i] * log_peak[i];
  }
  const double rate = -(n * sty - st * sy) / (n * stt - st * st);
  const double expected = c / (2 * m);
  std::printf("  damped spring-mass: decay rate %.6f 1/s from %zu peaks, c/(2m) = %.6f 1/s, error %.2e\n", rate,
              t.size(), expected, std::abs(rate - expected) / expected);
  EXPECT_NEAR(rate, expected, 0.01 * expected);
}

TEST(SpringDamper, BodyToBodySpringConservesMomentum) {
  fsi::RigidBody a(properties(1.5, Vector3d(0, 0, 0))), b(properties(2.5, Vector3d(1.2, 0.3, -0.2)));
  a.set_velocity(Vector3d(0.2, -0.1, 0.3));
  b.set_velocity(Vector3d(-0.1, 0.4, 0.0));
  a.set_angular_velocity(Vector3d(0.5, 0.2, -0.3));
  b.set_angular_velocity(Vector3d(-0.2, 0.6, 0.1));
  const fsi::SpringDamper spring{80.0, 0.9, 1.5};
  const fsi::Attachment ea{&a, Vector3d(0.1, 0.05, -0.02)}, eb{&b, Vector3d(-0.08, 0.02, 0.06)};
  const auto momentum = [&] { return Vector3d(a.linear_momentum() + b.linear_momentum()); };
  const auto angular = [&] {
    return Vector3d(a.position().cross(a.linear_momentum()) + a.angular_momentum() +
                    b.position().cross(b.linear_momentum()) + b.angular_momentum());
  };
  const Vector3d P0 = momentum(), J0 = angular();
  fsi::PairWrench w = fsi::spring_damper(spring, ea, eb);
  EXPECT_EQ((w.on_a.force + w.on_b.force).norm(), 0.0);  // Newton's third law, by construction exact
  const double dt = 1e-3;
  double dP = 0, dJ = 0;
  for (int i = 0; i < 2000; ++i) {
    a.kick(0.5 * dt, w.on_a);
    b.kick(0.5 * dt, w.on_b);
    a.drift(dt);
    b.drift(dt);
    w = fsi::spring_damper(spring, ea, eb);
    a.kick(0.5 * dt, w.on_a);
    b.kick(0.5 * dt, w.on_b);
    dP = std::max(dP, (momentum() - P0).norm() / P0.norm());
    dJ = std::max(dJ, (angular() - J0).norm() / J0.norm());
  }
  std::printf("  two bodies on a spring-dashpot, 2000 steps: |dP|/|P| = %.2e, |dJ|/|J| = %.2e\n", dP, dJ);
  EXPECT_LT(dP, 1e-12);
  EXPECT_LT(dJ, 1e-12);
  // The spring did work: the bodies did not just drift apart.
  EXPECT_GT((a.velocity() - Vector3d(0.2, -0.1, 0.3)).norm(), 1e-2);
}

TEST(SpringDamper, CoincidentEndsGiveNoForce) {
  const fsi::SpringDamper spring{10.0, 0.5, 1.0};
  EXPECT_EQ(fsi::spring_damper_force(spring, Vector3d(1, 2, 3), Vector3d(1, 0, 0), Vector3d(1, 2, 3), Vector3d::Zero()),
            Vector3d::Zero());
}

}  // namespace
