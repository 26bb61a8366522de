// Moving structures on the CUDA backend (sph/backend/cuda: place_bodies runs the shared placement
// pass, sph/body_motion.hpp, on the device; the bodies themselves are integrated on the host by the
// same fsi code for both backends). Runs on each device backend here (tests/device_backends.hpp:
// "cuda" with a GPU, "device-omp" where compiled); skipped with neither. References and tolerances:
//  - a free box pushed by a block of water (test::push_scene, 2D, no gravity) takes the CPU's path
//    over 100 steps within 1e-3 of its displacement: the fluid forces differ only by float32
//    association and fused multiply-adds (1e-5 of the largest acceleration, CudaParity), which the
//    body integrates over 100 steps;
//  - a prescribed oscillating cylinder (scenes/oscillating_cylinder_2d.yaml) has every structure
//    particle at the CPU's place within 1e-6 m after 50 steps (the placement is the same double
//    arithmetic rounded once to float on both);
//  - a bullet box in the same push takes the free box's path on the GPU as on the CPU (1e-3 of its
//    displacement).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "tests/unit/body_test_support.hpp"
#include "fsi/bullet_world.hpp"
#include "fsi/simulation.hpp"
#include "sph/backend.hpp"
#include "tests/device_backends.hpp"
#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;

fsi::RunOptions on(const std::string& backend) {
  fsi::RunOptions r = test::cpu();
  r.backend = backend;
  return r;
}

// The box's centre after `steps` steps of the push scene with this motion, on this backend.
Eigen::Vector3d pushed(const std::string& motion, const std::string& backend, int steps, double* moved) {
  fsi::Simulation sim(test::scene_of(test::push_scene(motion, "dbc")), on(backend));
  EXPECT_EQ(sim.backend_name(), backend);
  sim.start();
  const Eigen::Vector3d x0 = sim.bodies()->body(0).position();
  for (int s = 0; s < steps; ++s) sim.step();
  const Eigen::Vector3d x = sim.bodies()->body(0).position();
  if (moved) *moved = (x - x0).norm();
  return x;
}

// The pushed box's path on the GPU against the CPU's, bound 1e-3 of its displacement.
void expect_push_parity(const std::string& motion, const std::string& device) {
  double moved = 0;
  const Eigen::Vector3d cpu = pushed(motion, "cpu", 100, &moved);
  const Eigen::Vector3d gpu = pushed(motion, device, 100, nullptr);
  std::printf("[ measured ] pushed %s box, 100 steps: moved %.4e m; %s - cpu %.3e m\n", motion.c_str(), moved,
              device.c_str(), (gpu - cpu).norm());
  ASSERT_GT(moved, 1e-3);
  EXPECT_LE((gpu - cpu).norm(), 1e-3 * moved);
}

void expect_prescribed_parity(const std::string& device);

TEST(CudaBodies, PushedFreeBoxFollowsTheCpuPath) {
  turbid::testing::for_each_device_backend([](const std::string& device) { expect_push_parity("free", device); });
}

TEST(CudaBodies, PushedBulletBoxFollowsTheCpuPath) {
  if (!fsi::bullet_available()) GTEST_SKIP() << "built without Bullet";
  turbid::testing::for_each_device_backend([](const std::string& device) { expect_push_parity("bullet", device); });
}

TEST(CudaBodies, PrescribedCylinderParticlesSitWhereTheCpuPutsThem) {
  turbid::testing::for_each_device_backend([](const std::string& device) { expect_prescribed_parity(device); });
}

void expect_prescribed_parity(const std::string& device) {
  const std::string path = std::string(TURBID_SOURCE_DIR) + "/scenes/oscillating_cylinder_2d.yaml";
  auto run = [&](const std::string& backend) {
    fsi::Simulation sim(tools::read_scene_file(path), on(backend));
    EXPECT_EQ(sim.backend_name(), backend);
    sim.start();
    for (int s = 0; s < 50; ++s) sim.step();
    sim.sync_to_host();
    return test::positions_by_id_2d(sim);
  };
  const std::vector<double> cpu = run("cpu"), gpu = run(device);
  ASSERT_EQ(cpu.size(), gpu.size());
  fsi::Simulation probe(tools::read_scene_file(path), on("cpu"));
  const auto& s = probe.store();
  const auto* kind = s.data<std::uint8_t>(probe.fields().kind);
  const auto* id = s.data<std::uint32_t>(probe.fields().id);
  double worst = 0;
  std::size_t checked = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != 2) continue;  // structure particles
    for (int a = 0; a < 2; ++a) worst = std::max(worst, std::abs(gpu[2 * id[i] + a] - cpu[2 * id[i] + a]));
    ++checked;
  }
  std::printf("[ measured ] prescribed cylinder, 50 steps: %zu structure particles, %s - cpu <= %.3e m\n", checked,
              device.c_str(), worst);
  ASSERT_GT(checked, 0u);
  EXPECT_LE(worst, 1e-6);
}

}  // namespace
