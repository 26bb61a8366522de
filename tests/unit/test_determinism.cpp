// Thread-count determinism: the CPU backend's passes each write only their own particle's fields
// and read fields no thread of the same pass writes, the sort is stable and the reductions are
// exact (max, min) or in a fixed order, so a run must give the same bits on 1 and on 2 threads.
// Reference: that property itself (no tolerance). Before issue #20 the mDBC and buffer passes read
// neighbouring boundary particles' densities while writing their own (a data race, undefined
// behaviour under OpenMP); these scenes cover those passes, with several materials, no-slip walls,
// a structure and open boundaries, and are large enough (> 4096 particles) for the passes to run
// in parallel.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "tools/runner.hpp"

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// Runs the scene on 1 and on 2 threads and compares every output file byte for byte: the ParaView
// frames (positions, velocities, densities, pressures, materials of every particle), probes.csv
// and forces.csv. Returns the number of frames compared.
int expect_same_bits_on_1_and_2_threads(const std::string& name, const std::string& scene_text) {
  const fs::path dir = fs::temp_directory_path() / ("turbid_determinism_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scene = dir / "scene.yaml";
  std::ofstream(scene) << scene_text;
  nlohmann::json report[2];
  for (int t = 1; t <= 2; ++t) {
    turbid::tools::RunRequest r;
    r.scene_file = scene;
    r.out = dir / ("threads" + std::to_string(t));
    r.backend = "cpu";
    r.progress = false;
    r.threads = t;
    report[t - 1] = turbid::tools::run_scene(r);
    EXPECT_EQ(report[t - 1].at("status"), "completed") << name << " on " << t << " threads";
  }
  EXPECT_EQ(report[0].at("threads"), 1);
  EXPECT_EQ(report[1].at("threads"), 2);
  EXPECT_EQ(report[0].at("steps"), report[1].at("steps")) << name;
  EXPECT_GE(report[0].at("particles").get<long>(), 4096) << name << ": too small for the passes to run in parallel";
  int frames = 0;
  for (const auto& e : fs::directory_iterator(dir / "threads1")) {
    const auto ext = e.path().extension();
    if (ext != ".vtp" && ext != ".csv") continue;
    const fs::path twin = dir / "threads2" / e.path().filename();
    EXPECT_TRUE(fs::exists(twin)) << twin;
    EXPECT_TRUE(slurp(e.path()) == slurp(twin)) << name << ": " << e.path().filename() << " differs between 1 and 2 threads";
    if (ext == ".vtp") ++frames;
  }
  fs::remove_all(dir);
  return frames;
}

}  // namespace

// mDBC walls with no-slip and laminar viscosity: a water column collapsing in a closed tank.
TEST(Determinism, MdbcDamBreakIsBitIdenticalOnOneAndTwoThreads) {
  const int frames = expect_same_bits_on_1_and_2_threads("mdbc", R"(name: determinism_mdbc
dimensions: 2
resolution: {particle_spacing: 0.004, smoothing_ratio: 2.0}
time: {end: 0.04, cfl: 0.2}
gravity: [0, -9.81]
numerics:
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: laminar}
  boundary: {type: mdbc, velocity: no_slip}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.6, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.25, 0.2]}}
probes:
  - {name: front, type: front_position, material: water, axis: x}
  - {name: p_wall, type: pressure, point: [0.002, 0.01]}
output: {every: 0.01, vtk: true}
)");
  EXPECT_GE(frames, 4);
}

// mDBC walls beside two materials (Bingham debris under water): the walls take the material their
// ghost nodes see, the path of issue #20 item 3.
TEST(Determinism, MdbcTwoMaterialsIsBitIdenticalOnOneAndTwoThreads) {
  const int frames = expect_same_bits_on_1_and_2_threads("mdbc_two_materials", R"(name: determinism_two_materials
dimensions: 2
resolution: {particle_spacing: 0.005, smoothing_ratio: 2.0}
time: {end: 0.03, cfl: 0.2}
gravity: [0, -9.81]
numerics:
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: laminar}
  boundary: {type: mdbc, velocity: no_slip}
  interface_correction: ghost_density
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
  debris: {model: bingham, density: 1950, viscosity: 0.1, yield_stress: 20, papanastasiou_exponent: 100,
           max_viscosity: 1, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.5, 0.3]}
fluids:
  - {material: debris, box: {min: [0, 0], max: [0.15, 0.15]}}
  - {material: water, box: {min: [0.15, 0], max: [0.5, 0.2]}}
probes:
  - {name: p_floor, type: pressure, point: [0.05, 0.005]}
output: {every: 0.01, vtk: true}
)");
  EXPECT_GE(frames, 3);
}

// Implicit viscosity (sph/implicit_viscosity.hpp): a Bingham column with no stated cap (viscosity at
// rest m tau_y + mu_p = 2000 Pa s, integrated implicitly with the full stress, sph/full_stress.hpp) against a fixed
// structure, with no-slip mDBC walls: the conjugate-gradient solve (its inner products are summed in
// fixed blocks), the viscous load on the structure and forces.csv must give the same bits.
TEST(Determinism, ImplicitViscositySolveIsBitIdenticalOnOneAndTwoThreads) {
  const int frames = expect_same_bits_on_1_and_2_threads("implicit_viscosity", R"(name: determinism_implicit
dimensions: 2
resolution: {particle_spacing: 0.004, smoothing_ratio: 2.0}
time: {end: 0.008, cfl: 0.2}
gravity: [0, -9.81]
numerics:
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: laminar, integration: auto, stress: full}
  boundary: {type: mdbc, velocity: no_slip}
materials:
  debris: {model: bingham, density: 1800, viscosity: 0.5, yield_stress: 20, papanastasiou_exponent: 100,
           sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.5, 0.3]}
structures:
  - {name: block, box: {size: [0.04, 0.04]}, position: [0.3, 0.03]}
fluids:
  - {material: debris, box: {min: [0, 0], max: [0.25, 0.2]}}
probes:
  - {name: front, type: front_position, material: debris, axis: x}
output: {every: 0.002, vtk: true, forces_every: 0.001}
)");
  EXPECT_GE(frames, 4);
}

// Open boundaries (a parabolic inlet and an outlet) past a fixed cylinder with no-slip mDBC: the
// buffer pass, the structure force pass and forces.csv.
TEST(Determinism, OpenBoundaryChannelIsBitIdenticalOnOneAndTwoThreads) {
  const int frames = expect_same_bits_on_1_and_2_threads("open_boundaries", R"(name: determinism_channel
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 0.1, cfl: 0.2}
gravity: [0, 0]
numerics:
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: laminar}
  boundary: {type: mdbc, velocity: no_slip}
  shifting: {coefficient: 2.0, free_surface_threshold: 0}
materials:
  fluid: {model: newtonian, density: 1000, viscosity: 1.0, sound_speed: 3.0, background_pressure: 50}
walls:
  - box: {min: [-0.08, 0], max: [2.28, 0.41]}
    open: [-x, +x]
structures:
  - name: cylinder
    cylinder: {radius: 0.05}
    position: [0.2, 0.2]
open_boundaries:
  - {name: inlet, type: inlet, box: {min: [-0.08, 0], max: [0, 0.41]}, direction: +x,
     velocity: {profile: parabolic, mean: 0.2}}
  - {name: outlet, type: outlet, box: {min: [2.2, 0], max: [2.28, 0.41]}, direction: +x}
fluids:
  - material: fluid
    box: {min: [0, 0], max: [2.2, 0.41]}
    initial_velocity: {direction: +x, profile: parabolic, mean: 0.2}
probes:
  - {name: vmax, type: max_speed}
output: {every: 0.025, vtk: true, forces_every: 0.01}
)");
  EXPECT_GE(frames, 4);
}

// An inlet of a material other than the walls' (issue #20 item 3): its buffer particles hold their
// own material's density (1950 kg/m^3) and must be converted with that material's equation of state
// and judged against its rest density. Before, both used material 0's (water): the health check read
// 1950 / 1000 - 1 = 0.95 and stopped the run at the first step (as did the mDBC walls, which read
// the mud's density as water's). What must hold: the run completes and mud enters at the inlet.
TEST(OpenBoundaries, InletOfASecondMaterialUsesItsOwnEquationOfState) {
  const fs::path dir = fs::temp_directory_path() / ("turbid_inlet_material_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "scene.yaml") << R"(name: inlet_second_material
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 0.05, cfl: 0.2}
gravity: [0, 0]
numerics:
  density_diffusion: {type: fourtakas, delta: 0.1}
  viscosity: {type: laminar}
  boundary: {type: mdbc, velocity: no_slip}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 3.0}
  mud: {model: newtonian, density: 1950, viscosity: 0.1, sound_speed: 3.0}
walls:
  - box: {min: [-0.08, 0], max: [1.08, 0.2]}
    open: [-x, +x]
open_boundaries:
  - {name: inlet, type: inlet, box: {min: [-0.08, 0], max: [0, 0.2]}, direction: +x, material: mud,
     velocity: {profile: uniform, mean: 0.2}}
  - {name: outlet, type: outlet, box: {min: [1.0, 0], max: [1.08, 0.2]}, direction: +x}
fluids:
  - material: mud
    box: {min: [0, 0], max: [1.0, 0.2]}
    initial_velocity: {direction: +x, profile: uniform, mean: 0.2}
output: {every: 0.05, vtk: true}
)";
  turbid::tools::RunRequest r;
  r.scene_file = dir / "scene.yaml";
  r.out = dir / "out";
  r.backend = "cpu";
  r.progress = false;
  const nlohmann::json report = turbid::tools::run_scene(r);
  EXPECT_EQ(report.at("status"), "completed") << report.dump();
  EXPECT_GT(report.at("inflow_particles").get<long>(), 0);
  fs::remove_all(dir);
}
