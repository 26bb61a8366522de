// What moving structures cost (issue #8, docs/performance.md):
//
//  - BodiesInTank2D/N/B/C: a 2D tank with 100 small boxes in the water, N of them moving (B = 0: the
//    built-in integrator, motion: free; B = 1: motion: bullet) and the rest fixed. Every case has
//    the same particles, so the step time against N = 0 is the cost of coupling N bodies: placing
//    their particles twice per step, summing the fluid load on each and integrating it.
//    BodiesInTank2D/100/B/1: the same 100 moving boxes with contact materials (DEM substeps and
//    contact search, or Bullet's collision detection against the walls and each other).
//  - FixedStructure3D: the 3D dam break with its obstacle as a fixed *structure* (not a wall), so
//    the structure code paths (body id, force sums) run. Built at the commit before issue #8 and at
//    the current one, its median step time gives the "fixed structures pay nothing" ratio.
//
//   build/bin/turbid_bench --benchmark_filter='BodiesInTank2D|FixedStructure3D' --benchmark_repetitions=5
//
// Only the Scene API that existed before issue #8 is used by FixedStructure3D, so this file's
// second half builds at that commit too.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>

#include "fsi/bullet_world.hpp"
#include "fsi/simulation.hpp"

namespace {

using namespace turbid::fsi;

turbid::fsi::RunOptions bench_options() {
  RunOptions opts;
  const char* backend = std::getenv("TURBID_BENCH_BACKEND");
  opts.backend = backend ? backend : "cpu";
  return opts;
}

// 1.2 m x 1.0 m tank, water 0.95 m deep at dx = 0.01 m, 10 x 10 boxes of 0.03 m at 0.09 m pitch,
// density 1000 kg/m^3 (neutral: they drift slowly, so the fluid stays the same as N varies).
Scene bodies_in_tank_2d(int free_count, bool bullet, bool contacts = false) {
  Scene s;
  s.name = "bodies_in_tank_2d";
  s.dimensions = 2;
  s.particle_spacing = 0.01;
  s.smoothing_ratio = 2.0;
  s.end_time = 10.0;
  s.gravity = {0, -9.81, 0};
  s.numerics.boundary = BoundaryKind::mdbc;
  MaterialSpec water;
  water.name = "water";
  water.density = 1000;
  water.sound_speed = 40;
  s.materials.push_back(water);
  WallSpec tank;
  tank.kind = WallSpec::Kind::container;
  tank.box = {{0, 0, 0}, {1.2, 1.0, 0}};
  tank.open[3] = true;  // +y
  s.walls.push_back(tank);
  FluidBlock pool;
  pool.material = "water";
  pool.box = {{0, 0, 0}, {1.2, 0.95, 0}};
  s.fluids.push_back(pool);
  for (int k = 0; k < 100; ++k) {
    StructureSpec st;
    st.name = "box" + std::to_string(k);
    st.shape = StructureSpec::Shape::box;
    st.size = {0.03, 0.03, 0};
    st.position = {0.195 + 0.09 * (k % 10), 0.055 + 0.09 * (k / 10), 0};
    if (k < free_count) {
      st.motion = bullet ? StructureSpec::Motion::bullet : StructureSpec::Motion::free;
      st.density = 1000;
      if (contacts) {
        st.contact.given = true;
        st.contact.youngs_modulus = 1e8;  // the DEM's; Bullet's contacts are rigid
        st.contact.restitution = 0.5;
        st.contact.friction = 0.3;
      }
    }
    s.structures.push_back(st);
  }
  s.output.vtk = false;
  return s;
}

void BodiesInTank2D(benchmark::State& state) {
  const bool bullet = state.range(1) != 0;
  if (bullet && !turbid::fsi::bullet_available()) {
    state.SkipWithError("built without Bullet");
    return;
  }
  Simulation sim(bodies_in_tank_2d(int(state.range(0)), bullet, state.range(2) != 0), bench_options());
  sim.start();
  for (int i = 0; i < 5; ++i) sim.step();
  for (auto _ : state) sim.step();
  state.counters["particles"] = double(sim.store().size());
  state.counters["free_bodies"] = double(state.range(0));
  state.SetLabel(sim.backend_name() + ", " + std::to_string(sim.threads()) + " threads");
}

// The 3D dam break of throughput.cpp at dx = 0.012 m with the obstacle as a fixed structure.
Scene fixed_structure_3d() {
  Scene s;
  s.name = "fixed_structure_3d";
  s.dimensions = 3;
  s.particle_spacing = 0.012;
  s.smoothing_ratio = 1.7320508075688772;
  s.end_time = 1.0;
  s.gravity = {0, 0, -9.81};
  s.numerics.kernel = turbid::sph::KernelKind::cubic_spline;
  s.numerics.artificial_viscosity = 0.1;
  MaterialSpec water;
  water.name = "water";
  water.density = 1000;
  water.sound_speed = 33.7;
  s.materials.push_back(water);
  WallSpec tank;
  tank.kind = WallSpec::Kind::container;
  tank.box = {{0, 0, 0}, {1.6, 0.67, 0.4}};
  tank.open[5] = true;
  tank.layers = 1;
  s.walls.push_back(tank);
  StructureSpec obstacle;
  obstacle.name = "obstacle";
  obstacle.shape = StructureSpec::Shape::box;
  obstacle.size = {0.12, 0.12, 0.45};
  obstacle.position = {0.96, 0.30, 0.225};
  obstacle.layers = 1;
  s.structures.push_back(obstacle);
  FluidBlock column;
  column.material = "water";
  column.box = {{0, 0, 0}, {0.4, 0.67, 0.3}};
  s.fluids.push_back(column);
  s.output.vtk = false;
  return s;
}

void FixedStructure3D(benchmark::State& state) {
  Simulation sim(fixed_structure_3d(), bench_options());
  sim.start();
  for (int i = 0; i < 5; ++i) sim.step();
  std::size_t particle_steps = 0;
  for (auto _ : state) {
    particle_steps += sim.store().size();
    sim.step();
  }
  state.counters["particles"] = double(sim.store().size());
  state.counters["particle_steps_per_s"] = benchmark::Counter(double(particle_steps), benchmark::Counter::kIsRate);
  state.SetLabel(sim.backend_name() + ", " + std::to_string(sim.threads()) + " threads");
}

}  // namespace

BENCHMARK(BodiesInTank2D)
    ->Args({0, 0, 0})->Args({1, 0, 0})->Args({10, 0, 0})->Args({100, 0, 0})
    ->Args({1, 1, 0})->Args({10, 1, 0})->Args({100, 1, 0})
    ->Args({100, 0, 1})->Args({100, 1, 1})
    ->Unit(benchmark::kMillisecond)->Iterations(200)->UseRealTime();
BENCHMARK(FixedStructure3D)->Unit(benchmark::kMillisecond)->Iterations(20)->UseRealTime();
