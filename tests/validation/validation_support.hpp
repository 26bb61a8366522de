// Helpers shared by the validation tests: quick/full mode and reading the CSV files runs write.
#pragma once
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace turbid::validation {

// TURBID_FULL=1 selects the documented full-resolution runs; the default is CI's quick mode.
inline bool full_mode() {
  const char* v = std::getenv("TURBID_FULL");
  return v != nullptr && std::string(v) == "1";
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
  return columns;
}

}  // namespace turbid::validation
