// The scene-file reader: YAML text -> the plain fsi::Scene the engine runs. Every error it reports
// names the file, the line and the column and says what was expected, in the compiler-like form
// "FILE:LINE:COL: error: WHAT", so that editors and CI logs can jump to it. YAML stays inside
// tools/: this header includes no yaml-cpp header.
#pragma once
#include <optional>
#include <stdexcept>
#include <string>

#include "fsi/scene.hpp"

namespace turbid::tools {

// A scene that cannot be run. what() is "FILE:LINE:COL: error: MESSAGE" (1-based line and column);
// errors that belong to no line (a missing file, an empty file) point at 1:1.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A command-line value outside its range ("turbid: --end 0: must be a positive time [s]").
struct OptionError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Reads and checks a scene file. Throws SceneError for a missing or unreadable file, a YAML syntax
// error, a schema error (unknown or missing key, wrong type, value out of range) or a semantic error
// (unknown material, overlapping regions, ...). Fills Scene::source_file and every `where`.
// Relative mesh paths are resolved against `relative_to` when given (a resumed run reads the scene
// copied into its run directory, but the meshes stay beside the original scene), else against the
// scene file's directory.
// Command-line values that replace the scene's own (`--spacing`, `--end`, `--checkpoint-every`):
// they are put in before the scene is checked, so they meet every check the scene's values meet
// (issue #28 item 1), and a message they cause says so.
struct SceneOverrides {
  std::optional<double> spacing;           // resolution.particle_spacing [m]
  std::optional<double> end_time;          // time.end [s]
  std::optional<double> checkpoint_every;  // output.checkpoint_every [s]
  bool any() const { return spacing || end_time || checkpoint_every; }
};

fsi::Scene read_scene_file(const std::string& path, const std::string& relative_to = {},
                           const SceneOverrides& overrides = {});

// The same for YAML text held in memory; `file_name_for_messages` is used in error messages and as
// Scene::source_file.
fsi::Scene read_scene_string(const std::string& yaml_text, const std::string& file_name_for_messages);

// Where an output schedule of the run would write more entries than anyone could use (VTK frames
// every `output.every`, force rows every `forces_every`, checkpoints every `checkpoint_every`, each
// over `end` seconds), the reason in words naming `key`; empty where it is fine. The scene reader
// and the command-line overrides both ask it, so neither can start a run that never gets past its
// first outputs.
std::string schedule_problem(double end, const fsi::OutputSpec& out);

}  // namespace turbid::tools
