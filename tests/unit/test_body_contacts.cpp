// Constraints and DEM contacts of free bodies in coupled runs (fsi/body_contacts.hpp,
// fsi/body_constraints.hpp, fsi/body_coupling.hpp; issue #8), through the scene reader and the
// Simulation, with a tiny block of water in its own closed tank far away (a Simulation needs fluid).
// References and tolerances, per test:
//  - a 2D block hanging on a spring under gravity oscillates at omega = sqrt(k/m) (the weight only
//    shifts the equilibrium): the period between turning points within 0.5% of 2 pi sqrt(m/k);
//  - a spring between two bodies (no gravity) is central: total momentum stays 0 to double rounding
//    (1e-12 of m |v|) and the total angular momentum about the origin too;
//  - a disc dropped on the tank floor rebounds with the scene's restitution: -v_out / v_in within 5%
//    of e = 0.5 (v at the last step before the touch and the first after it);
//  - a box on a 30 degree polyline slope with mu = 0.3 slides with a = g (sin - mu cos) within 2%
//    (least-squares slope of the velocity along the incline over t = 0.05 .. 0.3 s); on a 20 degree
//    slope with mu = 0.5 (tan 20 = 0.36 < mu) it moves less than 1% of dx in 0.3 s (the tangential
//    springs' elastic deflection is ~1e-5 m here; sliding would take it 0.1 m);
//  - a 2D box on a hinge (a stiff pivot, body_constraints.hpp) swings as a compound pendulum,
//    T = 2 pi sqrt(I_pivot / (m g d)) (1 + theta0^2/16) within 0.5%, its pivot opening below 1% of dx;
//  - the disc dropped on a solid_box wall (exact face) and on a fixed box structure (its surface
//    particles as dx/2 spheres) rebounds with e within 5% as well; a 3D sphere on a tank floor too;
//  - the contact tests (Contacts.*) run for 'motion: free' (DEM) and 'motion: bullet' (Bullet's
//    rigid contacts) with the same scenes, references and tolerances;
//  - hard case: two boxes thrown by a tilted gravity into each other and a corner of the tank never
//    interpenetrate by more than 0.1 dx, measured on the particles (dx minus the smallest distance
//    between surface particles of the two bodies; dx/2 minus a surface particle's distance to a wall).
//    The same when a 2D dam break drives two boxes into each other and the right wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include "tests/unit/body_test_support.hpp"
#include "fsi/bullet_world.hpp"
#include "fsi/forces.hpp"
#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;
using test::cpu;
using test::scene_of;



// Scene head: 2D, dx = 0.01 m, a closed 0.1 x 0.05 m tank full of water at x = 3 m.
std::string head(const std::string& name, const std::string& gravity, double end) {
  return "name: " + name + R"(
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: )" + std::to_string(end) + R"(, cfl: 0.2}
gravity: )" + gravity + R"(
materials:
  water: {density: 1000, sound_speed: 10}
fluids:
  - {material: water, box: {min: [3.0, 0], max: [3.1, 0.05]}}
domain: {min: [-0.5, -0.5], max: [3.5, 2.0]}
)";
}
const char* kFarTank = "  - box: {min: [3.0, 0], max: [3.1, 0.05]}\n";

// Linear interpolation of the time where v crosses zero between two samples.
double crossing(double t0, double v0, double t1, double v1) { return t0 + (t1 - t0) * v0 / (v0 - v1); }

// The contact checks run for both integrators: 'motion: free' (the DEM contacts, body_contacts.hpp)
// and 'motion: bullet' (Bullet's rigid contacts, bullet_world.hpp), with the same scene, reference
// and tolerance; the bullet runs are skipped in a build without Bullet.
class Contacts : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (GetParam() == "bullet" && !fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  }
  // The scene text with every 'motion: free' given this test's motion.
  std::string moved(std::string yaml) const {
    for (std::size_t at = yaml.find("motion: free"); at != std::string::npos; at = yaml.find("motion: free", at + 1))
      yaml.replace(at, 12, "motion: " + GetParam());
    return yaml;
  }
  const char* name() const { return GetParam().c_str(); }
};

TEST(BodyConstraints, SpringMassOscillatesAtSqrtKOverM) {
  const double k = 500, m = 500 * 0.1 * 0.1;  // N/m per m, kg/m (the sampled box's mass is exact)
  const std::string yaml = head("spring", "[0, -9.81]", 2.0) + "walls:\n" + kFarTank + R"(structures:
  - {name: block, box: {size: [0.1, 0.1]}, position: [0.5, 1.0], motion: free, density: 500}
constraints:
  - {type: spring, name: hang, a: {structure: block, point: [0.5, 1.0]}, b: {anchor: [0.5, 1.3]}, stiffness: 500}
)";
  fsi::Simulation sim(scene_of(yaml), cpu());
  sim.start();
  ASSERT_NE(sim.bodies(), nullptr);
  const fsi::RigidBody& b = sim.bodies()->body(0);
  ASSERT_NEAR(b.mass(), m, 1e-12 * m);
  std::vector<double> turns;  // times where v_y goes from - to + (lowest points)
  double t_prev = sim.time(), v_prev = b.velocity().y();
  while (sim.time() < 2.0) {
    sim.step();
    const double v = b.velocity().y();
    if (v_prev < 0 && v >= 0) turns.push_back(crossing(t_prev, v_prev, sim.time(), v));
    t_prev = sim.time();
    v_prev = v;
  }
  ASSERT_GE(turns.size(), 2u);
  const double period = (turns.back() - turns.front()) / double(turns.size() - 1);
  const double expected = 2 * std::numbers::pi * std::sqrt(m / k);
  std::printf("[ measured ] spring-mass period %.6f s against 2 pi sqrt(m/k) = %.6f s (%+.4f%%), %zu periods, "
              "%d body substeps per fluid step (dt %.3e s)\n",
              period, expected, 100 * (period / expected - 1), turns.size() - 1, sim.bodies()->last_substeps(),
              sim.last_time_step());
  EXPECT_NEAR(period, expected, 0.005 * expected);
  // The weight moves the centre of the swing down to m g / k below the spring's rest position.
  // A spring at the centre of mass exerts no torque: the sampled centre and the attachment point
  // differ by double rounding only (~1e-16 m of lever under ~50 N), so the block turns by far less
  // than 1e-9 rad.
  const double angle = 2 * std::asin(std::min(1.0, b.orientation().vec().norm()));
  EXPECT_LT(angle, 1e-9);
}

// The message of the exception the first step of `yaml`'s scene throws ("" if none).
std::string first_step_error(const std::string& yaml) {
  fsi::Simulation sim(scene_of(yaml), cpu());
  sim.start();
  try {
    sim.step();
  } catch (const std::exception& e) {
    std::printf("[ measured ] %s\n", e.what());
    return e.what();
  }
  return "";
}

// A spring too stiff for the body substeps (issue #27 item 2): the run stops with a message that
// names the constraint's scene line, the key and a value that would do; that value, halved, runs.
TEST(BodyConstraints, TooStiffASpringIsNamedWithAStiffnessThatWouldDo) {
  const auto yaml = [](const std::string& k) {
    return head("stiff", "[0, -9.81]", 0.01) + "walls:\n" + kFarTank + R"(structures:
  - {name: block, box: {size: [0.1, 0.1]}, position: [0.5, 1.0], motion: free, density: 500}
constraints:
  - {type: spring, name: hang, a: {structure: block, point: [0.5, 1.0]}, b: {anchor: [0.5, 1.3]}, stiffness: )" +
           k + "}\n";
  };
  const std::string message = first_step_error(yaml("1e20"));
  ASSERT_NE(message.find(": error: constraint 'hang' needs body substeps"), std::string::npos) << message;
  EXPECT_NE(message.find("lower its 'stiffness' (1e+20 N/m)"), std::string::npos) << message;
  // The scene's line of the constraint: the one after 'constraints:'.
  const std::string text = yaml("1e20");
  const int line = 1 + int(std::count(text.begin(), text.begin() + long(text.find("  - {type: spring")), '\n'));
  EXPECT_NE(message.find(":" + std::to_string(line) + ":"), std::string::npos) << message << " (line " << line << ")";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex("below about ([0-9.e+]+) N/m"))) << message;
  const double suggested = std::stod(m[1].str());
  ASSERT_LT(suggested, 1e20);
  // The spring's substep scales as sqrt(m / k): half the suggested stiffness fits the limit.
  fsi::Simulation ok(scene_of(yaml(std::to_string(0.5 * suggested))), cpu());
  ok.start();
  EXPECT_NO_THROW(ok.step());
  EXPECT_LE(ok.bodies()->last_substeps(), int(fsi::BodyCoupling::kMaxSubsteps));
}

TEST(BodyConstraints, SpringBetweenTwoBodiesConservesMomentum) {
  const std::string yaml = head("pair", "[0, 0]", 0.2) + "walls:\n" + kFarTank + R"(structures:
  - {name: left, box: {size: [0.1, 0.1]}, position: [0.5, 1.0], rotation: 10, motion: free, density: 500}
  - {name: right, box: {size: [0.2, 0.1]}, position: [0.9, 1.05], motion: free, density: 800}
constraints:
  - {type: spring, a: {structure: left, point: [0.53, 1.02]}, b: {structure: right, point: [0.82, 1.0]},
     stiffness: 800, damping: 2, rest_length: 0.2}
)";
  fsi::Simulation sim(scene_of(yaml), cpu());
  sim.start();
  const fsi::RigidBody& a = sim.bodies()->body(0);
  const fsi::RigidBody& c = sim.bodies()->body(1);
  double scale = 0, worst_p = 0, worst_l = 0;
  for (int n = 0; n < 400; ++n) {
    sim.step();
    const Eigen::Vector3d p = a.linear_momentum() + c.linear_momentum();
    const Eigen::Vector3d l = a.position().cross(a.linear_momentum()) + a.angular_momentum() +
                              c.position().cross(c.linear_momentum()) + c.angular_momentum();
    scale = std::max(scale, a.linear_momentum().norm() + c.linear_momentum().norm());
    worst_p = std::max(worst_p, p.norm());
    worst_l = std::max(worst_l, l.norm());
  }
  std::printf("[ measured ] two bodies on a spring: |P| <= %.3e, |L| <= %.3e (momentum scale %.3e kg m/s)\n", worst_p,
              worst_l, scale);
  ASSERT_GT(scale, 1e-3) << "the stretched spring should set the bodies moving";
  EXPECT_LE(worst_p, 1e-12 * scale);
  EXPECT_LE(worst_l, 1e-12 * scale);
}

// A contact too stiff for the body substeps (issue #27 item 2): the message names the structure's
// line and its youngs_modulus with a value that would do; that value, halved, runs.
TEST(BodyContacts, TooStiffAContactIsNamedWithAModulusThatWouldDo) {
  const auto yaml = [](const std::string& e) {
    return head("hard", "[0, -9.81]", 0.01) + "walls:\n  - box: {min: [0, 0], max: [0.6, 0.6]}\n" + kFarTank +
           "structures:\n  - {name: ball, sphere: {radius: 0.05}, position: [0.3, 0.25], motion: free, density: "
           "1000,\n     contact: {youngs_modulus: " +
           e + ", poisson_ratio: 0.3, restitution: 0.5, friction: 0.3}}\n";
  };
  const std::string message = first_step_error(yaml("1e40"));
  ASSERT_NE(message.find(": error: the contacts of structure 'ball' need body substeps"), std::string::npos) << message;
  const std::string text = yaml("1e40");
  const int line = 1 + int(std::count(text.begin(), text.begin() + long(text.find("  - {name: ball")), '\n'));
  EXPECT_NE(message.find(":" + std::to_string(line) + ":"), std::string::npos) << message << " (line " << line << ")";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex("'contact: youngs_modulus' \\(1e\\+40 Pa\\) below about ([0-9.e+]+) Pa")))
      << message;
  const double suggested = std::stod(m[1].str());
  fsi::Simulation ok(scene_of(yaml(std::to_string(0.5 * suggested))), cpu());
  ok.start();
  EXPECT_NO_THROW(ok.step());
}

TEST_P(Contacts, DiscDroppedOnTheFloorReboundsWithTheRestitution) {
  const double e = 0.5;
  const std::string yaml = head("drop", "[0, -9.81]", 0.3) + "walls:\n  - box: {min: [0, 0], max: [0.6, 0.6]}\n" +
                           kFarTank + R"(structures:
  - {name: ball, sphere: {radius: 0.05}, position: [0.3, 0.25], motion: free, density: 1000,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: 0.3}}
)";
  fsi::Simulation sim(scene_of(moved(yaml)), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  double v_in = 0, v_out = 0;
  bool touched = false;
  int substeps = 0;
  while (sim.time() < 0.3) {
    const double v_before = b.velocity().y();
    sim.step();
    const bool touching = sim.bodies()->contact_load(0).force.norm() > 0;
    if (touching && !touched) {
      touched = true;
      v_in = v_before;
    }
    substeps = std::max(substeps, sim.bodies()->last_substeps());
    if (touched && !touching) {
      v_out = b.velocity().y();
      break;
    }
  }
  ASSERT_TRUE(touched);
  ASSERT_GT(v_out, 0) << "the ball should have left the floor by t = 0.3 s";
  const double measured = -v_out / v_in;
  std::printf("[ measured ] %s disc on the floor: v_in = %.4f m/s, v_out = %.4f m/s, e = %.4f against %.2f (%+.2f%%), "
              "up to %d body substeps per fluid step\n",
              name(), v_in, v_out, measured, e, 100 * (measured / e - 1), substeps);
  EXPECT_NEAR(measured, e, 0.05 * e);
}

// The first bounce of body 0: -v_out / v_in along `axis` (v at the last step before the touch and the
// first step after it), or 0 when it did not bounce by `end`.
double bounce(fsi::Simulation& sim, int axis, double end, double* v_in_out = nullptr) {
  const fsi::RigidBody& b = sim.bodies()->body(0);
  double v_in = 0;
  bool touched = false;
  while (sim.time() < end) {
    const double v_before = b.velocity()[axis];
    sim.step();
    const bool touching = sim.bodies()->contact_load(0).force.norm() > 0;
    if (touching && !touched) {
      touched = true;
      v_in = v_before;
    }
    if (touched && !touching) {
      if (v_in_out) *v_in_out = v_in;
      return -b.velocity()[axis] / v_in;
    }
  }
  return 0;
}

TEST_P(Contacts, DiscReboundsFromASolidBoxAndFromAFixedStructure) {
  const double e = 0.5;
  const std::string disc = R"(  - {name: ball, sphere: {radius: 0.05}, position: [0.3, 0.45], motion: free, density: 1000,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: 0.3}}
)";
  // On a solid box (an exact face) ...
  fsi::Simulation on_box(scene_of(moved(head("drop_box", "[0, -9.81]", 0.4) + "walls:\n  - solid_box: {min: [0.1, 0.1], max: [0.5, 0.2]}\n" +
                                  kFarTank + "structures:\n" + disc)),
                         cpu());
  on_box.start();
  double v_box = 0;
  const double e_box = bounce(on_box, 1, 0.4, &v_box);
  // ... and on a fixed box structure (its surface particles, spheres of dx/2), whose contact
  // material is rigid-like and more elastic: the pair takes the smaller restitution, the disc's.
  fsi::Simulation on_structure(
      scene_of(moved(head("drop_post", "[0, -9.81]", 0.4) + "walls:\n" + kFarTank + "structures:\n" + disc +
               "  - {name: post, box: {size: [0.4, 0.1]}, position: [0.3, 0.15], contact: {youngs_modulus: 1.0e10, "
               "restitution: 0.9, friction: 0.5}}\n")),
      cpu());
  on_structure.start();
  double v_post = 0;
  const double e_post = bounce(on_structure, 1, 0.4, &v_post);
  std::printf("[ measured ] %s disc on a solid box: e = %.4f (v_in %.3f m/s); on a fixed structure: e = %.4f (v_in %.3f "
              "m/s); against %.2f\n",
              name(), e_box, v_box, e_post, v_post, e);
  EXPECT_NEAR(e_box, e, 0.05 * e);
  EXPECT_NEAR(e_post, e, 0.05 * e);
  // forces.csv names the contact force with its unit.
  const auto cols = fsi::force_columns(on_structure.scene());
  EXPECT_NE(std::find(cols.begin(), cols.end(), "ball.contact_Fy [N/m]"), cols.end());
  EXPECT_EQ(std::find(cols.begin(), cols.end(), "post.contact_Fy [N/m]"), cols.end()) << "a fixed structure has no body";
}

// A prescribed paddle (a 0.1 x 0.2 m box moving at V = 0.5 m/s along +x, rigid) strikes a disc at
// rest, no gravity: in the paddle's frame the disc arrives at -V and leaves at e V, so it leaves at
// v = (1 + e) V (Newton's restitution against an infinite mass), within 5%; the paddle's spheres
// move along its path through the substeps (DEM) or as a kinematic Bullet body.
TEST_P(Contacts, PrescribedPaddleKicksADiscWithTheRestitution) {
  const double e = 0.5, V = 0.5;
  fsi::Simulation sim(scene_of(moved(head("paddle", "[0, 0]", 0.6) + "walls:\n" + kFarTank + R"(structures:
  - {name: ball, sphere: {radius: 0.05}, position: [0.5, 0.3], motion: free, density: 1000,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: 0.3}}
  - {name: paddle, box: {size: [0.1, 0.2]}, position: [0.2, 0.3], motion: prescribed, path: {velocity: [0.5, 0]}}
)")),
                      cpu());
  sim.start();
  bool touched = false, left = false;
  while (sim.time() < 0.6 && !left) {
    sim.step();
    const bool touching = sim.bodies()->contact_load(0).force.norm() > 0;
    touched = touched || touching;
    left = touched && !touching;
  }
  const double v_out = sim.bodies()->body(0).velocity().x();
  std::printf("[ measured ] %s disc kicked by a paddle at %.2f m/s: leaves at %.4f m/s against (1 + e) V = %.4f (%+.2f%%)\n",
              name(), V, v_out, (1 + e) * V, 100 * (v_out / ((1 + e) * V) - 1));
  ASSERT_TRUE(left) << "the paddle should have struck the disc and let it go by t = 0.6 s";
  EXPECT_NEAR(v_out, (1 + e) * V, 0.05 * (1 + e) * V);
}

// A clump's flat face lands on all its bottom spheres at once: they act in parallel and share the
// mass (body_contacts.hpp), so the box rebounds with the law's restitution too (within 5%).
TEST_P(Contacts, BoxLandingFlatReboundsWithTheRestitution) {
  const double e = 0.5;
  fsi::Simulation sim(scene_of(moved(head("flat", "[0, -9.81]", 0.4) + "walls:\n  - box: {min: [0, 0], max: [0.6, 0.6]}\n" +
                                     kFarTank + R"(structures:
  - {name: block, box: {size: [0.2, 0.1]}, position: [0.3, 0.25], motion: free, density: 800,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: 0.3}}
)")),
                      cpu());
  sim.start();
  double v_in = 0;
  const double measured = bounce(sim, 1, 0.4, &v_in);
  const auto* dem = sim.bodies()->contacts();
  std::printf("[ measured ] %s box landing flat: v_in %.4f m/s, e = %.4f against %.2f (%+.2f%%), face of %d spheres\n",
              name(), v_in, measured, e, 100 * (measured / e - 1), dem ? dem->shape(0).face_count : 0);
  EXPECT_NEAR(measured, e, 0.05 * e);
}

TEST_P(Contacts, SphereReboundsFromATankFloorIn3D) {
  const double e = 0.6;
  const std::string yaml = R"(name: drop3d
dimensions: 3
resolution: {particle_spacing: 0.02, smoothing_ratio: 1.3}
time: {end: 0.4, cfl: 0.2}
gravity: [0, 0, -9.81]
materials:
  water: {density: 1000, sound_speed: 10}
walls:
  - box: {min: [0, 0, 0], max: [0.4, 0.4, 0.5]}
  - box: {min: [2.0, 0, 0], max: [2.06, 0.06, 0.04]}
fluids:
  - {material: water, box: {min: [2.0, 0, 0], max: [2.06, 0.06, 0.04]}}
structures:
  - {name: ball, sphere: {radius: 0.06}, position: [0.2, 0.2, 0.3], motion: free, density: 2000,
     contact: {youngs_modulus: 1.0e9, poisson_ratio: 0.3, restitution: 0.6, friction: 0.3}}
domain: {min: [-0.2, -0.2, -0.2], max: [2.3, 0.6, 0.7]}
)";
  fsi::Simulation sim(scene_of(moved(yaml)), cpu());
  sim.start();
  double v_in = 0;
  const double measured = bounce(sim, 2, 0.4, &v_in);
  const fsi::RigidBody& b = sim.bodies()->body(0);
  std::printf("[ measured ] %s 3D sphere on the floor: v_in %.4f m/s, e = %.4f against %.2f (%+.2f%%); x, y drift %.2e, "
              "%.2e m\n",
              name(), v_in, measured, e, 100 * (measured / e - 1), b.position().x() - 0.2, b.position().y() - 0.2);
  EXPECT_NEAR(measured, e, 0.05 * e);
}

TEST(BodyConstraints, HingedBoxSwingsAsACompoundPendulum) {
  const double dx = 0.01, g = 9.81, d = 0.2, theta0 = 5 * std::numbers::pi / 180;
  // The box's centre hangs d below the hinge, released at theta0 from the vertical.
  const double hx = 0.5, hy = 1.2, cx = hx + d * std::sin(theta0), cy = hy - d * std::cos(theta0);
  char buf[1024];
  std::snprintf(buf, sizeof buf, R"(walls:
%sstructures:
  - {name: flap, box: {size: [0.1, 0.1]}, position: [%.17g, %.17g], rotation: %.17g, motion: free, density: 500}
constraints:
  - {type: hinge, a: {structure: flap, point: [%.17g, %.17g]}, b: {anchor: [%.17g, %.17g]}}
)",
                kFarTank, cx, cy, 5.0, hx, hy, hx, hy);
  fsi::Simulation sim(scene_of(head("pendulum", "[0, -9.81]", 2.0) + buf), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const Eigen::Vector3d pivot_body = Eigen::Vector3d(hx, hy, 0) - b.position();
  std::vector<double> turns;
  double t_prev = sim.time(), w_prev = b.angular_velocity().z(), worst = 0;
  while (sim.time() < 2.0) {
    sim.step();
    const double w = b.angular_velocity().z();
    if (w_prev > 0 && w <= 0) turns.push_back(crossing(t_prev, w_prev, sim.time(), w));
    t_prev = sim.time();
    w_prev = w;
    worst = std::max(worst, (b.to_world(pivot_body) - Eigen::Vector3d(hx, hy, 0)).norm());
  }
  ASSERT_GE(turns.size(), 2u);
  const double period = (turns.back() - turns.front()) / double(turns.size() - 1);
  const double m = 500 * 0.01, inertia = m * (0.01 + 0.01) / 12 + m * d * d;
  const double expected = 2 * std::numbers::pi * std::sqrt(inertia / (m * g * d)) * (1 + theta0 * theta0 / 16);
  std::printf("[ measured ] hinged box: period %.5f s against %.5f s (%+.3f%%), pivot opening <= %.3e m (%.2e dx), "
              "%d body substeps per fluid step\n",
              period, expected, 100 * (period / expected - 1), worst, worst / dx, sim.bodies()->last_substeps());
  EXPECT_NEAR(period, expected, 0.005 * expected);
  EXPECT_LT(worst, 0.01 * dx);
}

// A 0.1 x 0.05 m box resting on a polyline slope of `degrees`, friction mu; returns the box's
// velocity and displacement along the slope (down the slope negative) sampled every step.
struct SlopeRun {
  std::vector<double> t, v, s;
};
SlopeRun slide(const std::string& motion, double degrees, double mu, double end) {
  const double th = degrees * std::numbers::pi / 180, c = std::cos(th), s = std::sin(th);
  const double along = 0.7, half = 0.025;
  const double cx = along * c - half * s, cy = along * s + half * c;
  char buf[1024];
  std::snprintf(buf, sizeof buf, R"(walls:
  - polyline: {points: [[0, 0], [%.17g, %.17g]]}
%sstructures:
  - {name: block, box: {size: [0.1, 0.05]}, position: [%.17g, %.17g], rotation: %.17g, motion: %s, density: 1000,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: %.17g}}
)",
                c, s, kFarTank, cx, cy, degrees, motion.c_str(), mu);
  fsi::Simulation sim(scene_of(head("slope", "[0, -9.81]", end) + buf), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const Eigen::Vector3d x0 = b.position(), u(c, s, 0);
  SlopeRun r;
  while (sim.time() < end) {
    sim.step();
    r.t.push_back(sim.time());
    r.v.push_back(b.velocity().dot(u));
    r.s.push_back((b.position() - x0).dot(u));
  }
  return r;
}

TEST_P(Contacts, BoxSlidesDownAnInclineWithCoulombFriction) {
  const double degrees = 30, mu = 0.3, g = 9.81;
  const double th = degrees * std::numbers::pi / 180;
  const double expected = -g * (std::sin(th) - mu * std::cos(th));
  const SlopeRun r = slide(GetParam(), degrees, mu, 0.3);
  // Least-squares line v = v0 + a t over t >= 0.05 s (after the first settling).
  double n = 0, st = 0, sv = 0, stt = 0, stv = 0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < 0.05) continue;
    n += 1;
    st += r.t[i];
    sv += r.v[i];
    stt += r.t[i] * r.t[i];
    stv += r.t[i] * r.v[i];
  }
  const double a = (n * stv - st * sv) / (n * stt - st * st);
  std::printf("[ measured ] %s box on a %.0f degree slope, mu = %.2f: a = %.4f m/s^2 against g (sin - mu cos) = %.4f "
              "(%+.3f%%), slid %.4f m\n",
              name(), degrees, mu, a, expected, 100 * (a / expected - 1), r.s.back());
  EXPECT_NEAR(a, expected, 0.02 * std::abs(expected));
}

TEST_P(Contacts, BoxStaysPutWhenTheSlopeIsBelowTheFrictionAngle) {
  const double dx = 0.01;
  const SlopeRun r = slide(GetParam(), 20, 0.5, 0.3);
  double worst = 0;
  for (double s : r.s) worst = std::max(worst, std::abs(s));
  std::printf("[ measured ] %s box on a 20 degree slope, mu = 0.5: largest displacement along the slope %.3e m "
              "(%.2e dx), final speed %.3e m/s\n",
              name(), worst, worst / dx, r.v.back());
  EXPECT_LT(worst, 0.01 * dx);
}

// A floor of two collinear polyline segments joined at x = 0.5 m: a 0.1 x 0.05 m box pushed along it
// by a tilted gravity [2, -9.81] with mu = 0.1 slides across the joint with a = 2 - mu g =
// 1.019 m/s^2 within 2% (least squares over 0.05..0.6 s, from x = 0.42 m to past 0.58 m) and is not
// kicked up there: its height stays within 0.01 dx of resting and its vertical speed below 1 cm/s,
// under 2% of its sliding speed at the joint. (The DEM takes one contact per sphere at a joint,
// body_contacts.hpp; Bullet's box-box test could pick the next slab's end. Bullet's resting contacts
// jitter at about g dt, 2.5e-3 m/s here, when its manifold renews its points.)
TEST_P(Contacts, BoxSlidesAcrossTheJointOfTwoCollinearSegments) {
  const double dx = 0.01, mu = 0.1, g = 9.81, gx = 2.0;
  fsi::Simulation sim(scene_of(moved(head("joint", "[2.0, -9.81]", 0.6) + R"(walls:
  - polyline: {points: [[0, 0], [0.5, 0], [1.2, 0]]}
)" + kFarTank + R"(structures:
  - {name: block, box: {size: [0.1, 0.05]}, position: [0.42, 0.025], motion: free, density: 1000,
     contact: {youngs_modulus: 1.0e8, poisson_ratio: 0.3, restitution: 0.5, friction: 0.1}}
)")),
                      cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const double y_rest0 = b.position().y();
  double n = 0, st = 0, sv = 0, stt = 0, stv = 0, worst_vy = 0, lo = 1e9, hi = -1e9;
  while (sim.time() < 0.6) {
    sim.step();
    const double t = sim.time(), v = b.velocity().x();
    if (t < 0.05) continue;
    n += 1;
    st += t;
    sv += v;
    stt += t * t;
    stv += t * v;
    worst_vy = std::max(worst_vy, std::abs(b.velocity().y()));
    lo = std::min(lo, b.position().y());
    hi = std::max(hi, b.position().y());
  }
  const double a = (n * stv - st * sv) / (n * stt - st * st), expected = gx - mu * g;
  std::printf("[ measured ] %s box across a joint: reached x = %.3f m, a = %.4f m/s^2 against %.4f (%+.3f%%), height "
              "range %.2e m (%.4f dx; at rest %.4f m), |vy| <= %.2e m/s\n",
              name(), b.position().x(), a, expected, 100 * (a / expected - 1), hi - lo, (hi - lo) / dx, y_rest0, worst_vy);
  ASSERT_GT(b.position().x(), 0.58) << "the box should have crossed the joint at x = 0.5 m";
  EXPECT_NEAR(a, expected, 0.02 * expected);
  EXPECT_LT(hi - lo, 0.01 * dx);
  EXPECT_LT(worst_vy, 1e-2);
}

// Interpenetration seen on the particles of bodies 0 and 1 in a closed tank [0, width] x [0, height]
// (2D): the smallest distance between a particle of one body and one of the other (touching
// surfaces put their surface layers dx apart), and the deepest a body particle reaches past dx/2
// from a tank face (surface particles lie dx/2 inside the surface).
struct ParticleGaps {
  double closest = 1e9;  // [m]
  double wall = -1e9;    // [m], dx/2 minus the smallest distance to a face
};
ParticleGaps particle_gaps(const fsi::Simulation& sim, double dx, double width, double height) {
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const auto* x = st.data<float>(ids.position);
  const auto* kind = st.data<std::uint8_t>(ids.kind);
  const auto* body = st.data<std::uint8_t>(ids.body);
  std::vector<std::size_t> p0, p1;
  ParticleGaps g;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 2) continue;
    (body[i] == 0 ? p0 : p1).push_back(i);
    const double d = std::min({double(x[2 * i]), double(x[2 * i + 1]), width - x[2 * i], height - x[2 * i + 1]});
    g.wall = std::max(g.wall, 0.5 * dx - d);
  }
  for (std::size_t i : p0)
    for (std::size_t j : p1)
      g.closest = std::min(g.closest, std::hypot(double(x[2 * i] - x[2 * j]), double(x[2 * i + 1] - x[2 * j + 1])));
  return g;
}

TEST_P(Contacts, BodiesDrivenIntoEachOtherAndACornerDoNotInterpenetrate) {
  const double dx = 0.01;
  // Gravity tilted towards -x: the lower box is pressed into the corner, the upper one falls on it
  // and both are pushed against the left wall.
  const std::string yaml = head("pile", "[-6.0, -9.81]", 0.5) + "walls:\n  - box: {min: [0, 0], max: [0.6, 0.6]}\n" +
                           kFarTank + R"(structures:
  - {name: lower, box: {size: [0.12, 0.08]}, position: [0.12, 0.06], rotation: 5, motion: free, density: 1200,
     contact: {youngs_modulus: 3.0e10, poisson_ratio: 0.3, restitution: 0.3, friction: 0.4}}
  - {name: upper, box: {size: [0.1, 0.1]}, position: [0.2, 0.3], rotation: -20, motion: free, density: 2000,
     contact: {youngs_modulus: 3.0e10, poisson_ratio: 0.3, restitution: 0.3, friction: 0.4}}
)";
  fsi::Simulation sim(scene_of(moved(yaml)), cpu());
  sim.start();
  double worst_pair = -1e9, worst_wall = -1e9, worst_sphere = 0;
  int most_substeps = 0;
  int touched_pair = 0;
  while (sim.time() < 0.5) {
    sim.step();
    // The contact law's own overlap: DEM spheres, or Bullet's deepest penetration.
    const auto* bullet = sim.bodies()->bullet();
    worst_sphere = std::max(worst_sphere, bullet ? bullet->last_max_penetration() : sim.bodies()->last_max_overlap());
    most_substeps = std::max(most_substeps, sim.bodies()->last_substeps());
    const ParticleGaps g = particle_gaps(sim, dx, 0.6, 0.6);
    const double closest = g.closest;
    worst_wall = std::max(worst_wall, g.wall);
    worst_pair = std::max(worst_pair, dx - closest);
    if (closest < 1.01 * dx) ++touched_pair;  // touching, within 1% of dx (rigid Bullet contacts do not overlap)
  }
  const auto& lo = sim.bodies()->body(0);
  const auto& up = sim.bodies()->body(1);
  std::printf("[ measured ] %s pile in the corner: body-body overlap <= %.3e m (%.4f dx), body-wall <= %.3e m (%.4f dx), "
              "contact spheres <= %.3e m; steps with the bodies touching %d; final x %.4f, %.4f m; up to %d body substeps "
              "per fluid step of %.3e s\n",
              name(), worst_pair, worst_pair / dx, worst_wall, worst_wall / dx, worst_sphere, touched_pair, lo.position().x(),
              up.position().x(), most_substeps, sim.last_time_step());
  EXPECT_GT(touched_pair, 100) << "the upper box should land on the lower one";
  EXPECT_LT(lo.position().x(), 0.1) << "gravity should press the lower box into the corner";
  EXPECT_LE(worst_pair, 0.1 * dx);
  EXPECT_LE(worst_wall, 0.1 * dx);
  EXPECT_LE(worst_sphere, 0.1 * dx);
}


// The same bound when the flow drives them: a 2D dam break (0.25 x 0.3 m of water, dx = 0.01 m)
// strikes two boxes standing on the floor near the right wall and pushes them into each other and
// into the wall; overlaps measured on the particles as above, bound 0.1 dx.
TEST_P(Contacts, DamBreakDrivesTwoBoxesIntoEachOtherAndTheWallWithoutInterpenetration) {
  const double dx = 0.01, end = 0.8;
  const std::string yaml = R"(name: dam_boxes
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: 0.8, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {density: 1000, sound_speed: 25}
walls:
  - box: {min: [0, 0], max: [0.8, 0.5]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.25, 0.3]}}
structures:
  - {name: first, box: {size: [0.06, 0.06]}, position: [0.6, 0.03], motion: free, density: 1300,
     contact: {youngs_modulus: 3.0e10, poisson_ratio: 0.3, restitution: 0.3, friction: 0.3}}
  - {name: second, box: {size: [0.06, 0.08]}, position: [0.7, 0.04], motion: free, density: 1300,
     contact: {youngs_modulus: 3.0e10, poisson_ratio: 0.3, restitution: 0.3, friction: 0.3}}
)";
  fsi::Simulation sim(scene_of(moved(yaml)), cpu());
  sim.start();
  double worst_pair = -1e9, worst_wall = -1e9;
  int touched_pair = 0, touched_wall = 0, most_substeps = 0;
  const fsi::RigidBody& a = sim.bodies()->body(0);
  const fsi::RigidBody& b = sim.bodies()->body(1);
  const double a0 = a.position().x(), b0 = b.position().x();
  while (sim.time() < end) {
    sim.step();
    most_substeps = std::max(most_substeps, sim.bodies()->last_substeps());
    const ParticleGaps g = particle_gaps(sim, dx, 0.8, 0.5);
    const double closest = g.closest;
    worst_pair = std::max(worst_pair, dx - closest);
    worst_wall = std::max(worst_wall, g.wall);
    if (closest < dx) ++touched_pair;
    if (b.position().x() > 0.8 - 0.03 - 0.5 * dx) ++touched_wall;
  }
  std::printf("[ measured ] %s dam break on two boxes: moved %.4f m and %.4f m; steps touching each other %d, the right "
              "wall %d; body-body overlap <= %.3e m (%.4f dx), body-wall <= %.3e m (%.4f dx); up to %d substeps, "
              "%llu steps\n",
              name(), a.position().x() - a0, b.position().x() - b0, touched_pair, touched_wall, worst_pair, worst_pair / dx,
              worst_wall, worst_wall / dx, most_substeps, static_cast<unsigned long long>(sim.steps()));
  EXPECT_GT(touched_pair, 10) << "the flow should push the first box against the second";
  EXPECT_LE(worst_pair, 0.1 * dx);
  EXPECT_LE(worst_wall, 0.1 * dx);
}


// 3D: a hinge to an anchor about the world y axis locks rx and rz (scene_interactions.hpp); a cube
// hanging d = 0.2 m below it, released at 5 degrees about y, swings as the compound pendulum of the
// 2D test (same period formula, I_yy of the cube) within 0.5%, its pivot within 0.01 dx, and turns
// about y only (rx, rz stay 0 exactly).
TEST(BodyConstraints, HingedCubeSwingsAboutItsWorldAxisIn3D) {
  const double dx = 0.02, g = 9.81, d = 0.2, theta0 = 5 * std::numbers::pi / 180;
  const double hx = 0.5, hz = 1.2, cx = hx + d * std::sin(theta0), cz = hz - d * std::cos(theta0);
  char buf[2048];
  std::snprintf(buf, sizeof buf, R"(name: pendulum3d
dimensions: 3
resolution: {particle_spacing: 0.02, smoothing_ratio: 1.3}
time: {end: 1.2, cfl: 0.2}
gravity: [0, 0, -9.81]
materials:
  water: {density: 1000, sound_speed: 10}
walls:
  - box: {min: [3.0, 0, 0], max: [3.06, 0.06, 0.04]}
fluids:
  - {material: water, box: {min: [3.0, 0, 0], max: [3.06, 0.06, 0.04]}}
structures:
  - {name: flap, box: {size: [0.1, 0.1, 0.1]}, position: [%.17g, 0.5, %.17g], rotation: [0, %.17g, 0], motion: free,
     density: 500}
constraints:
  - {type: hinge, a: {structure: flap, point: [%.17g, 0.5, %.17g]}, b: {anchor: [%.17g, 0.5, %.17g]}, axis: [0, 1, 0]}
domain: {min: [-0.5, -0.5, -0.5], max: [3.5, 1.5, 2.0]}
)",
                cx, cz, -5.0, hx, hz, hx, hz);
  fsi::Simulation sim(scene_of(buf), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  EXPECT_FALSE(b.mask().rotation[0]);
  EXPECT_TRUE(b.mask().rotation[1]);
  EXPECT_FALSE(b.mask().rotation[2]);
  const Eigen::Vector3d pivot_body = Eigen::Vector3d(hx, 0.5, hz) - b.position();
  std::vector<double> turns;
  double t_prev = sim.time(), w_prev = b.angular_velocity().y(), worst = 0, off_axis = 0;
  while (sim.time() < 1.2) {
    sim.step();
    const Eigen::Vector3d w = b.angular_velocity();
    if (w_prev > 0 && w.y() <= 0) turns.push_back(crossing(t_prev, w_prev, sim.time(), w.y()));
    t_prev = sim.time();
    w_prev = w.y();
    worst = std::max(worst, (b.to_world(pivot_body) - Eigen::Vector3d(hx, 0.5, hz)).norm());
    off_axis = std::max({off_axis, std::abs(w.x()), std::abs(w.z())});
  }
  ASSERT_GE(turns.size(), 1u);
  // Released at rest at one extreme, w_y grows positive and falls back through 0 at the other
  // extreme, half a period in: successive such turns are a period apart; a single one is T/2.
  const double m = 500 * 1e-3, inertia = m * (0.01 + 0.01) / 12 + m * d * d;
  const double expected = 2 * std::numbers::pi * std::sqrt(inertia / (m * g * d)) * (1 + theta0 * theta0 / 16);
  const double period = turns.size() >= 2 ? (turns.back() - turns.front()) / double(turns.size() - 1) : 2 * turns[0];
  std::printf("[ measured ] hinged cube (3D): period %.5f s against %.5f s (%+.3f%%), pivot opening <= %.3e m (%.2e dx), "
              "|w_x|, |w_z| <= %.1e rad/s\n",
              period, expected, 100 * (period / expected - 1), worst, worst / dx, off_axis);
  EXPECT_NEAR(period, expected, 0.005 * expected);
  EXPECT_LT(worst, 0.01 * dx);
  EXPECT_EQ(off_axis, 0.0);
}


// The design card's case in 2D (scenes/moored_pipe_dam_break_2d.yaml): a pipe on two moorings struck
// by a dam break runs to its end with finite loads, no water particle gets inside the pipe (every
// fluid particle at least R from its moving axis, checked after every step: the structure's
// particles fill the disc up to R, so a fluid particle closer has passed through its surface), and
// where the flow presses it onto the bed the contact holds it there: its surface dips below the bed
// by less than 0.1 dx. The scene uses DBC; with mDBC water gets 4.1 dx inside this light (700
// kg/m^3) pipe at the impact (docs/validation.md C).
TEST(BodyContacts, MooredPipeStruckByADamBreak) {
  fsi::Scene scene = tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/moored_pipe_dam_break_2d.yaml");
  const double dx = scene.particle_spacing, R = 0.05, end = scene.end_time;
  fsi::Simulation sim(std::move(scene), cpu());
  sim.start();
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  const fsi::RigidBody& pipe = sim.bodies()->body(0);
  const Eigen::Vector3d x0 = pipe.position();
  double closest = 1e9, lowest = 1e9, largest_force = 0, largest_shift = 0, first_inside = -1, bed_gap_then = 0;
  bool finite = true;
  while (sim.time() < end) {
    sim.step();
    const auto* x = st.data<float>(ids.position);
    const auto* kind = st.data<std::uint8_t>(ids.kind);
    const Eigen::Vector3d c = pipe.position();
    for (std::size_t i = 0; i < st.size(); ++i)
      if (kind[i] == 0) closest = std::min(closest, std::hypot(x[2 * i] - c.x(), x[2 * i + 1] - c.y()));
    lowest = std::min(lowest, c.y() - R);
    if (first_inside < 0 && closest < R - 0.5 * dx) {
      first_inside = sim.time();
      bed_gap_then = c.y() - R;
    }
    const fsi::Wrench& f = sim.bodies()->fluid_load(0);
    finite = finite && f.force.allFinite() && f.torque.allFinite() && c.allFinite();
    largest_force = std::max(largest_force, f.force.norm());
    largest_shift = std::max(largest_shift, (c - x0).norm());
  }
  std::printf("[ measured ] moored pipe in a dam break to t = %.2f s (%llu steps): nearest water particle %.4f m from the "
              "axis (R = %.2f m, %.2f dx inside the surface at most), lowest surface point %.4f m, largest fluid force "
              "%.1f N/m, largest displacement %.4f m\n",
              sim.time(), static_cast<unsigned long long>(sim.steps()), closest, R, (R - closest) / dx, lowest,
              largest_force, largest_shift);
  if (first_inside >= 0)
    std::printf("[ measured ] first water particle inside the pipe at t = %.4f s, the pipe %.2e m above the bed then\n",
                first_inside, bed_gap_then);
  EXPECT_TRUE(finite);
  EXPECT_GT(largest_force, 10.0) << "the wave should have struck the pipe";
  EXPECT_GE(closest, R) << "a water particle got inside the pipe";
  EXPECT_GT(lowest, -0.1 * dx);
}

INSTANTIATE_TEST_SUITE_P(Motion, Contacts, ::testing::Values(std::string("free"), std::string("bullet")),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

}  // namespace
