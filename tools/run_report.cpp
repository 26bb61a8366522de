// run.json writer; see run_report.hpp.
#include "tools/run_report.hpp"

#include <stdexcept>
#include <system_error>

#include "tools/atomic_file.hpp"

namespace turbid::tools {

void write_run_json(const std::filesystem::path& file, const nlohmann::json& j) {
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec)
      throw std::runtime_error("cannot create directory '" + file.parent_path().string() + "': " + ec.message());
  }
  // `replace`: a stray invalid UTF-8 byte (a scene name, say) must not lose the whole report.
  write_text_atomic(file, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

}  // namespace turbid::tools
