// The device backend's own machinery (sph/backend/device/), on each device backend here
// (tests/device_backends.hpp: "cuda" with a GPU, "device-omp" where compiled; CI runs the latter):
//  - open-boundary conversions on the device write the bytes the host rule writes
//    (sph::update_open_boundaries, the reference: same particles, same order, same new ids);
//  - structure loads summed on the device equal the host's double sums (sph::sum_body_loads) to
//    1e-12 relative (the same double arithmetic in another order);
//  - what a step copies between host and device does not grow with the particle count (issue #22:
//    O(bodies + zones) bytes, not O(N)), measured with Backend::host_device_bytes at two spacings
//    of a scene with open boundaries and of one with a free body;
//  - steady steps allocate no temporary storage (the caching allocator);
//  - a step of a water scene waits for the device once (issue #22: dt, health and the particle
//    count from one reduction), counted with Backend::host_waits, and particles that leave the
//    domain are still removed at the step they leave, as on the CPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "sph/backend.hpp"
#include "sph/body_loads.hpp"
#include "sph/fields.hpp"
#include "sph/open_boundary.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"
#include "tests/device_backends.hpp"
#include "tests/unit/body_test_support.hpp"
#include "tools/scene_reader.hpp"

namespace {

using namespace turbid;
using namespace turbid::sph;

constexpr double kDx = 0.01;  // [m]

// A 2D channel along x: an inlet zone (0) on [-0.04, 0], fluid on [0, 0.5], an outlet zone (1) on
// [0.5, 0.54], 0.2 m high; the outlet's cross-section stops at y = 0.15. Particles are jittered
// across the planes so that each crossing happens: inlet buffer past x = 0 (inflow), outlet
// buffer past 0.54 (outflow), fluid past 0.5 below y = 0.15 (to the outlet) and above it (stays fluid).
PhysicsParams channel_params() {
  PhysicsParams p;
  p.dimensions = 2;
  p.smoothing_length = Real(2 * kDx);
  p.max_smoothing_length = p.smoothing_length;
  p.material_count = 2;
  for (int m = 0; m < 2; ++m) {
    p.materials[m].eos = TaitEos::make(1000.0, 10.0, 7.0, 0.0);
    p.materials[m].sound_speed = Real(10);
  }
  p.zone_count = 2;
  BufferZone& in = p.zones[0];
  in.type = ZoneType::inlet;
  in.axis = 0;
  in.sign = 1;
  in.plane = 0;
  in.thickness = Real(0.04);
  in.velocity = Real(0.1);
  in.lo[0] = Real(-0.04), in.hi[0] = 0, in.lo[1] = 0, in.hi[1] = Real(0.2);
  in.material = 1;  // what it makes is recognisable
  BufferZone& out = p.zones[1];
  out.type = ZoneType::outlet;
  out.axis = 0;
  out.sign = 1;
  out.plane = Real(0.5);
  out.thickness = Real(0.04);
  out.lo[0] = Real(0.5), out.hi[0] = Real(0.54), out.lo[1] = 0, out.hi[1] = Real(0.15);
  return p;
}

// `room`: reserve half as many again (else the store is exactly full).
FieldIds build_channel(ParticleStore& s, const PhysicsParams& p, Domain& domain, bool room = true) {
  const FieldIds ids = register_fields(s, p);
  struct Particle {
    Vec<2> x;
    std::uint8_t kind, zone;
  };
  std::vector<Particle> parts;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3 * kDx, 0.3 * kDx);
  for (int j = 0; j < 20; ++j)
    for (int i = -4; i < 54; ++i) {
      Particle q{};
      q.x[0] = Real((i + 0.5) * kDx + jitter(rng));
      q.x[1] = Real((j + 0.5) * kDx + jitter(rng));
      if (i < 0) q.kind = std::uint8_t(Kind::buffer), q.zone = 0;
      else if (i >= 50) q.kind = std::uint8_t(Kind::buffer), q.zone = 1;
      else q.kind = std::uint8_t(Kind::fluid), q.zone = kNoZone;
      // Crossings: the inlet's last column moved past its plane, the outlet's last past its far face.
      if (i == -1 && j % 2 == 0) q.x[0] = Real(0.002);
      if (i == 53 && j % 3 == 0) q.x[0] = Real(0.545);
      // Fluid past the outlet's plane: inside its cross-section (y < 0.15) for j = 0, 4, 8, 12; not for 16.
      if (i == 49 && j % 4 == 0) q.x[0] = Real(0.502);
      parts.push_back(q);
    }
  std::shuffle(parts.begin(), parts.end(), rng);
  if (room) s.reserve(parts.size() + parts.size() / 2);
  s.resize(parts.size());
  for (std::size_t n = 0; n < parts.size(); ++n) {
    s.data<Vec<2>>(ids.position)[n] = parts[n].x;
    s.data<Vec<2>>(ids.velocity)[n] = Vec<2>{Real(0.1), Real(0.01 * double(n % 7))};
    s.data<Real>(ids.density)[n] = Real(1000 + double(n % 11));
    s.data<Real>(ids.mass)[n] = Real(1000 * kDx * kDx);
    s.data<Real>(ids.smoothing_length)[n] = p.smoothing_length;
    s.data<std::uint8_t>(ids.kind)[n] = parts[n].kind;
    s.data<std::uint8_t>(ids.zone)[n] = parts[n].zone;
    s.data<std::uint32_t>(ids.id)[n] = std::uint32_t(3 * n + 1);  // not dense: new ids follow the largest
  }
  domain.min[0] = -0.1, domain.max[0] = 0.7;
  domain.min[1] = -0.1, domain.max[1] = 0.3;
  return ids;
}

TEST(DeviceBackend, OpenBoundaryUpdateWritesTheBytesOfTheHostRule) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    const PhysicsParams p = channel_params();
    ParticleStore host, dev;
    Domain domain;
    const FieldIds ids = build_channel(host, p, domain);
    build_channel(dev, p, domain);
    auto gpu = turbid::testing::make_device_backend(device);
    gpu->bind(dev, ids, p, domain);
    const OpenBoundaryCounts want = update_open_boundaries(host, ids, p);
    const OpenBoundaryCounts got = gpu->update_open_boundaries();
    std::printf("[ measured ] %s: inflow %zu, outflow %zu, to outlet %zu; %d -> %zu particles\n", device.c_str(),
                got.inflow, got.outflow, got.to_outlet, 20 * 58, dev.size());
    // The block is built so that every kind of crossing happens.
    EXPECT_EQ(want.inflow, 10u);
    EXPECT_EQ(want.outflow, 7u);
    EXPECT_EQ(want.to_outlet, 4u);
    EXPECT_EQ(got.inflow, want.inflow);
    EXPECT_EQ(got.outflow, want.outflow);
    EXPECT_EQ(got.to_outlet, want.to_outlet);
    EXPECT_EQ(dev.size(), host.size()) << "the host count follows the device";
    gpu->sync_to_host();
    ASSERT_EQ(dev.size(), host.size());
    for (int f = 0; f < host.field_count(); ++f)
      EXPECT_EQ(std::memcmp(host.raw(f), dev.raw(f), host.size() * host.field_bytes(f)), 0)
          << "field " << host.desc(f).name << " differs from the host rule's";
  });
}

TEST(DeviceBackend, OpenBoundaryUpdateGrowsTheDeviceBuffersWhenFull) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    const PhysicsParams p = channel_params();
    ParticleStore host, dev;
    Domain domain;
    const FieldIds ids = build_channel(host, p, domain);
    build_channel(dev, p, domain, false);  // no room: the 10 new buffer particles need the buffers to grow
    ASSERT_EQ(dev.capacity(), dev.size());
    auto gpu = turbid::testing::make_device_backend(device);
    gpu->bind(dev, ids, p, domain);
    const OpenBoundaryCounts want = update_open_boundaries(host, ids, p);
    const OpenBoundaryCounts got = gpu->update_open_boundaries();
    EXPECT_EQ(got.inflow, want.inflow);
    gpu->sync_to_host();
    ASSERT_EQ(dev.size(), host.size());
    for (int f = 0; f < host.field_count(); ++f)
      EXPECT_EQ(std::memcmp(host.raw(f), dev.raw(f), host.size() * host.field_bytes(f)), 0) << host.desc(f).name;
    // And the grown buffers run a neighbour update.
    EXPECT_EQ(gpu->update_neighbours(), 0u);
  });
}

// Structure particles of three bodies (and fluid) with forces; loads about three points.
TEST(DeviceBackend, StructureLoadsEqualTheHostSums) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    PhysicsParams p;
    p.dimensions = 3;
    p.smoothing_length = Real(2 * kDx);
    p.max_smoothing_length = p.smoothing_length;
    p.material_count = 1;
    p.materials[0].eos = TaitEos::make(1000.0, 10.0, 7.0, 0.0);
    p.body_count = 3;
    ParticleStore s;
    const FieldIds ids = register_fields(s, p, true, true);
    const std::size_t n = 5000;
    s.resize(n);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
      s.data<Vec<3>>(ids.position)[i] = Vec<3>{Real(u(rng)), Real(u(rng)), Real(u(rng))};
      s.data<Vec<3>>(ids.structure_force)[i] = Vec<3>{Real(u(rng) - 0.5), Real(u(rng) - 0.5), Real(u(rng) - 0.2)};
      const bool structure = i % 4 != 0;
      s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(structure ? Kind::structure : Kind::fluid);
      s.data<std::uint8_t>(ids.body)[i] = structure ? std::uint8_t(i % 3) : kNoBody;
      s.data<Real>(ids.density)[i] = Real(1000);
      s.data<Real>(ids.mass)[i] = Real(1);
      s.data<Real>(ids.smoothing_length)[i] = p.smoothing_length;
      s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
    }
    Domain domain;
    for (int a = 0; a < 3; ++a) domain.min[a] = -0.1, domain.max[a] = 1.1;
    const std::vector<std::array<double, 3>> ref = {{0.5, 0.5, 0.5}, {0, 0, 0}, {0.2, 0.9, 0.1}};
    const std::vector<BodyLoad> want =
        sum_body_loads<3>(s.data<Vec<3>>(ids.position), s.data<Vec<3>>(ids.structure_force), s.data<std::uint8_t>(ids.body), n, ref);
    auto gpu = turbid::testing::make_device_backend(device);
    gpu->bind(s, ids, p, domain);
    const std::uint64_t before = gpu->host_device_bytes();
    const std::vector<BodyLoad> got = gpu->body_loads(ref);
    const std::uint64_t moved = gpu->host_device_bytes() - before;
    std::printf("[ measured ] %s: structure loads of 3 bodies over %zu particles moved %llu bytes\n", device.c_str(), n,
                (unsigned long long)moved);
    EXPECT_LE(moved, 3 * 48u + 8u) << "the loads only, not the particles";
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t b = 0; b < want.size(); ++b) {
      double scale = 0;
      for (int a = 0; a < 3; ++a) scale = std::max({scale, std::abs(want[b].force[a]), std::abs(want[b].torque[a])});
      ASSERT_GT(scale, 1.0);
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(got[b].force[a], want[b].force[a], 1e-12 * scale) << "body " << b << " force " << a;
        EXPECT_NEAR(got[b].torque[a], want[b].torque[a], 1e-12 * scale) << "body " << b << " torque " << a;
      }
    }
  });
}

fsi::RunOptions on(const std::string& backend) {
  fsi::RunOptions r = test::cpu();
  r.backend = backend;
  return r;
}

struct Traffic {
  std::size_t particles = 0;
  double bytes_per_step = 0;
  double waits_per_step = 0;  // times the host waited for the device (Backend::host_waits)
  std::size_t allocations_after_warmup = 0, allocations_at_end = 0;
};

// Steps 5 (warm-up) then `steps` more, and measures what moved per step in the latter; then
// `steps` more, over which the temporary blocks are counted (every kind of operation, the first
// inflow's scan and outflow's compaction among them, has run by then).
Traffic traffic(fsi::Scene scene, const std::string& device, int steps) {
  scene.output.vtk = false;
  fsi::Simulation sim(scene, on(device));
  EXPECT_EQ(sim.backend_name(), device);
  sim.start();
  for (int k = 0; k < 5; ++k) sim.step();
  Traffic t;
  t.particles = sim.store().size();
  const std::uint64_t before = sim.backend().host_device_bytes(), waits = sim.backend().host_waits();
  for (int k = 0; k < steps; ++k) sim.step();
  t.bytes_per_step = double(sim.backend().host_device_bytes() - before) / steps;
  t.waits_per_step = double(sim.backend().host_waits() - waits) / steps;
  t.allocations_after_warmup = sim.backend().temporary_allocations();
  for (int k = 0; k < steps; ++k) sim.step();
  t.allocations_at_end = sim.backend().temporary_allocations();
  return t;
}

// max_waits: the waits a step of the scene may have whatever N is (counted from the calls it makes).
void expect_traffic_independent_of_n(const std::string& what, fsi::Scene coarse, fsi::Scene fine, const std::string& device,
                                     double max_waits) {
  const Traffic a = traffic(coarse, device, 20), b = traffic(fine, device, 20);
  std::printf("[ measured ] %s on %s: %zu particles %.1f bytes/step (%.2f waits), %zu particles %.1f bytes/step "
              "(%.2f waits); temporary blocks %zu -> %zu and %zu -> %zu over the 20 steps after\n",
              what.c_str(), device.c_str(), a.particles, a.bytes_per_step, a.waits_per_step, b.particles,
              b.bytes_per_step, b.waits_per_step, a.allocations_after_warmup, a.allocations_at_end,
              b.allocations_after_warmup, b.allocations_at_end);
  ASSERT_GT(b.particles, 3 * a.particles);
  // O(bodies + zones): a few small reductions and the bodies' states, whatever N is.
  EXPECT_LE(b.bytes_per_step, 1024.0);
  EXPECT_LE(b.bytes_per_step, a.bytes_per_step + 64.0) << "grows with the particle count";
  EXPECT_LE(a.waits_per_step, max_waits);
  EXPECT_LE(b.waits_per_step, max_waits);
  // Steady steps reuse the cached blocks, also while inflow adds particles.
  EXPECT_EQ(a.allocations_at_end, a.allocations_after_warmup);
  EXPECT_EQ(b.allocations_at_end, b.allocations_after_warmup);
}

TEST(DeviceBackend, HostTrafficPerStepDoesNotGrowWithParticlesWithOpenBoundaries) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    const std::string path = std::string(TURBID_SOURCE_DIR) + "/scenes/cylinder_2d_re20.yaml";
    fsi::Scene coarse = tools::read_scene_file(path), fine = coarse;
    coarse.particle_spacing = 0.02;
    fine.particle_spacing = 0.01;
    // The step's check, the zone tally, and the compaction's count on steps where particles leave.
    expect_traffic_independent_of_n("channel with inlet and outlet", coarse, fine, device, 3.0);
  });
}

TEST(DeviceBackend, HostTrafficPerStepDoesNotGrowWithParticlesWithAFreeBody) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    fsi::Scene coarse = test::scene_of(test::push_scene("free", "dbc")), fine = coarse;
    fine.particle_spacing = coarse.particle_spacing / 2;
    // The step's check; two uploads of the placements; the loads: the count left by the sort, the
    // structure list's count, one reduction for the body.
    expect_traffic_independent_of_n("pushed free box", coarse, fine, device, 7.0);
  });
}

// What the backend holds against sph::device_memory_per_particle, which `turbid check` prints: the
// 3D dam break of the throughput benchmark, coarse (fields, sort). Bound 15%: Thrust's own small
// blocks and the cell arrays are outside the plan.
TEST(DeviceBackend, DeviceMemoryPerParticleIsWhatTurbidCheckSays) {
  turbid::testing::for_each_device_backend([](const std::string& device) {
    fsi::Scene scene = tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/dam_break_obstacle_3d.yaml");
    scene.output.vtk = false;
    scene.particle_spacing = 0.03;
    fsi::Simulation sim(scene, on(device));
    sim.start();
    for (int k = 0; k < 3; ++k) sim.step();
    const double capacity = double(std::max(sim.store().capacity(), sim.store().size()));
    const double held = double(sim.backend().device_bytes()) / capacity;
    const sph::DeviceMemory& plan = sim.summary().device_memory;
    std::printf("[ measured ] %s, 3D dam break, %zu particles: %.1f bytes/particle held, %zu planned (fields %zu, sort %zu)\n",
                device.c_str(), sim.store().size(), held, plan.total(), plan.fields, plan.sort);
    EXPECT_NEAR(held, double(plan.total()), 0.15 * double(plan.total()));
  });
}

// A step of a scene with walls and water and nothing else (the 2D dam break) waits for the device
// once: the step's check (dt's speeds, the health check and the count of particles still in the
// domain after the sort, in one reduction). Counted over 20 steps after 5 of warm-up. The CPU
// backend, where host and device are one, waits never.
TEST(DeviceBackend, AStepOfWaterWaitsForTheDeviceOnce) {
  // Waits per step over 20 steps after 5 of warm-up.
  auto waits_per_step = [](const fsi::RunOptions& options, std::size_t* particles) {
    fsi::Scene scene = tools::read_scene_file(std::string(TURBID_SOURCE_DIR) + "/scenes/dam_break_2d.yaml");
    scene.output.vtk = false;
    scene.particle_spacing = 0.005;
    fsi::Simulation sim(scene, options);
    sim.start();
    for (int k = 0; k < 5; ++k) sim.step();
    const std::uint64_t before = sim.backend().host_waits();
    constexpr int kSteps = 20;
    for (int k = 0; k < kSteps; ++k) sim.step();
    *particles = sim.store().size();
    return double(sim.backend().host_waits() - before) / kSteps;
  };
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    std::size_t particles = 0;
    const double per_step = waits_per_step(on(device), &particles);
    std::printf("[ measured ] %s, dam break 2D, %zu particles: %.2f waits for the device per step\n", device.c_str(),
                particles, per_step);
    EXPECT_EQ(per_step, 1.0);
  });
  std::size_t particles = 0;
  EXPECT_EQ(waits_per_step(test::cpu(), &particles), 0.0);
}

// The count of particles in the domain waits for the step's check on the device backend; the
// particles that left are still gone from that step on, as on the CPU: a block of water falls
// freely out through the floor of a domain without walls (gravity 100 m/s^2). Reference: the CPU
// backend, which removes them at the sort; the particle count and the removed count agree at every
// step, and the last particle has gone at the same step.
TEST(DeviceBackend, ParticlesLeavingTheDomainGoAtTheStepTheyLeaveAsOnTheCpu) {
  const std::string yaml = R"(
name: falling_out
dimensions: 2
resolution: {particle_spacing: 0.005, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, -100]
numerics:
  kernel: wendland_c2
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: artificial, alpha: 0.02}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
domain: {min: [0, 0], max: [0.2, 0.2]}
fluids:
  - {material: water, box: {min: [0.05, 0.0], max: [0.15, 0.05]}}
output: {every: 1.0, vtk: false}
)";
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    const fsi::Scene scene = tools::read_scene_string(yaml, "falling_out.yaml");
    fsi::Simulation cpu(scene, test::cpu()), gpu(scene, on(device));
    cpu.start();
    gpu.start();
    const std::size_t n0 = cpu.store().size();
    ASSERT_EQ(gpu.store().size(), n0);
    ASSERT_GT(n0, 100u);
    int steps_with_removals = 0, last_step = -1;
    for (int k = 0; k < 2000 && cpu.store().size() > 0; ++k) {
      const std::size_t before = cpu.store().size();
      cpu.step();
      gpu.step();
      ASSERT_EQ(gpu.store().size(), cpu.store().size()) << device << ", step " << k;
      ASSERT_EQ(gpu.removed(), cpu.removed()) << device << ", step " << k;
      ASSERT_EQ(cpu.removed(), n0 - cpu.store().size()) << "step " << k;
      if (cpu.store().size() < before) ++steps_with_removals;
      last_step = k;
    }
    std::printf("[ measured ] %s: %zu particles left the domain over %d steps (removals at %d of them)\n",
                device.c_str(), n0, last_step + 1, steps_with_removals);
    EXPECT_EQ(cpu.store().size(), 0u) << "the block fell out of the domain";
    EXPECT_GT(steps_with_removals, 5) << "particles left over several steps, not all at once";
  });
}

}  // namespace
