// The `turbid` command: run, check and info.
#include <omp.h>

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <string>

#include "fsi/bullet_world.hpp"
#include "sph/backend.hpp"
#include "sph/config.hpp"
#include "tools/runner.hpp"
#include "tools/scene_reader.hpp"

namespace {

// A message that starts "FILE:LINE:COL: error:" (a scene item refused past the reader): printed as
// it is, where editors and log matchers look for the location.
bool located(const std::string& message) {
  const auto at = message.find(": error: ");
  return at != std::string::npos && at < message.find(' ');
}

// OpenMP threads that spin while they wait (libgomp's default when OMP_WAIT_POLICY is unset: a
// spin of about 300,000 iterations, some 3 ms, before sleeping, at every barrier) take the cores from
// other jobs on a shared machine, and the run collapses: 20 times slower beside one other job (issue
// #24, docs/performance.md "OpenMP on a shared machine"). Threads that sleep at once pay a wake-up
// at every one of a step's parallel loops: a small scene ran 1.3 times slower than with a spin of
// 300 iterations (about 3 us), which costs 2% beside a busy job. libgomp reads these once, when it
// is loaded, so a run started with neither is restarted here with OMP_WAIT_POLICY=passive (what
// other OpenMP runtimes read) and GOMP_SPINCOUNT=300 (libgomp's spin, which overrides the policy's).
// A policy or spin count set by the user is kept: `active` gains a little on a machine of one's own.
constexpr const char* kSpinCount = "300";

void prefer_passive_openmp(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0 || setenv("GOMP_SPINCOUNT", kSpinCount, 1) != 0) return;
  setenv("TURBID_OMP_WAIT_POLICY_SET", "1", 1);  // `turbid info` says who chose it
  execv("/proc/self/exe", argv);
  // The restart failed: go on with the runtime's default (the variables are set, too late to count).
}

std::string omp_wait_policy_text() {
  const char* p = std::getenv("OMP_WAIT_POLICY");
  const char* spin = std::getenv("GOMP_SPINCOUNT");
  if (std::getenv("TURBID_OMP_WAIT_POLICY_SET") != nullptr)
    return std::string("passive after a spin of ") + kSpinCount +
           " (turbid's default; set OMP_WAIT_POLICY or GOMP_SPINCOUNT to choose)";
  std::string text = p ? p : "the runtime's default";
  if (spin) text += std::string(", GOMP_SPINCOUNT=") + spin;
  return text;
}

int cmd_info() {
  std::printf("turbid %s (git %s, %s build)\n", TURBID_VERSION, TURBID_GIT_REVISION, TURBID_BUILD_TYPE);
  std::printf("precision        particle fields float32, conservation sums float64\n");
  std::printf("backends         cpu (OpenMP, %d threads available)", omp_get_max_threads());
  std::printf("%s", turbid::sph::cuda_backend_compiled() ? ", cuda (compiled in)" : "");
  std::printf("%s\n", turbid::sph::omp_device_backend_compiled() ? ", device-omp (compiled in)" : "");
  std::printf("openmp wait      %s\n", omp_wait_policy_text().c_str());
  std::printf("rigid bodies     built-in (motion: free)%s\n",
              turbid::fsi::bullet_available() ? ", Bullet double precision (motion: bullet)"
                                              : "; no Bullet (motion: bullet refused; install libbullet-dev and rebuild)");
  std::string why;
  const int gpus = turbid::sph::cuda_device_count(&why);
  if (gpus > 0) std::printf("gpus             %s\n", why.c_str());
  else std::printf("gpus             none usable: %s\n", why.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  prefer_passive_openmp(argv);
  CLI::App app{"turbid: weakly compressible SPH with fluid-structure interaction"};
  // At most one command; none is answered below (an unknown word is then named by CLI11 as an
  // argument it did not expect, instead of "A subcommand is required").
  app.require_subcommand(0, 1);
  app.set_version_flag("--version", std::string("turbid ") + TURBID_VERSION + " (git " + TURBID_GIT_REVISION + ")");
  app.footer(
      "Exit codes: 0 done; 1 a run-time error; 2 a scene error (FILE:LINE:COL: error:) or a refused option value;\n"
      "3 a run that blew up or failed (run.json says why); 130 / 143 stopped by Ctrl-C / SIGTERM with a checkpoint;\n"
      "105-114 command-line syntax (CLI11: unknown option or command, missing value, value out of range).\n");

  turbid::tools::RunRequest req;
  std::string scene_file, out, resume;
  std::optional<double> end, spacing, checkpoint_every;
  bool quiet = false;
  auto* run = app.add_subcommand("run", "Run a scene and write its results");
  run->add_option("scene", scene_file, "Scene file (YAML)");
  run->add_option("--out", out, "Run directory (default: runs/<scene name>)");
  run->add_option("--backend", req.backend,
                  "auto | cpu | cuda | device-omp (the CUDA backend's code on CPU threads, for testing it without a GPU)")
      ->check(CLI::IsMember({"auto", "cpu", "cuda", "device-omp"}));
  run->add_option("--threads", req.threads, "CPU threads, 0 = all (default)")->check(CLI::Range(0, 4096));
  run->add_option("--end", end, "End time [s], overrides the scene");
  run->add_option("--spacing", spacing, "Particle spacing [m], overrides the scene");
  run->add_option("--checkpoint-every", checkpoint_every, "Checkpoint interval [s] (0 = none)");
  run->add_option("--resume", resume, "Continue the run in this directory from its checkpoint");
  run->add_flag("--quiet", quiet, "No progress line");

  auto* check = app.add_subcommand("check", "Validate a scene; print particle counts and memory");
  std::string check_file;
  check->add_option("scene", check_file, "Scene file (YAML)")->required();
  std::optional<double> check_spacing;
  check->add_option("--spacing", check_spacing, "Particle spacing [m], overrides the scene");

  app.add_subcommand("info", "Version, build options, backends and GPUs");

  CLI11_PARSE(app, argc, argv);

  try {
    if (app.get_subcommands().empty()) {
      std::fprintf(stderr, "turbid: give a command: run, check or info (turbid --help lists them)\n");
      return 2;
    }
    if (app.got_subcommand("info")) return cmd_info();
    if (app.got_subcommand("check")) {
      turbid::tools::SceneOverrides o;
      o.spacing = check_spacing;
      const auto scene = turbid::tools::read_scene_file(check_file, {}, o);
      std::cout << turbid::tools::describe_scene(scene) << "scene OK\n";
      return 0;
    }
    // run
    if (scene_file.empty() && resume.empty()) {
      std::fprintf(stderr, "turbid run: give a scene file or --resume DIR\n");
      return 2;
    }
    if (!scene_file.empty() && !resume.empty()) {
      std::fprintf(stderr, "turbid run: give either a scene file or --resume DIR, not both\n");
      return 2;
    }
    req.end_time = end;
    req.spacing = spacing;
    req.checkpoint_every = checkpoint_every;
    req.progress = !quiet;
    if (!resume.empty()) req.resume = resume;
    req.scene_file = scene_file;
    if (!out.empty()) {
      req.out = out;
    } else if (resume.empty()) {
      req.out = std::filesystem::path("runs") / std::filesystem::path(scene_file).stem();
    }
    const auto report = turbid::tools::run_scene(req);
    const std::string dir = req.out.empty() ? resume : req.out.string();
    if (report.at("status") == "interrupted") {
      // Ctrl-C or SIGTERM: the run stopped after a step with a checkpoint; exit 128 + the signal.
      const int signo = report.at("signal_number").get<int>();
      std::fprintf(stderr, "turbid: %s at t = %.6g s (step %llu): checkpoint and run.json written in %s\n",
                   report.at("signal").get<std::string>().c_str(), report.at("simulated_time").get<double>(),
                   static_cast<unsigned long long>(report.at("steps").get<std::uint64_t>()), dir.c_str());
      std::fprintf(stderr, "turbid: continue with: turbid run --resume %s\n", dir.c_str());
      return 128 + signo;
    }
    if (report.contains("run_json_error"))
      std::fprintf(stderr, "turbid: error: run.json could not be written: %s\n",
                   report.at("run_json_error").get<std::string>().c_str());
    if (report.at("status") != "completed") {
      // A located message (a scene item refused during the run) keeps FILE:LINE:COL at the start.
      const std::string error = report.value("error", std::string("run failed"));
      if (located(error)) std::fprintf(stderr, "%s\n", error.c_str());
      else std::fprintf(stderr, "turbid: error: %s\n", error.c_str());
      std::fprintf(stderr, "turbid: outputs up to the failure are in %s\n", dir.c_str());
      if (std::filesystem::exists(std::filesystem::path(dir) / "checkpoint" / "checkpoint.json"))
        std::fprintf(stderr, "turbid: the last checkpoint before it resumes with: turbid run --resume %s\n", dir.c_str());
      return 3;
    }
    std::printf("finished: %llu steps, %.4g s simulated in %.1f s wall, %.3g particle-steps/s, %llu particles removed\n",
                static_cast<unsigned long long>(report.at("steps").get<std::uint64_t>()),
                report.at("simulated_time").get<double>(), report.at("wall_seconds").get<double>(),
                report.at("particle_steps_per_second").get<double>(),
                static_cast<unsigned long long>(report.at("removed_particles").get<std::uint64_t>()));
    const bool vtk = std::filesystem::exists(std::filesystem::path(dir) / "particles.pvd");
    const bool forces = std::filesystem::exists(std::filesystem::path(dir) / "forces.csv");
    std::printf("results in %s: %sprobes.csv, %srun.json\n", dir.c_str(), vtk ? "particles.pvd (open in ParaView), " : "",
                forces ? "forces.csv (tools/plot_forces draws it), " : "");
    return 0;
  } catch (const turbid::tools::OptionError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const turbid::tools::SceneError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    // Messages that already start with FILE:LINE:COL: error: stay at the start of the line, where
    // editors and log matchers look for them.
    // Such a message is a scene error found past the reader (a material that the physics refuses,
    // a body whose inertia is not finite): exit 2 like the reader's own.
    const std::string what = e.what();
    if (located(what)) {
      std::fprintf(stderr, "%s\n", what.c_str());
      return 2;
    }
    std::fprintf(stderr, "turbid: error: %s\n", what.c_str());
    return 1;
  }
}
