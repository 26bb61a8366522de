// Throughput benchmark: the 3D dam break with an obstacle (scenes/dam_break_obstacle_3d.yaml),
// reported in particle-steps per second counting fluid and wall particles, as the
// DualSPHysics figures in docs/reference/performance-anchors.md do.
//
//   build/bin/turbid_bench --benchmark_filter=DamBreakObstacle3D --benchmark_repetitions=3
//
// Arguments: spacing in micrometres (8500 = 0.0085 m, the reference case). Env TURBID_BENCH_BACKEND
// selects the backend (cpu by default; cuda on a GPU machine).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "fsi/simulation.hpp"

namespace {

turbid::fsi::Scene dam_break_obstacle_3d(double dx) {
  using namespace turbid::fsi;
  Scene s;
  s.name = "dam_break_obstacle_3d";
  s.dimensions = 3;
  s.particle_spacing = dx;
  s.smoothing_ratio = 1.7320508075688772;  // h = sqrt(3) dx
  s.end_time = 1.0;
  s.gravity = {0, 0, -9.81};
  s.numerics.kernel = turbid::sph::KernelKind::cubic_spline;
  s.numerics.diffusion = DiffusionKind::fourtakas;
  s.numerics.diffusion_delta = 0.1;
  s.numerics.viscosity = ViscosityKind::artificial;
  s.numerics.artificial_viscosity = 0.1;
  s.numerics.cfl = 0.2;
  MaterialSpec water;
  water.name = "water";
  water.density = 1000;
  water.sound_speed = 33.7;
  s.materials.push_back(water);
  WallSpec tank;
  tank.kind = WallSpec::Kind::container;
  tank.box = {{0, 0, 0}, {1.6, 0.67, 0.4}};
  tank.open[5] = true;  // +z
  tank.layers = 1;
  s.walls.push_back(tank);
  WallSpec obstacle;
  obstacle.kind = WallSpec::Kind::solid_box;
  obstacle.box = {{0.9, 0.24, 0}, {1.02, 0.36, 0.45}};
  obstacle.layers = 1;
  s.walls.push_back(obstacle);
  FluidBlock column;
  column.material = "water";
  column.box = {{0, 0, 0}, {0.4, 0.67, 0.3}};
  s.fluids.push_back(column);
  return s;
}

void DamBreakObstacle3D(benchmark::State& state) {
  const double dx = double(state.range(0)) * 1e-6;
  turbid::fsi::RunOptions opts;
  const char* backend = std::getenv("TURBID_BENCH_BACKEND");
  opts.backend = backend ? backend : "cpu";
  turbid::fsi::Simulation sim(dam_break_obstacle_3d(dx), opts);
  sim.start();
  for (int i = 0; i < 5; ++i) sim.step();  // warm-up: first steps touch fresh memory
  const double pairs_per_step = double(sim.backend().pair_count());
  std::size_t particle_steps = 0;
  const std::uint64_t fluid_before = sim.fluid_particle_steps();
  for (auto _ : state) {
    particle_steps += sim.store().size();
    sim.step();
  }
  state.counters["particles"] = double(sim.store().size());
  state.counters["particle_steps_per_s"] = benchmark::Counter(double(particle_steps), benchmark::Counter::kIsRate);
  // Fluid only (the tank's walls are about a fifth of this case's particles; issue #24 item 3).
  state.counters["fluid_particle_steps_per_s"] =
      benchmark::Counter(double(sim.fluid_particle_steps() - fluid_before), benchmark::Counter::kIsRate);
  state.counters["pairs_per_s"] =
      benchmark::Counter(pairs_per_step * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["neighbours"] = pairs_per_step / double(sim.store().size());
  state.SetLabel(sim.backend_name() + ", " + std::to_string(sim.threads()) + " threads");
}

// The same case scaled for the GPU (issue #3): 4500, 2800 and 1750 um give about 1.0, 4.0 and 15.9
// million particles. Skipped on the CPU backend.
void DamBreakObstacle3DLarge(benchmark::State& state) {
  const char* backend = std::getenv("TURBID_BENCH_BACKEND");
  if (!backend || std::string(backend) != "cuda") {
    state.SkipWithError("GPU sizes: set TURBID_BENCH_BACKEND=cuda");
    return;
  }
  DamBreakObstacle3D(state);
}

}  // namespace

BENCHMARK(DamBreakObstacle3D)->Arg(8500)->Unit(benchmark::kMillisecond)->Iterations(20)->UseRealTime();
BENCHMARK(DamBreakObstacle3DLarge)->Arg(4500)->Arg(2800)->Arg(1750)->Unit(benchmark::kMillisecond)->Iterations(20)->UseRealTime();

BENCHMARK_MAIN();
