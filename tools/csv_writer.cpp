// CSV time-series writer; see csv_writer.hpp.
#include "tools/csv_writer.hpp"

#include <cerrno>
#include <charconv>
#include <fstream>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "tools/atomic_file.hpp"

namespace turbid::tools {
namespace fs = std::filesystem;

namespace {

void append_number(std::string& out, double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

// RFC 4180: a cell with a comma, quote or line break is quoted, with quotes doubled.
std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string errno_text() { return std::error_code(errno, std::generic_category()).message(); }

}  // namespace

std::string CsvSeriesWriter::header_line(const std::vector<std::string>& columns, const std::string& time_column) {
  std::string h = csv_cell(time_column);
  for (const auto& c : columns) {
    h += ',';
    h += csv_cell(c);
  }
  return h;
}

CsvSeriesWriter::CsvSeriesWriter(fs::path file, std::vector<std::string> columns,
                                 std::optional<double> resume_time, std::string time_column)
    : file_(std::move(file)), columns_(std::move(columns)) {
  if (file_.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(file_.parent_path(), ec);
    if (ec)
      throw std::runtime_error("cannot create directory '" + file_.parent_path().string() + "': " + ec.message());
  }
  const std::string header = header_line(columns_, time_column);

  // Keep the rows a resumed run has already produced, up to the checkpoint's time.
  std::string kept = header + "\n";
  if (resume_time) {
    std::ifstream in(file_);
    std::string line;
    if (in && std::getline(in, line) && line == header) {
      while (std::getline(in, line)) {
        if (line.empty()) continue;
        double t = 0;
        const auto cut = line.find(',');
        const auto r = std::from_chars(line.data(), line.data() + (cut == std::string::npos ? line.size() : cut), t);
        if (r.ec != std::errc{} || !(t <= *resume_time)) break;
        kept += line + "\n";
        ++rows_;
      }
    }
  }
  // Atomic: a resume that fails here leaves the previous file whole.
  write_text_atomic(file_, kept);

  out_ = std::fopen(file_.c_str(), "ab");
  if (!out_) throw std::runtime_error("cannot open '" + file_.string() + "' for writing: " + errno_text());
}

CsvSeriesWriter::~CsvSeriesWriter() {
  if (out_) std::fclose(out_);
}

CsvSeriesWriter::CsvSeriesWriter(CsvSeriesWriter&& o) noexcept
    : file_(std::move(o.file_)), columns_(std::move(o.columns_)), out_(std::exchange(o.out_, nullptr)), rows_(o.rows_) {}

CsvSeriesWriter& CsvSeriesWriter::operator=(CsvSeriesWriter&& o) noexcept {
  if (this != &o) {
    if (out_) std::fclose(out_);
    file_ = std::move(o.file_);
    columns_ = std::move(o.columns_);
    out_ = std::exchange(o.out_, nullptr);
    rows_ = o.rows_;
  }
  return *this;
}

void CsvSeriesWriter::append(const std::vector<double>& row) {
  if (row.empty() || row.size() != columns_.size() + 1)
    throw std::invalid_argument("CSV row for '" + file_.string() + "' has " + std::to_string(row.size()) +
                                " values, expected " + std::to_string(columns_.size() + 1) + " (time + columns)");
  append(row[0], std::span<const double>(row).subspan(1));
}

void CsvSeriesWriter::append(double time, std::span<const double> values) {
  if (values.size() != columns_.size())
    throw std::invalid_argument("CSV row for '" + file_.string() + "' has " + std::to_string(values.size()) +
                                " values after the time, expected " + std::to_string(columns_.size()));
  std::string line;
  line.reserve(24 * (values.size() + 1));
  append_number(line, time);
  for (double v : values) {
    line += ',';
    append_number(line, v);
  }
  line += '\n';
  write_line(line);
  ++rows_;
}

void CsvSeriesWriter::write_line(const std::string& line) {
  if (!out_) throw std::logic_error("CsvSeriesWriter used after being moved from");
  if (std::fwrite(line.data(), 1, line.size(), out_) != line.size() || std::fflush(out_) != 0)
    throw std::runtime_error("cannot write to '" + file_.string() + "': " + errno_text());
}

}  // namespace turbid::tools
