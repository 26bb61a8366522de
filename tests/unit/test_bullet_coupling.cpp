// motion: bullet structures coupled to the fluid (fsi/body_coupling.hpp with fsi/bullet_world.hpp,
// issue #8). Skipped without Bullet, except the refusal. References and tolerances, per test:
//  - Free fall far from the fluid: Bullet takes the two half-kick impulses of the fluid's step, so
//    its symplectic Euler step read on the half steps is the kick-drift-kick leapfrog, exact for a
//    constant force: y = y0 - g t^2 / 2 and v = -g t to double rounding (1e-10 m, 1e-10 m/s over
//    ~750 steps of a few roundings each); x and the orientation do not change; every body particle
//    sits at its analytic place to float rounding (4 ulp), as for a free body.
//  - A free and a bullet box pushed by the same block of water (2D, no gravity) take the same path to
//    1e-6 m over 100 steps: in 2D both integrators take the same steps to rounding.
//  - `turbid check` names the bullet body with its mass properties; a 3D bullet body locking a
//    rotation about an axis that is not principal is refused at its structure's line.
//  - A mesh body (block.ply) gets a convex hull shape and falls exactly (1e-10 m).
//  - A bullet disc with a contact material stays on the tank floor (within 0.1 dx), and at rest the
//    contact force forces.csv reports carries its weight within 1% (statics); without a material it
//    touches nothing and falls through the floor. (Restitution, friction and the hard cases: Contacts.* in
//    test_body_contacts.cpp, for free and bullet bodies alike.)
//  - Without Bullet: 'motion: bullet' is refused where it is written, with the install hint.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>

#include "tests/unit/body_test_support.hpp"
#include "fsi/bullet_world.hpp"
#include "fsi/simulation.hpp"
#include "tools/runner.hpp"
#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;
using test::cpu;
using test::replace;

// A 3D scene (dx = 0.025 m) with scenes/meshes/block.ply as its one structure: `world` holds its
// walls and fluid, `body` the structure's keys after the mesh, `domain` the domain's map.
std::string block_scene(const std::string& world, const std::string& body, const std::string& domain) {
  return std::string(R"(
name: block
dimensions: 3
resolution: {particle_spacing: 0.025}
time: {end: 1.0}
gravity: [0, 0, -9.81]
materials:
  water: {density: 1000, sound_speed: 20}
)") + world + "structures:\n  - {name: block, mesh: {file: " + TURBID_SOURCE_DIR + "/scenes/meshes/block.ply}, " + body +
         "}\ndomain: " + domain + "\n";
}




TEST(BulletCoupling, FreeFallFarFromTheFluidIsExact) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  fsi::Simulation sim(tools::read_scene_string(test::fall_scene("bullet"), "test.yaml"), cpu());
  sim.start();
  ASSERT_NE(sim.bodies(), nullptr);
  ASSERT_TRUE(sim.bodies()->is_bullet(0));
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const Eigen::Vector3d x0 = b.position();
  const auto& s = sim.store();
  const auto& ids = sim.fields();
  const std::vector<double> start = test::positions_by_id_2d(sim);
  const double g = 9.81;
  while (sim.time() < 0.3) sim.step();
  const double t = sim.time();
  const double y = x0.y() - 0.5 * g * t * t;
  std::printf("[ measured ] bullet free fall to t = %.6f s in %llu steps: y - y_exact = %.3e m, v - v_exact = %.3e m/s\n",
              t, static_cast<unsigned long long>(sim.steps()), b.position().y() - y, b.velocity().y() + g * t);
  EXPECT_LE(std::abs(b.position().y() - y), 1e-10);
  EXPECT_LE(std::abs(b.velocity().y() + g * t), 1e-10);
  EXPECT_EQ(b.position().x(), x0.x());
  EXPECT_EQ(b.velocity().x(), 0.0);
  EXPECT_EQ(b.orientation().w(), 1.0);
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


TEST(BulletCoupling, PushedBoxFollowsTheFreeBoxPath) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  fsi::Simulation free_sim(tools::read_scene_string(test::push_scene("free", "mdbc"), "test.yaml"), cpu());
  fsi::Simulation bullet_sim(tools::read_scene_string(test::push_scene("bullet", "mdbc"), "test.yaml"), cpu());
  free_sim.start();
  bullet_sim.start();
  double dx = 0, dq = 0;
  for (int n = 0; n < 100; ++n) {
    free_sim.step();
    bullet_sim.step();
    const fsi::RigidBody& f = free_sim.bodies()->body(0);
    const fsi::RigidBody& b = bullet_sim.bodies()->body(0);
    dx = std::max(dx, (f.position() - b.position()).norm());
    dq = std::max(dq, f.orientation().angularDistance(b.orientation()));
  }
  const fsi::RigidBody& f = free_sim.bodies()->body(0);
  std::printf("[ measured ] pushed box, 100 steps to t = %.4f s: moved %.3e m, turned %.3e rad; bullet - free max "
              "|dx| = %.3e m, max angle %.3e rad\n", free_sim.time(), (f.position() - Eigen::Vector3d(0.35, 0.2, 0)).norm(),
              f.orientation().angularDistance(Eigen::Quaterniond::Identity()), dx, dq);
  EXPECT_GT(f.velocity().x(), 0.0);
  EXPECT_LE(dx, 1e-6);
  EXPECT_LE(dq, 1e-5);
}

TEST(BulletCoupling, CheckPrintsTheBulletBodyAndBadLocksAreLocated) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  const std::string text = tools::describe_scene(tools::read_scene_string(test::fall_scene("bullet"), "t.yaml"));
  EXPECT_NE(text.find("bullet body block: mass 5 kg/m"), std::string::npos) << text;
  const char* k3d = R"(
name: lock
dimensions: 3
resolution: {particle_spacing: 0.05}
time: {end: 1.0}
gravity: [0, 0, -9.81]
materials:
  water: {density: 1000, sound_speed: 20}
fluids:
  - {material: water, box: {min: [0, 0, 0], max: [0.2, 0.2, 0.2]}}
structures:
  - {name: slab, box: {size: [0.4, 0.2, 0.1]}, position: [1, 1, 1], rotation: [0, 0, 30], motion: bullet, density: 500, lock: [ry]}
)";
  try {
    fsi::Simulation sim(tools::read_scene_string(k3d, "lock.yaml"), cpu());
    FAIL() << "no error";
  } catch (const std::exception& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("lock.yaml:12:5: error: structure 'slab'"), std::string::npos) << m;
    EXPECT_NE(m.find("principal axis"), std::string::npos) << m;
  }
}

// A mesh body (scenes/meshes/block.ply, turned 30 degrees) takes a convex hull of its vertices as its
// Bullet shape and its sampled mass properties; far from the fluid it falls exactly (1e-10 m).
TEST(BulletCoupling, MeshBodyFallsExactlyWithItsHull) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  const std::string yaml = block_scene("fluids:\n  - {material: water, box: {min: [0, 0, 0], max: [0.1, 0.1, 0.1]}}\n",
                                      "position: [1, 1, 1], rotation: [0, 0, 30], motion: bullet, density: 600",
                                      "{min: [-0.5, -0.5, -1], max: [1.5, 1.5, 1.5]}");
  fsi::Simulation sim(tools::read_scene_string(yaml, "mesh.yaml"), cpu());
  sim.start();
  ASSERT_TRUE(sim.bodies()->is_bullet(0));
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const Eigen::Vector3d x0 = b.position();
  while (sim.time() < 0.1) sim.step();
  const double t = sim.time(), z = x0.z() - 0.5 * 9.81 * t * t;
  std::printf("[ measured ] bullet mesh body free fall to t = %.4f s: z - z_exact = %.3e m\n", t, b.position().z() - z);
  EXPECT_LE(std::abs(b.position().z() - z), 1e-10);
  EXPECT_EQ(b.position().x(), x0.x());
  EXPECT_LE(b.orientation().angularDistance(Eigen::Quaterniond::Identity()), 1e-14);
}

TEST(BulletCoupling, WithoutBulletTheSceneIsRefusedAtTheMotion) {
  if (fsi::bullet_available()) GTEST_SKIP() << "built with Bullet";
  try {
    tools::read_scene_string(test::fall_scene("bullet"), "t.yaml");
    FAIL() << "no error";
  } catch (const std::exception& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("t.yaml:12:"), std::string::npos) << m;
    EXPECT_NE(m.find("this turbid was built without Bullet; install libbullet-dev and rebuild"), std::string::npos) << m;
  }
}

}  // namespace

// Contacts are switched on per structure, as for free bodies (fsi/bullet_world.hpp): a bullet disc
// dropped on the tank floor with a contact material (restitution and friction only: Bullet's contacts
// are rigid, the Young's modulus is optional) stays above the floor, its surface never more than
// 0.1 dx below it (the contact tests' bound); without a material it falls through the floor (it
// touches nothing), more than its radius below it by t = 0.4 s.
TEST(BulletCoupling, ABulletBodyTouchesTheWallsOnlyWithAContactMaterial) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  const double dx = 0.01, R = 0.05;
  auto lowest = [&](const std::string& contact) {
    const std::string yaml = R"(name: drop
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: 0.4, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {density: 1000, sound_speed: 10}
walls:
  - box: {min: [0, 0], max: [0.6, 0.6]}
  - box: {min: [3.0, 0], max: [3.1, 0.05]}
fluids:
  - {material: water, box: {min: [3.0, 0], max: [3.1, 0.05]}}
domain: {min: [-0.5, -0.5], max: [3.5, 2.0]}
structures:
  - {name: ball, sphere: {radius: 0.05}, position: [0.3, 0.25], motion: bullet, density: 1000)" +
                             contact + "}\n";
    fsi::Simulation sim(tools::read_scene_string(yaml, "test.yaml"), cpu());
    sim.start();
    double low = 1e9;
    while (sim.time() < 0.4) {
      sim.step();
      low = std::min(low, sim.bodies()->body(0).position().y() - R);
    }
    if (contact.empty()) return std::pair{low, 0.0};
    // At rest (bounces below Bullet's 0.2 m/s threshold end without rebound): the mean contact force
    // over 0.8..1 s, which forces.csv reports.
    double sum = 0, n = 0;
    while (sim.time() < 1.0) {
      sim.step();
      low = std::min(low, sim.bodies()->body(0).position().y() - R);
      if (sim.time() < 0.8) continue;
      sum += sim.bodies()->contact_load(0).force.y();
      n += 1;
    }
    return std::pair{low, sum / n};
  };
  const auto [with, support] = lowest(", contact: {restitution: 0.5, friction: 0.3}");
  const double without = lowest("").first;
  const double weight = 1000 * std::numbers::pi * R * R * 9.81;
  std::printf("[ measured ] bullet disc on the floor: lowest surface point %.3e m (%.3f dx) with a contact material, "
              "%.3f m without; contact force at rest %.4f N/m against the weight %.4f N/m (%+.3f%%)\n",
              with, with / dx, without, support, weight, 100 * (support / weight - 1));
  EXPECT_GT(with, -0.1 * dx);
  EXPECT_LT(without, -R);
  EXPECT_NEAR(support, weight, 0.01 * weight);
}

// A 3D mesh body (block.ply's convex hull: GJK against the floor's slab, whose manifold gathers its
// points over a few steps) dropped from 0.275 m onto a tank floor with restitution 0.3 rests flat:
// over 0.5..0.6 s its lowest point is within 0.1 dx of the floor (the hull's margin is 1e-4 of its
// size, docs/choices.md), it is tilted by less than 0.01 rad and moves by less than 0.01 dx, and the
// mean contact force carries its weight within 1% (statics).
TEST(BulletCoupling, MeshBodyComesToRestFlatOnTheFloor) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  const double dx = 0.025, weight = 0.2 * 0.1 * 0.05 * 600 * 9.81;
  const std::string yaml = block_scene(R"(walls:
  - box: {min: [0, 0, 0], max: [0.5, 0.4, 0.4]}
  - box: {min: [1, 0, 0], max: [1.1, 0.1, 0.1]}
fluids:
  - {material: water, box: {min: [1, 0, 0], max: [1.1, 0.1, 0.1]}}
)",
                                      "position: [0.25, 0.2, 0.3], motion: bullet, density: 600, "
                                      "contact: {restitution: 0.3, friction: 0.5}",
                                      "{min: [-0.2, -0.2, -0.2], max: [1.3, 0.6, 0.6]}");
  fsi::Simulation sim(tools::read_scene_string(yaml, "mesh_rest.yaml"), cpu());
  sim.start();
  const fsi::RigidBody& b = sim.bodies()->body(0);
  const auto& st = sim.store();
  const auto& ids = sim.fields();
  while (sim.time() < 0.5) sim.step();
  const Eigen::Vector3d x_then = b.position();
  double lowest = 1e9, highest = -1e9, support = 0, n = 0;
  while (sim.time() < 0.6) {
    sim.step();
    support += sim.bodies()->contact_load(0).force.z();
    n += 1;
    const auto* x = st.data<float>(ids.position);
    const auto* kind = st.data<std::uint8_t>(ids.kind);
    double low = 1e9;
    for (std::size_t i = 0; i < st.size(); ++i)
      if (kind[i] == 2) low = std::min(low, double(x[3 * i + 2]) - 0.5 * dx);  // surface particles lie dx/2 inside
    lowest = std::min(lowest, low);
    highest = std::max(highest, low);
  }
  support /= n;
  // Flat: the block's own z axis along the world's (a turn about z on landing is allowed).
  const Eigen::Vector3d up = b.orientation() * Eigen::Vector3d::UnitZ();
  const double turned = std::acos(std::min(1.0, up.z()));
  const double moved = (b.position() - x_then).norm();
  std::printf("[ measured ] bullet mesh block at rest: lowest surface %.3e..%.3e m from the floor, tilted %.2e rad, moved "
              "%.2e m in 0.1 s, contact force %.4f N against the weight %.4f N (%+.2f%%)\n",
              lowest, highest, turned, moved, support, weight, 100 * (support / weight - 1));
  EXPECT_NEAR(lowest, 0.0, 0.1 * dx);
  EXPECT_NEAR(highest, 0.0, 0.1 * dx);
  EXPECT_LT(turned, 0.01);
  EXPECT_LT(moved, 0.01 * dx);
  EXPECT_NEAR(support, weight, 0.01 * weight);
}
