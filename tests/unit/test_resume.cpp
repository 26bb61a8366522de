// Checkpoint/resume: a run resumed from a checkpoint ends bit-identical to one that never stopped
// (reference: the CPU backend is deterministic — gather sums in a fixed neighbour order, stable
// counting sort, fixed-order reductions — so the same state must give the same bits).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "tools/runner.hpp"

namespace fs = std::filesystem;

namespace {

const char* kScene = R"(name: resume_check
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 1.3}
time: {end: 0.06, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.25]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.1, 0.2]}}
probes:
  - {name: front, type: front_position, material: water, axis: x}
  - {name: vmax, type: max_speed}
output: {every: 0.01, vtk: true}
)";

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

turbid::tools::RunRequest request(const fs::path& scene, const fs::path& out) {
  turbid::tools::RunRequest r;
  r.scene_file = scene;
  r.out = out;
  r.backend = "cpu";
  r.progress = false;
  return r;
}

}  // namespace

void check_resume(const std::string& scene_text) {
  const fs::path dir = fs::temp_directory_path() / ("turbid_resume_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path scene = dir / "scene.yaml";
  std::ofstream(scene) << scene_text;

  // Uninterrupted run to 0.06 s.
  const auto full = turbid::tools::run_scene(request(scene, dir / "full"));
  ASSERT_EQ(full.at("status"), "completed");

  // Interrupted run: stops at 0.035 s with a checkpoint taken at 0.02 s, then resumes to 0.06 s.
  auto first = request(scene, dir / "split");
  first.end_time = 0.035;
  first.checkpoint_every = 0.02;
  const auto part = turbid::tools::run_scene(first);
  ASSERT_EQ(part.at("status"), "completed");
  turbid::tools::RunRequest again;
  again.resume = dir / "split";
  again.backend = "cpu";
  again.progress = false;
  again.end_time = 0.06;
  const auto resumed = turbid::tools::run_scene(again);
  ASSERT_EQ(resumed.at("status"), "completed");

  EXPECT_EQ(full.at("steps"), resumed.at("steps"));
  EXPECT_EQ(full.at("simulated_time").get<double>(), resumed.at("simulated_time").get<double>());
  // Every frame and every probe row must match byte for byte.
  int frames = 0;
  for (const auto& e : fs::directory_iterator(dir / "full")) {
    if (e.path().extension() != ".vtp") continue;
    const fs::path twin = dir / "split" / e.path().filename();
    ASSERT_TRUE(fs::exists(twin)) << twin;
    EXPECT_EQ(slurp(e.path()), slurp(twin)) << e.path().filename() << " differs after resume";
    ++frames;
  }
  EXPECT_GE(frames, 6);
  EXPECT_EQ(slurp(dir / "full" / "probes.csv"), slurp(dir / "split" / "probes.csv"));
  EXPECT_EQ(slurp(dir / "full" / "particles.pvd"), slurp(dir / "split" / "particles.pvd"));
  fs::remove_all(dir);
}

TEST(CheckpointResume, ResumedRunIsBitIdenticalToUninterruptedRun) { check_resume(kScene); }

// With particle shifting the next drift uses the shifting velocity of the last force pass, which
// the checkpoint must therefore hold (like the acceleration).
TEST(CheckpointResume, ResumedRunWithShiftingIsBitIdentical) {
  check_resume(std::string(kScene) + "numerics: {shifting: {coefficient: 2.0}}\n");
}
