// Helpers shared by the validation tests: quick/full mode, running a scene of scenes/ and reading
// the CSV files runs write.
#pragma once
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <unistd.h>
#include <vector>

#include "tools/runner.hpp"

namespace turbid::validation {

// TURBID_FULL=1 selects the documented full-resolution runs; the default is CI's quick mode.
inline bool full_mode() {
  const char* v = std::getenv("TURBID_FULL");
  return v != nullptr && std::string(v) == "1";
}

// Runs scenes/<scene>.yaml at spacing dx (and to end time `end` when > 0), without progress line,
// into a fresh directory `out` under the system's temporary directory (named after the scene and
// this process); `report` is run.json as the runner returns it.
struct SceneRun {
  std::filesystem::path out;
  nlohmann::json report;
};
inline SceneRun run_scene_file(const std::string& scene, double dx, double end = 0) {
  SceneRun run;
  run.out = std::filesystem::temp_directory_path() / ("turbid_validation_" + scene + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(run.out);
  tools::RunRequest request;
  request.scene_file = std::filesystem::path(TURBID_SOURCE_DIR) / "scenes" / (scene + ".yaml");
  request.out = run.out;
  request.spacing = dx;
  if (end > 0) request.end_time = end;
  request.progress = false;
  run.report = tools::run_scene(request);
  return run;
}

// Columns of a CSV file with a header line; lines starting with '#' are skipped.
inline std::map<std::string, std::vector<double>> read_csv(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path.string());
  std::map<std::string, std::vector<double>> columns;
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream ss(line);
    std::string cell;
    std::vector<std::string> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (names.empty()) {
      names = cells;
      continue;
    }
    for (std::size_t k = 0; k < names.size() && k < cells.size(); ++k) columns[names[k]].push_back(std::stod(cells[k]));
  }
  // Each column also under its name without the unit ("front [m]" as "front"), unless taken.
  for (const std::string& n : names) {
    const std::size_t unit = n.find(" [");
    if (unit != std::string::npos && unit > 0 && !columns.count(n.substr(0, unit)))
      columns[n.substr(0, unit)] = columns[n];
  }
  return columns;
}

}  // namespace turbid::validation
