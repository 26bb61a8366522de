// Running a scene as the `turbid run` command does: overrides, writers (VTK, probes.csv,
// run.json, checkpoints), progress, resume. Used by the command line and by tests.
#pragma once
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "fsi/scene.hpp"
#include "tools/scene_reader.hpp"

namespace turbid::tools {

struct RunRequest {
  std::filesystem::path scene_file;          // empty with `resume`
  std::filesystem::path out;                 // run directory
  std::string backend = "auto";              // auto | cpu | cuda
  int threads = 0;                           // 0 = OpenMP default
  std::optional<double> end_time;            // overrides time.end [s]
  std::optional<double> spacing;             // overrides resolution.particle_spacing [m]
  std::optional<double> checkpoint_every;    // overrides output.checkpoint_every [s]
  std::optional<std::filesystem::path> resume;  // run directory holding checkpoint/
  bool progress = true;                      // progress line on stderr
};

// Applies command-line overrides to a parsed scene (spacing must be > 0, end > 0); a resume uses
// it. A new run reads its scene with the overrides instead (overrides_of, read_scene_file), so that
// they meet every check of the scene's own values.
void apply_overrides(fsi::Scene& scene, const RunRequest& request);
SceneOverrides overrides_of(const RunRequest& request);

// Runs to the end. Returns run.json's content; "status" is "completed" or "blow-up"
// (then "error" holds the diagnosis). Throws SceneError / std::runtime_error for bad input.
nlohmann::json run_scene(const RunRequest& request);

// Text of `turbid check`: particle counts, spacing, h, sound speed, memory estimate.
std::string describe_scene(const fsi::Scene& scene);

}  // namespace turbid::tools
