// Time series as CSV (forces.csv, probes.csv): header `time,<name>,...`, then one row per call
// to append. Cells hold the shortest decimal text that reads back as the same double, so nothing
// is lost to rounding. Every row is flushed to the operating system as it is written, so a run
// that is killed keeps the rows it had reached. Units are SI; probes.csv documents them with the
// quantity that fills each column, forces.csv names them in its header.
#pragma once
#include <cstdio>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace turbid::tools {

class CsvSeriesWriter {
 public:
  // `columns` are the names after the leading "time" column (header: time,columns...). The
  // parent directory is created if missing.
  // Without `resume_time` the file is started afresh. With it (a restart from a checkpoint taken
  // at that time) an existing file with the same header keeps its rows with time <= resume_time
  // and new rows are appended after them; a missing file or a different header starts afresh.
  // `time_column` names the first column ("time"; forces.csv uses "time [s]").
  CsvSeriesWriter(std::filesystem::path file, std::vector<std::string> columns,
                  std::optional<double> resume_time = std::nullopt, std::string time_column = "time");
  ~CsvSeriesWriter();
  CsvSeriesWriter(const CsvSeriesWriter&) = delete;
  CsvSeriesWriter& operator=(const CsvSeriesWriter&) = delete;
  CsvSeriesWriter(CsvSeriesWriter&& other) noexcept;
  CsvSeriesWriter& operator=(CsvSeriesWriter&& other) noexcept;

  // A full row: row[0] is the time, then one value per column (size must be columns + 1).
  void append(const std::vector<double>& row);
  // The same with the time apart: values.size() must equal the number of columns.
  void append(double time, std::span<const double> values);

  const std::filesystem::path& file() const { return file_; }
  const std::vector<std::string>& columns() const { return columns_; }
  std::size_t rows() const { return rows_; }  // rows in the file, kept ones included

  static std::string header_line(const std::vector<std::string>& columns,
                                 const std::string& time_column = "time");  // without '\n'

 private:
  void write_line(const std::string& line);

  std::filesystem::path file_;
  std::vector<std::string> columns_;
  std::FILE* out_ = nullptr;
  std::size_t rows_ = 0;
};

}  // namespace turbid::tools
