// run.json: the summary of a run (counts, steps, wall time, particle-steps per second,
// conservation errors), written atomically and pretty printed.
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

namespace turbid::tools {

// Writes `j` indented by 2 spaces with a final newline, atomically (temp file + rename). The
// parent directory is created if missing. NaN and infinity become null (JSON has no such numbers).
void write_run_json(const std::filesystem::path& file, const nlohmann::json& j);

}  // namespace turbid::tools
