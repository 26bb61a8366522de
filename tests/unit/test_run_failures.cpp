// Runs that go wrong must stop with a diagnosis (blow-up) or carry on and count (particles leaving
// the domain), never crash, and keep what was written before.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "tools/runner.hpp"

namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("turbid_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

nlohmann::json run(const fs::path& dir, const std::string& yaml) {
  std::ofstream(dir / "scene.yaml") << yaml;
  turbid::tools::RunRequest r;
  r.scene_file = dir / "scene.yaml";
  r.out = dir / "out";
  r.backend = "cpu";
  r.progress = false;
  return turbid::tools::run_scene(r);
}

}  // namespace

// A dam break whose density may vary by only 1%: the collapsing column compresses the water by
// about v/c0 = 10% where it hits the wall (hydrostatic compression at rest is only ~0.5% for
// c0 = 20 m/s, H = 0.2 m), so the run must stop naming the step, the time, the particle and the field.
TEST(RunFailures, BlowUpStopsWithDiagnosisAndKeepsOutputs) {
  const fs::path dir = scratch("blowup");
  const auto report = run(dir, R"(name: blow_up
dimensions: 2
resolution: {particle_spacing: 0.02}
time: {end: 0.5}
numerics: {max_density_variation: 0.01}
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.2, 0.2]}}
probes:
  - {name: vmax, type: max_speed}
output: {every: 0.01, vtk: true}
)");
  EXPECT_EQ(report.at("status"), "blow-up");
  const std::string error = report.at("error");
  EXPECT_NE(error.find("step"), std::string::npos) << error;
  EXPECT_NE(error.find("t = "), std::string::npos) << error;
  EXPECT_NE(error.find("particle id"), std::string::npos) << error;
  EXPECT_NE(error.find("density"), std::string::npos) << error;
  EXPECT_LT(report.at("simulated_time").get<double>(), 0.5);
  EXPECT_TRUE(fs::exists(dir / "out" / "run.json"));
  EXPECT_TRUE(fs::exists(dir / "out" / "particles.pvd"));
  EXPECT_TRUE(fs::exists(dir / "out" / "particles_0000.vtp"));
  fs::remove_all(dir);
}

// A write that fails mid-run (here the second ParaView frame's path is taken by a directory, as a
// full disk fails a write) ends the run with run.json saying "failed" and naming the file, the
// outputs before it kept, and the checkpoint before it resumable (issue #27 item 6).
TEST(RunFailures, AFailedWriteEndsWithRunJsonAndTheCheckpointBeforeItResumes) {
  const fs::path dir = scratch("write");
  fs::create_directories(dir / "out" / "particles_0002.vtp");
  const auto report = run(dir, R"(name: failed_write
dimensions: 2
resolution: {particle_spacing: 0.02}
time: {end: 0.05}
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.2, 0.2]}}
output: {every: 0.01, vtk: true, checkpoint_every: 0.005}
)");
  ASSERT_EQ(report.at("status"), "failed");
  const std::string error = report.at("error");
  std::printf("[ measured ] failed at t = %.4f s: %s\n", report.at("simulated_time").get<double>(), error.c_str());
  EXPECT_NE(error.find("particles_0002.vtp"), std::string::npos) << error;
  ASSERT_TRUE(fs::exists(dir / "out" / "run.json"));
  std::ifstream in(dir / "out" / "run.json");
  const auto written = nlohmann::json::parse(in);
  EXPECT_EQ(written.at("status"), "failed");
  EXPECT_EQ(written.at("error"), error);
  EXPECT_TRUE(fs::exists(dir / "out" / "particles_0001.vtp"));
  // Output 2 is due at t = 0.02 s; the checkpoints every 0.005 s before it are on disk and resume.
  EXPECT_GE(report.at("simulated_time").get<double>(), 0.02);
  EXPECT_LT(report.at("simulated_time").get<double>(), 0.03);
  ASSERT_TRUE(fs::exists(dir / "out" / "checkpoint" / "checkpoint.json"));
  fs::remove_all(dir / "out" / "particles_0002.vtp");
  turbid::tools::RunRequest again;
  again.resume = dir / "out";
  again.backend = "cpu";
  again.progress = false;
  const auto resumed = turbid::tools::run_scene(again);
  EXPECT_EQ(resumed.at("status"), "completed");
  EXPECT_NEAR(resumed.at("simulated_time").get<double>(), 0.05, 0.002);
  fs::remove_all(dir);
}

// A blow-up within the first steps comes from an input, not the flow: with a density diffusion
// delta of 50 (usually 0.1) the dam break blows up at its 4th step, and the message names that key
// and value besides the particle (issue #27 item 2).
TEST(RunFailures, ABlowUpInTheFirstStepsNamesTheInputOutOfRange) {
  const fs::path dir = scratch("early");
  const std::string scene = R"(name: early
dimensions: 2
resolution: {particle_spacing: 0.02}
time: {end: 0.05}
numerics: {density_diffusion: {type: fourtakas, delta: DELTA}}
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.4, 0.3]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.2, 0.2]}}
)";
  auto text = scene;
  text.replace(text.find("DELTA"), 5, "50");
  const auto report = run(dir, text);
  ASSERT_EQ(report.at("status"), "blow-up");
  const std::string error = report.at("error");
  std::printf("[ measured ] step %llu: %s\n", static_cast<unsigned long long>(report.at("steps").get<std::uint64_t>()),
              error.c_str());
  EXPECT_LE(report.at("steps").get<std::uint64_t>(), 20u);
  EXPECT_NE(error.find("particle id"), std::string::npos) << error;
  EXPECT_NE(error.find("numerics: density_diffusion: delta = 50"), std::string::npos) << error;
  // The usual delta runs to the end: the hint is about the input, not the scene.
  auto usual = scene;
  usual.replace(usual.find("DELTA"), 5, "0.1");
  fs::remove_all(dir / "out");
  EXPECT_EQ(run(dir, usual).at("status"), "completed");
  fs::remove_all(dir);
}

// Free fall out of the domain: after 0.3 s a body released at rest has fallen g t^2 / 2 = 0.44 m,
// further than the 0.25 m to the bottom of the domain, so every one of the 25 fluid particles must
// have been removed and counted, and the run must still complete.
TEST(RunFailures, ParticlesLeavingTheDomainAreRemovedAndCounted) {
  const fs::path dir = scratch("leave");
  const auto report = run(dir, R"(name: leave
dimensions: 2
resolution: {particle_spacing: 0.02}
time: {end: 0.3}
materials:
  water: {density: 1000, sound_speed: 10}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.1, 0.1]}}
domain: {min: [-0.2, -0.25], max: [0.3, 0.3]}
probes:
  - {name: n, type: fluid_particles}
output: {every: 0.05, vtk: false}
)");
  EXPECT_EQ(report.at("status"), "completed");
  EXPECT_EQ(report.at("fluid_particles").get<int>(), 25);
  EXPECT_EQ(report.at("removed_particles").get<int>(), 25);
  EXPECT_EQ(report.at("particles_end").get<int>(), 0);
  fs::remove_all(dir);
}

// Issue #27: '--checkpoint-every 1e-300' passed and the run hung after its first step. The
// command-line schedule goes through the scene's own bound and is refused, naming the option's key.
TEST(RunFailures, ACheckpointIntervalNoRunCouldHonourIsRefused) {
  turbid::fsi::Scene scene;
  scene.end_time = 0.25;
  turbid::tools::RunRequest request;
  request.checkpoint_every = 1e-300;
  try {
    turbid::tools::apply_overrides(scene, request);
    ADD_FAILURE() << "no error for --checkpoint-every 1e-300";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'checkpoint_every' = 1e-300 s over an end time of 0.25 s asks for 2.5e+299 "
                                         "checkpoints, more than 1e+05"),
              std::string::npos)
        << e.what();
  }
  request.checkpoint_every = 0.01;  // 25 checkpoints: fine
  EXPECT_NO_THROW(turbid::tools::apply_overrides(scene, request));
  EXPECT_DOUBLE_EQ(scene.output.checkpoint_every, 0.01);
}

// Issue #27: Ctrl-C killed a run with no message, no run.json and no checkpoint. Now SIGINT (here
// sent to this process one second into a run that would take minutes) stops it after the current
// step with a checkpoint and run.json (status "interrupted"), and the run resumes from there.
TEST(RunFailures, CtrlCKeepsTheWorkAndTheRunResumes) {
  const fs::path dir = scratch("sigint");
  std::thread sender([] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    ::kill(::getpid(), SIGINT);
  });
  const auto report = run(dir, R"(name: interrupted
dimensions: 2
resolution: {particle_spacing: 0.02}
time: {end: 100.0}
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.8, 0.4]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.2, 0.2]}}
probes:
  - {name: vmax, type: max_speed}
output: {every: 0.01}
)");
  sender.join();
  ASSERT_EQ(report.at("status"), "interrupted");
  EXPECT_EQ(report.at("signal"), "SIGINT");
  EXPECT_EQ(report.at("signal_number").get<int>(), SIGINT);
  const double stopped = report.at("simulated_time").get<double>();
  EXPECT_GT(stopped, 0.0);
  EXPECT_LT(stopped, 100.0);
  std::ifstream in(dir / "out" / "run.json");
  const auto written = nlohmann::json::parse(in);
  EXPECT_EQ(written.at("status"), "interrupted");
  EXPECT_TRUE(fs::exists(dir / "out" / "checkpoint"));

  // A checkpoint belongs to its scene (issue #27 item 5): an edited scene.yaml is refused, naming
  // it; so is a state value of the wrong type, naming the file and key.
  const fs::path saved = dir / "out" / "scene.yaml";
  std::string text;
  {
    std::ifstream f(saved);
    text.assign(std::istreambuf_iterator<char>(f), {});
  }
  std::ofstream(saved) << std::string(text).replace(text.find("sound_speed: 20"), 15, "sound_speed: 25");
  turbid::tools::RunRequest r;
  r.resume = dir / "out";
  r.out = dir / "out";
  r.backend = "cpu";
  r.progress = false;
  try {
    turbid::tools::run_scene(r);
    ADD_FAILURE() << "an edited scene.yaml resumed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'scene.yaml' is not the file its checkpoint was written with"),
              std::string::npos) << e.what();
  }
  std::ofstream(saved) << text;
  const fs::path meta = dir / "out" / "checkpoint" / "checkpoint.json";
  std::string meta_text;
  {
    std::ifstream f(meta);
    meta_text.assign(std::istreambuf_iterator<char>(f), {});
  }
  auto edited = nlohmann::json::parse(meta_text);
  edited["state"]["time"] = "soon";
  std::ofstream(meta) << edited.dump(2);
  try {
    turbid::tools::run_scene(r);
    ADD_FAILURE() << "an edited state resumed";
  } catch (const std::runtime_error& e) {
    // The state's digest sees the edit first (tools/checkpoint.hpp).
    EXPECT_NE(std::string(e.what()).find("checkpoint.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the 'state' block differs"), std::string::npos) << e.what();
  }
  // A version 1 checkpoint (no digests) with the same edit: the wrong type is named with its key.
  edited["version"] = 1;
  edited.erase("digests");
  std::ofstream(meta) << edited.dump(2);
  try {
    turbid::tools::run_scene(r);
    ADD_FAILURE() << "a string time resumed";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint.json"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'state.time' must be a number, got \"soon\""), std::string::npos) << e.what();
  }
  std::ofstream(meta) << meta_text;

  // Leftovers of a run that died while writing are cleaned on the next start.
  fs::create_directories(dir / "out" / "checkpoint.tmp");
  std::ofstream(dir / "out" / "checkpoint.tmp" / "x.bin") << "partial";
  std::ofstream(dir / "out" / "probes.csv.tmp-99999") << "partial";
  fs::create_directories(dir / "out" / "checkpoint.old");

  r = {};
  r.resume = dir / "out";
  r.out = dir / "out";
  r.backend = "cpu";
  r.progress = false;
  r.end_time = stopped + 0.02;
  const auto resumed = turbid::tools::run_scene(r);
  EXPECT_EQ(resumed.at("status"), "completed");
  EXPECT_GE(resumed.at("simulated_time").get<double>(), stopped + 0.02);
  EXPECT_GT(resumed.at("steps").get<std::uint64_t>(), report.at("steps").get<std::uint64_t>());
  EXPECT_FALSE(fs::exists(dir / "out" / "checkpoint.tmp"));
  EXPECT_FALSE(fs::exists(dir / "out" / "probes.csv.tmp-99999"));
  EXPECT_FALSE(fs::exists(dir / "out" / "checkpoint.old"));
  // Numbers after a resume (issue #27 item 10): the whole run's wall time includes the second
  // before the interruption (it was not restored, so the rate came out up to 100 times too high),
  // and the resumed segment reports its own steps and rate.
  EXPECT_GT(resumed.at("wall_seconds").get<double>(), report.at("wall_seconds").get<double>());
  EXPECT_GE(report.at("wall_seconds").get<double>(), 0.9);
  const auto& segment = resumed.at("segment");
  EXPECT_EQ(segment.at("steps").get<std::uint64_t>(),
            resumed.at("steps").get<std::uint64_t>() - report.at("steps").get<std::uint64_t>());
  EXPECT_DOUBLE_EQ(segment.at("from_time").get<double>(), stopped);
  EXPECT_GT(segment.at("particle_steps_per_second").get<double>(), 0.0);

  // Resuming a run that already reached its end, or with an end before the checkpoint, is refused
  // and leaves run.json as it was (issue #27 item 5; it was overwritten with wall time 0 and rate 0).
  const auto before = fs::last_write_time(dir / "out" / "run.json");
  try {
    turbid::tools::run_scene(r);  // the same end again: finished
    ADD_FAILURE() << "no error for resuming a finished run";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("already finished at t = "), std::string::npos) << e.what();
  }
  r.end_time = stopped / 2;
  try {
    turbid::tools::run_scene(r);
    ADD_FAILURE() << "no error for an end time before the checkpoint";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("is not past the time of the checkpoint"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::last_write_time(dir / "out" / "run.json"), before);
  fs::remove_all(dir);
}
