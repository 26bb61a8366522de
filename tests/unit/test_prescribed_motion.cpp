// motion: prescribed (issue #8): the path (fsi/prescribed_path.hpp) against the table or formula it
// was given, its velocity against the finite difference of its positions, and a prescribed cylinder
// oscillating in a small 2D tank (fsi/prescribed_coupling.hpp) whose particles must sit exactly on
// x_ref + d(t) + R(t) r0 while the fluid pushes on it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "fsi/prescribed_path.hpp"
#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"

namespace {

using turbid::fsi::PathState;
using turbid::fsi::PrescribedPath;
using turbid::fsi::PrescribedPathSpec;
using Kind = PrescribedPathSpec::Kind;
using Interp = PrescribedPathSpec::Interpolation;
constexpr double kPi = std::numbers::pi;
constexpr double kEps = std::numeric_limits<double>::epsilon();

// The axis-angle vector of R (small rotations): the skew part of R - R^T over 2.
Eigen::Vector3d skew_part(const Eigen::Matrix3d& R) {
  return 0.5 * Eigen::Vector3d(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
}

PrescribedPathSpec samples(Interp interp) {
  PrescribedPathSpec s;
  s.kind = Kind::samples;
  s.interpolation = interp;
  s.times = {0.0, 0.3, 0.5, 1.1, 1.4};
  s.displacement = {{0, 0, 0}, {0.02, -0.01, 0.005}, {0.05, 0.01, 0}, {0.03, 0.04, -0.01}, {0.1, 0, 0.02}};
  s.angles = {{0, 0, 0}, {0.1, -0.05, 0.2}, {0.2, 0.1, -0.1}, {-0.1, 0.3, 0.05}, {0, 0, 0.4}};
  return s;
}

}  // namespace

// Reference: the table itself. At every sample time both interpolations return the sample (to
// rounding, 4 eps of the largest value); outside the samples the path holds with zero velocity.
TEST(PrescribedPath, PassesThroughTheSamplesAndHoldsOutside) {
  for (Interp interp : {Interp::spline, Interp::linear}) {
    const auto spec = samples(interp);
    const PrescribedPath path(spec);
    for (std::size_t i = 0; i < spec.times.size(); ++i) {
      const PathState s = path.at(spec.times[i]);
      const Eigen::Matrix3d R = turbid::fsi::rotation_from_angles(
                                    Eigen::Vector3d(spec.angles[i][0], spec.angles[i][1], spec.angles[i][2]))
                                    .toRotationMatrix();
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(s.displacement[a], spec.displacement[i][std::size_t(a)], 4 * 0.1 * kEps);
      EXPECT_LE((s.rotation - R).cwiseAbs().maxCoeff(), 4 * kEps) << "sample " << i;
    }
    for (double t : {-1.0, 0.0 - 1e-12, 1.4 + 1e-12, 7.0}) {
      const PathState s = path.at(t);
      const std::size_t i = t < 0.5 ? 0 : spec.times.size() - 1;
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(s.displacement[a], spec.displacement[i][std::size_t(a)]) << "hold at t = " << t;
        EXPECT_EQ(s.velocity[a], 0.0);
        EXPECT_EQ(s.angular_velocity[a], 0.0);
      }
    }
  }
}

// Reference: the clamped cubic spline reproduces any cubic with zero end slopes exactly (it is the
// unique C2 piecewise cubic through the samples with those end slopes), so samples of
// y = 3 t^2 - 2 t^3 on [0, 1] at uneven times give y and y' = 6 t - 6 t^2 between the samples, to
// rounding (1e-14). The linear interpolation gives the chord and its slope.
TEST(PrescribedPath, SplineReproducesACubicAndLinearTheChords) {
  PrescribedPathSpec spec;
  spec.kind = Kind::samples;
  spec.times = {0.0, 0.15, 0.4, 0.45, 0.8, 1.0};
  for (double t : spec.times) {
    spec.displacement.push_back({3 * t * t - 2 * t * t * t, 0, -(3 * t * t - 2 * t * t * t)});
    spec.angles.push_back({0, 0, 0.5 * (3 * t * t - 2 * t * t * t)});
  }
  const PrescribedPath spline(spec);
  for (double t = 0.013; t < 1.0; t += 0.0617) {
    const PathState s = spline.at(t);
    const double y = 3 * t * t - 2 * t * t * t, dy = 6 * t - 6 * t * t;
    EXPECT_NEAR(s.displacement[0], y, 1e-14) << t;
    EXPECT_NEAR(s.displacement[2], -y, 1e-14) << t;
    EXPECT_NEAR(s.velocity[0], dy, 1e-14) << t;
    EXPECT_NEAR(s.angular_velocity[2], 0.5 * dy, 1e-14) << t;
    EXPECT_NEAR(std::atan2(s.rotation(1, 0), s.rotation(0, 0)), 0.5 * y, 1e-14) << t;
  }
  spec.interpolation = Interp::linear;
  const PrescribedPath linear(spec);
  for (std::size_t i = 0; i + 1 < spec.times.size(); ++i) {
    const double t0 = spec.times[i], t1 = spec.times[i + 1], tm = 0.3 * t0 + 0.7 * t1;
    const double y0 = spec.displacement[i][0], y1 = spec.displacement[i + 1][0];
    const PathState s = linear.at(tm);
    EXPECT_NEAR(s.displacement[0], y0 + (y1 - y0) * (tm - t0) / (t1 - t0), 1e-15);
    EXPECT_NEAR(s.velocity[0], (y1 - y0) / (t1 - t0), 1e-13);
    // At a sample time: the interval that starts there.
    if (i > 0) {
      EXPECT_NEAR(linear.at(t0).velocity[0], (y1 - y0) / (t1 - t0), 1e-13);
    }
  }
}

// Reference: Taylor's theorem. The central differences (d(t+h) - d(t-h)) / 2h and the rotation
// vector of R(t+h) R(t-h)^T / 2h differ from the path's velocity and angular velocity by
// h^2/6 |x'''| + O(h^4) for a smooth path: the error falls by 4 (within 3.5 .. 4.5, order 2 +- 0.17)
// when h halves from 1e-3, for the spline (3D angles: the Euler-rate formula of w), the
// oscillation and the constant rotation; a wrong velocity (a missing term of w, a wrong factor)
// would leave an error that does not fall with h. Its size at h = 1e-3 stays below 1e-4 of the
// velocity scale (|x'''| up to ~200 s^-3 x the amplitude on these paths).
TEST(PrescribedPath, VelocityIsTheDerivativeOfThePositions) {
  PrescribedPathSpec osc;
  osc.kind = Kind::oscillation;
  osc.amplitude = {0.02, 0.01, -0.03};
  osc.angular_amplitude = {0.1, -0.2, 0.3};
  osc.period = 0.7;
  osc.phase = 0.4;
  PrescribedPathSpec turn;
  turn.kind = Kind::velocity;
  turn.velocity = {0.1, -0.2, 0.05};
  turn.angular_velocity = {0.3, 1.1, -0.7};
  const PrescribedPathSpec specs[] = {samples(Interp::spline), osc, turn};
  for (const auto& spec : specs) {
    const PrescribedPath path(spec);
    for (double t : {0.17, 0.41, 0.77, 1.23}) {
      const PathState s = path.at(t);
      double err[2];
      for (int k = 0; k < 2; ++k) {
        const double h = k == 0 ? 1e-3 : 0.5e-3;
        const PathState p = path.at(t + h), m = path.at(t - h);
        const Eigen::Vector3d v = (p.displacement - m.displacement) / (2 * h);
        const Eigen::Vector3d w = skew_part(p.rotation * m.rotation.transpose()) / (2 * h);
        err[k] = std::max((v - s.velocity).norm(), (w - s.angular_velocity).norm());
      }
      const double scale = std::max(1.0, s.velocity.norm() + s.angular_velocity.norm());
      EXPECT_LT(err[0], 1e-4 * scale) << "kind " << int(spec.kind) << " t = " << t;
      std::printf("kind %d t = %.2f: |FD - v| = %.3g (h = 1e-3), %.3g (h = 5e-4), ratio %.3f\n", int(spec.kind), t,
                  err[0], err[1], err[0] / err[1]);
      if (err[0] > 1e-9) {  // above rounding: check the order
        EXPECT_GT(err[0] / err[1], 3.5) << "kind " << int(spec.kind) << " t = " << t;
        EXPECT_LT(err[0] / err[1], 4.5) << "kind " << int(spec.kind) << " t = " << t;
      }
    }
  }
}

// Reference: the formulas of prescribed_path.hpp evaluated by hand. Oscillation: d = A (sin(W t + phi)
// - sin phi), d' = A W cos(W t + phi); constant velocity: d = v t and a rotation by |w| t about w.
TEST(PrescribedPath, OscillationAndConstantVelocityMatchTheirFormulas) {
  PrescribedPathSpec osc;
  osc.kind = Kind::oscillation;
  osc.amplitude = {0.02, 0, 0};
  osc.angular_amplitude = {0, 0, 0.1};
  osc.period = 0.5;
  osc.phase = kPi / 6;
  const PrescribedPath p(osc);
  EXPECT_EQ(p.at(0).displacement.norm(), 0.0);
  for (double t : {0.0, 0.1, 0.125, 0.3, 1.7}) {
    const double W = 2 * kPi / 0.5, ph = W * t + kPi / 6;
    const PathState s = p.at(t);
    EXPECT_NEAR(s.displacement[0], 0.02 * (std::sin(ph) - 0.5), 1e-16);
    EXPECT_NEAR(s.velocity[0], 0.02 * W * std::cos(ph), 1e-15);
    EXPECT_NEAR(std::atan2(s.rotation(1, 0), s.rotation(0, 0)), 0.1 * (std::sin(ph) - 0.5), 1e-15);
    EXPECT_NEAR(s.angular_velocity[2], 0.1 * W * std::cos(ph), 1e-15);
  }
  PrescribedPathSpec vel;
  vel.kind = Kind::velocity;
  vel.velocity = {0.1, -0.2, 0};
  vel.angular_velocity = {0, 0, 0.5};
  const PrescribedPath q(vel);
  const PathState s = q.at(3.0);
  EXPECT_DOUBLE_EQ(s.displacement[0], 0.3);  // v t, to rounding (4 ulp)
  EXPECT_DOUBLE_EQ(s.displacement[1], -0.6);
  EXPECT_NEAR(s.rotation(0, 0), std::cos(1.5), 2 * kEps);
  EXPECT_NEAR(s.rotation(1, 0), std::sin(1.5), 2 * kEps);
  EXPECT_EQ(s.rotation(2, 2), 1.0);
  EXPECT_EQ(s.angular_velocity[2], 0.5);
  // The quaternion stays continuous through a half turn (forces.csv columns do not jump sign).
  EXPECT_GT(q.at(2 * kPi / 0.5 * 0.499).orientation.dot(q.at(2 * kPi / 0.5 * 0.501).orientation), 0.99);
}

TEST(PrescribedPath, RefusesPathsItCannotFollow) {
  PrescribedPathSpec s = samples(Interp::spline);
  s.times[2] = s.times[1];
  EXPECT_THROW(PrescribedPath{s}, std::invalid_argument);
  s = samples(Interp::spline);
  s.times.resize(1);
  s.displacement.resize(1);
  s.angles.resize(1);
  EXPECT_THROW(PrescribedPath{s}, std::invalid_argument);
  PrescribedPathSpec o;
  o.kind = Kind::oscillation;
  o.period = 0;
  EXPECT_THROW(PrescribedPath{o}, std::invalid_argument);
}

namespace {

// A cylinder of radius 0.05 m oscillating across a 0.4 x 0.3 m tank of still water (no gravity:
// the fluid is at rest until the cylinder moves it), and turning as it goes.
const char* kOscillatingScene = R"(name: prescribed_check
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 0.1, cfl: 0.2}
gravity: [0, 0]
materials:
  water: {density: 1000, viscosity: 1.0e-3, sound_speed: 10}
walls:
  - box: {min: [0, 0], max: [0.4, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.4, 0.3]}}
structures:
  - name: cylinder
    cylinder: {radius: 0.05}
    position: [0.2, 0.15]
    reference_point: [0.21, 0.15]
    motion: prescribed
    path: {oscillation: {amplitude: [0.02, 0.005], angular_amplitude: 20, period: 0.1}}
output: {every: 0.1, vtk: false}
)";

}  // namespace

// Reference: the path. After every step each cylinder particle is at
// Real(x_ref + d(t) + R(t) r0) and carries Real(d'(t) + w(t) x R(t) r0) at the solver's time t,
// with r0 its offset from the reference point at t = 0 (single-precision fields rounded once
// from double: equal to the rounding of the path's own evaluation, tolerance 1 ulp of the
// coordinate for the order of the sums). The fluid's force on it stays finite and the forces.csv
// kinematics are the path's.
TEST(PrescribedCoupling, ParticlesFollowThePathExactly) {
  auto scene = turbid::tools::read_scene_string(kOscillatingScene, "prescribed_check.yaml");
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  turbid::fsi::Simulation sim(scene, opt);
  ASSERT_NE(sim.prescribed(), nullptr);
  sim.start();
  const PrescribedPath path(scene.structures[0].path);
  const Eigen::Vector3d ref(0.21, 0.15, 0);
  const auto& ids = sim.fields();
  // r0 as built: from the sampled positions before any step (the placement at t = 0 is the identity).
  int checked = 0, rounds = 0;
  double max_dev = 0, max_vdev = 0;
  for (int step = 1; step <= 1000 && sim.time() < 0.1; ++step) {
    sim.step();
    if (step % 10 != 0) continue;
    ++rounds;
    sim.sync_to_host();
    const double t = sim.time();
    const PathState s = path.at(t);
    const auto& store = sim.store();
    const auto* x = store.data<float>(ids.position);
    const auto* v = store.data<float>(ids.velocity);
    const auto* r0 = store.data<float>(ids.body_offset);
    const auto* kind = store.data<std::uint8_t>(ids.kind);
    for (std::size_t i = 0; i < store.size(); ++i) {
      if (kind[i] != std::uint8_t(turbid::sph::Kind::structure)) continue;
      const Eigen::Vector3d r = s.rotation * Eigen::Vector3d(r0[2 * i], r0[2 * i + 1], 0);
      const Eigen::Vector3d xe = ref + s.displacement + r;
      const Eigen::Vector3d ve = s.velocity + s.angular_velocity.cross(r);
      for (int a = 0; a < 2; ++a) {
        const double dev = std::abs(double(x[2 * i + a]) - xe[a]);
        const double vdev = std::abs(double(v[2 * i + a]) - ve[a]);
        max_dev = std::max(max_dev, dev);
        max_vdev = std::max(max_vdev, vdev);
        EXPECT_LE(dev, std::nextafter(float(xe[a]), 1e9f) - float(xe[a])) << "particle " << i << " t = " << t;
        EXPECT_LE(vdev, std::max(1e-12, double(std::nextafter(float(ve[a]), 1e9f) - float(ve[a]))))
            << "particle " << i << " t = " << t;
      }
      ++checked;
    }
    const auto loads = sim.structure_loads();
    EXPECT_TRUE(std::isfinite(loads[0].force[0]) && std::isfinite(loads[0].force[1]) && std::isfinite(loads[0].torque[2]));
    const auto kin = sim.body_kinematics();
    EXPECT_EQ(kin[0].position[0], ref[0] + s.displacement[0]);
    EXPECT_EQ(kin[0].velocity[1], s.velocity[1]);
    EXPECT_EQ(kin[0].angular_velocity[2], s.angular_velocity[2]);
  }
  EXPECT_GE(rounds, 10) << "a whole period checked";
  EXPECT_EQ(checked, rounds * int(sim.summary().structure_particles));
  const auto loads = sim.structure_loads();
  std::printf("%d checks of %zu particles over %llu steps: max deviation from the path %.3g m (position), %.3g m/s "
              "(velocity); Fx = %.4g N/m at t = %.4f s\n", rounds, sim.summary().structure_particles,
              (unsigned long long)sim.steps(), max_dev, max_vdev, loads[0].force[0], sim.time());
  EXPECT_GT(std::abs(loads[0].force[0]), 0.0) << "the moving cylinder pushes the water";
}

// A free box falling beside a prescribed cylinder that moves at constant velocity and turns (mDBC):
// both couplings run in one step (CouplingChain), each placing only its own particles. Reference:
// the path, as above (1 ulp), and for the mDBC ghost offsets n = R(t) n0 (1 ulp of the offset,
// 1e-9 m); the free box must have fallen (its velocity below zero).
TEST(PrescribedCoupling, RunsBesideAFreeBodyWithMdbc) {
  const char* text = R"(name: prescribed_and_free
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 0.03, cfl: 0.2}
gravity: [0, -9.81]
numerics: {boundary: {type: mdbc}}
materials:
  water: {density: 1000, viscosity: 1.0e-3, sound_speed: 15}
walls:
  - box: {min: [0, 0], max: [0.5, 0.4]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.5, 0.3]}}
structures:
  - {name: box, box: {size: [0.06, 0.06]}, position: [0.12, 0.35], motion: free, density: 800}
  - name: rotor
    box: {size: [0.12, 0.03]}
    position: [0.32, 0.15]
    motion: prescribed
    path: {velocity: [0.2, 0.05], angular_velocity: 180}
output: {every: 0.03, vtk: false}
)";
  auto scene = turbid::tools::read_scene_string(text, "prescribed_and_free.yaml");
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  turbid::fsi::Simulation sim(scene, opt);
  ASSERT_NE(sim.prescribed(), nullptr);
  ASSERT_NE(sim.bodies(), nullptr);
  sim.start();
  while (sim.time() < 0.03) sim.step();
  sim.sync_to_host();
  const PathState s = PrescribedPath(scene.structures[1].path).at(sim.time());
  const Eigen::Vector3d ref(0.32, 0.15, 0);
  const auto& ids = sim.fields();
  const auto& store = sim.store();
  const auto* x = store.data<float>(ids.position);
  const auto* r0 = store.data<float>(ids.body_offset);
  const auto* n = store.data<float>(ids.boundary_normal);
  const auto* n0 = store.data<float>(ids.body_normal);
  const auto* kind = store.data<std::uint8_t>(ids.kind);
  const auto* body = store.data<std::uint8_t>(ids.body);
  int checked = 0;
  for (std::size_t i = 0; i < store.size(); ++i) {
    if (kind[i] != std::uint8_t(turbid::sph::Kind::structure) || body[i] != 1) continue;
    const Eigen::Vector3d xe = ref + s.displacement + s.rotation * Eigen::Vector3d(r0[2 * i], r0[2 * i + 1], 0);
    const Eigen::Vector3d ne = s.rotation * Eigen::Vector3d(n0[2 * i], n0[2 * i + 1], 0);
    for (int a = 0; a < 2; ++a) {
      EXPECT_LE(std::abs(double(x[2 * i + a]) - xe[a]), std::nextafter(float(xe[a]), 1e9f) - float(xe[a]));
      EXPECT_LE(std::abs(double(n[2 * i + a]) - ne[a]), 1e-9 + std::abs(std::nextafter(float(ne[a]), 1e9f) - float(ne[a])));
    }
    ++checked;
  }
  EXPECT_GT(checked, 20);
  // The path turned the rotor by 180 deg/s x t, and the box, above the water, fell under gravity.
  EXPECT_NEAR(std::atan2(s.rotation(1, 0), s.rotation(0, 0)), kPi * sim.time(), 1e-12);
  EXPECT_LT(sim.bodies()->body(0).velocity()[1], 0.0);
  const auto kin = sim.body_kinematics();
  EXPECT_EQ(kin[1].position[0], 0.32 + s.displacement[0]);
  EXPECT_EQ(kin[1].orientation[3], s.orientation.z());
  EXPECT_EQ(kin[0].position[1], sim.bodies()->body(0).position()[1]);
}

// A path that would carry the structure out of the domain (where its particles would be removed)
// is refused when the run is built, at the path in the scene, with the time it leaves: the cylinder
// (its right edge at x = 0.25 m) moving at 1 m/s reaches the domain's upper x face (the particles'
// bounding box, walls included, grown by 4h = 0.08 m: about 0.52 m) near t = 0.27 s, before the
// end at 0.5 s; to 0.1 s it stays inside.
TEST(PrescribedCoupling, APathOutOfTheDomainIsRefused) {
  std::string text = kOscillatingScene;
  const std::string from = "path: {oscillation: {amplitude: [0.02, 0.005], angular_amplitude: 20, period: 0.1}}";
  text.replace(text.find(from), from.size(), "path: {velocity: [1, 0]}");
  text.replace(text.find("time: {end: 0.1"), 15, "time: {end: 0.5");
  auto scene = turbid::tools::read_scene_string(text, "out.yaml");
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  try {
    turbid::fsi::Simulation sim(scene, opt);
    ADD_FAILURE() << "no error for a path out of the domain";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("out.yaml:18:11: error: structure 'cylinder': its path carries it out of the domain at t = ", 0), 0u)
        << m;
  }
  // The same path to 0.1 s stays inside and runs.
  text.replace(text.find("time: {end: 0.5"), 15, "time: {end: 0.1");
  EXPECT_NO_THROW(turbid::fsi::Simulation(turbid::tools::read_scene_string(text, "in.yaml"), opt));
}

// The time alignment of prescribed_coupling.hpp, hook by hook, on the particles of the oscillating
// cylinder (reference: the path at the stated times, 1 ulp as above). With the clock at t(n) = 0.0123 s
// and dt = 4e-4 s: after the first half-kick the velocity is the path's at t(n) + dt/2 and the
// particles have not moved; after the drift they are at the path's position at t(n) + dt with the
// half-step velocity; after the second half-kick they carry the velocity at t(n) + dt.
TEST(PrescribedCoupling, KickDriftKickSeesTheHalfStepVelocityAndTheNewPositions) {
  auto scene = turbid::tools::read_scene_string(kOscillatingScene, "prescribed_check.yaml");
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  turbid::fsi::Simulation sim(scene, opt);
  const double tn = 0.0123, dt = 4e-4;
  const PrescribedPath path(scene.structures[0].path);
  const Eigen::Vector3d ref(0.21, 0.15, 0);
  std::vector<std::optional<turbid::fsi::PrescribedBody>> bodies(1);
  bodies[0].emplace(turbid::fsi::PrescribedBody{path, ref});
  turbid::fsi::PrescribedCoupling c(std::move(bodies), [tn] { return tn; });
  auto& backend = sim.backend();
  const auto& ids = sim.fields();
  // Largest deviation, in ulps of the expected value, of the structure particles' positions from the
  // path at t_x and of their velocities from the path's velocity at t_v.
  const auto check = [&](double t_x, double t_v, const char* when) {
    sim.sync_to_host();
    const PathState sx = path.at(t_x), sv = path.at(t_v);
    const auto& store = sim.store();
    const auto* x = store.data<float>(ids.position);
    const auto* v = store.data<float>(ids.velocity);
    const auto* r0 = store.data<float>(ids.body_offset);
    const auto* kind = store.data<std::uint8_t>(ids.kind);
    int n = 0;
    for (std::size_t i = 0; i < store.size(); ++i) {
      if (kind[i] != std::uint8_t(turbid::sph::Kind::structure)) continue;
      const Eigen::Vector3d r0i(r0[2 * i], r0[2 * i + 1], 0);
      const Eigen::Vector3d xe = ref + sx.displacement + sx.rotation * r0i;
      const Eigen::Vector3d ve = sv.velocity + sv.angular_velocity.cross(sx.rotation * r0i);
      for (int a = 0; a < 2; ++a) {
        EXPECT_LE(std::abs(double(x[2 * i + a]) - xe[a]), std::nextafter(float(xe[a]), 1e9f) - float(xe[a])) << when;
        EXPECT_LE(std::abs(double(v[2 * i + a]) - ve[a]),
                  std::max(1e-12, double(std::nextafter(float(std::abs(ve[a])), 1e9f) - float(std::abs(ve[a])))))
            << when;
      }
      ++n;
    }
    EXPECT_GT(n, 50);
  };
  c.place_at(backend, tn);
  check(tn, tn, "placed at t(n)");
  c.after_kick(backend, 0.5 * dt);
  check(tn, tn + 0.5 * dt, "after the first half-kick");
  c.after_drift(backend, dt);
  check(tn + dt, tn + 0.5 * dt, "after the drift");
  c.after_forces(backend);
  c.after_kick(backend, 0.5 * dt);
  check(tn + dt, tn + dt, "after the second half-kick");
  // The velocities of the three stages differ (the test can tell them apart).
  EXPECT_GT((path.at(tn + 0.5 * dt).velocity - path.at(tn).velocity).norm(), 1e-4);
  EXPECT_GT((path.at(tn + dt).velocity - path.at(tn + 0.5 * dt).velocity).norm(), 1e-4);
}

// The shipped scenes with prescribed structures read and build. The paddle's CSV
// (scenes/paths/piston_stroke.csv) passes through its samples: at t = 0.5 s the stroke
// S/2 (t/T) (1 - cos(2 pi t/T)) = 0.02 m, written to 6 decimals (reference: the table).
TEST(PrescribedScenes, OscillatingCylinderAndWavePaddleBuild) {
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  for (const char* name : {"oscillating_cylinder_2d.yaml", "wave_paddle_2d.yaml"}) {
    SCOPED_TRACE(name);
    const auto scene = turbid::tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/" + name);
    turbid::fsi::Simulation sim(scene, opt);
    EXPECT_NE(sim.prescribed(), nullptr);
    EXPECT_GT(sim.summary().structure_particles, 50u);
  }
  const auto paddle = turbid::tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/wave_paddle_2d.yaml");
  const PrescribedPath path(paddle.structures[0].path);
  EXPECT_EQ(paddle.structures[0].path.times.size(), 61u);
  EXPECT_EQ(path.at(0.5).displacement[0], 0.02);
  EXPECT_EQ(path.at(10.0).displacement[0], 0.0);  // held at the last sample (t = 3 s, x = 0)
}

// 3D: a box turning about all three axes from an inline table (clamped spline) in a small tank.
// Reference: the path, every structure particle to 1 ulp after each of 20 steps, and forces.csv's
// quaternion and angular velocity equal to the path's.
TEST(PrescribedCoupling, FollowsA3dTableOfAnglesExactly) {
  const char* text = R"(name: prescribed_3d
dimensions: 3
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, 0, -9.81]
materials:
  water: {density: 1000, viscosity: 1.0e-3, sound_speed: 10}
walls:
  - box: {min: [0, 0, 0], max: [0.3, 0.3, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0, 0], max: [0.3, 0.3, 0.2]}}
structures:
  - name: block
    box: {size: [0.08, 0.06, 0.04]}
    position: [0.15, 0.15, 0.12]
    motion: prescribed
    path:
      samples:
        - [0, 0, 0, 0, 0, 0, 0]
        - [0.01, 0.002, -0.001, 0.001, 5, -3, 8]
        - [0.03, 0.004, 0.001, -0.002, -4, 6, 15]
output: {every: 1.0, vtk: false}
)";
  auto scene = turbid::tools::read_scene_string(text, "prescribed_3d.yaml");
  turbid::fsi::RunOptions opt;
  opt.backend = "cpu";
  opt.threads = 1;
  turbid::fsi::Simulation sim(scene, opt);
  sim.start();
  const PrescribedPath path(scene.structures[0].path);
  const Eigen::Vector3d ref(0.15, 0.15, 0.12);
  const auto& ids = sim.fields();
  int checked = 0;
  for (int step = 0; step < 20; ++step) {
    sim.step();
    sim.sync_to_host();
    const PathState s = path.at(sim.time());
    const auto& store = sim.store();
    const auto* x = store.data<float>(ids.position);
    const auto* r0 = store.data<float>(ids.body_offset);
    const auto* kind = store.data<std::uint8_t>(ids.kind);
    for (std::size_t i = 0; i < store.size(); ++i) {
      if (kind[i] != std::uint8_t(turbid::sph::Kind::structure)) continue;
      const Eigen::Vector3d xe = ref + s.displacement + s.rotation * Eigen::Vector3d(r0[3 * i], r0[3 * i + 1], r0[3 * i + 2]);
      for (int a = 0; a < 3; ++a)
        EXPECT_LE(std::abs(double(x[3 * i + a]) - xe[a]), std::nextafter(float(xe[a]), 1e9f) - float(xe[a]));
      ++checked;
    }
    const auto kin = sim.body_kinematics();
    EXPECT_EQ(kin[0].orientation[1], s.orientation.x());
    EXPECT_EQ(kin[0].orientation[2], s.orientation.y());
    EXPECT_EQ(kin[0].angular_velocity[0], s.angular_velocity[0]);
    EXPECT_EQ(kin[0].angular_velocity[1], s.angular_velocity[1]);
  }
  EXPECT_GT(sim.time(), 0.005) << "the steps went into the turning part of the table";
  EXPECT_EQ(checked, 20 * int(sim.summary().structure_particles));
  EXPECT_GE(sim.summary().structure_particles, 20u);
  EXPECT_GT(path.at(sim.time()).angular_velocity.norm(), 1.0);
}
