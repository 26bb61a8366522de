// Prescribed-path samples from CSV; see path_csv.hpp.
#include "tools/path_csv.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string_view>
#include <vector>

#include "tools/scene_reader.hpp"

namespace turbid::tools {

namespace {

struct Field {
  std::string text;
  int column = 1;  // 1-based, of the first character after leading blanks
};

std::vector<Field> split(const std::string& line) {
  std::vector<Field> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = std::min(line.find(',', start), line.size());
    std::size_t a = start, b = end;
    while (a < b && (line[a] == ' ' || line[a] == '\t')) ++a;
    while (b > a && (line[b - 1] == ' ' || line[b - 1] == '\t' || line[b - 1] == '\r')) --b;
    out.push_back({line.substr(a, b - a), int(a) + 1});
    if (end >= line.size()) break;
    start = end + 1;
  }
  return out;
}

bool skipped(const std::string& line) {
  for (char c : line) {
    if (c == '#') return true;
    if (c != ' ' && c != '\t' && c != '\r') return false;
  }
  return true;
}

}  // namespace

void read_path_csv(const std::string& path, const std::string& shown, int dims, fsi::PrescribedPathSpec& spec) {
  const auto fail = [&](int line, int column, const std::string& message) {
    throw SceneError(shown + ":" + std::to_string(line) + ":" + std::to_string(column) + ": error: " + message);
  };
  std::ifstream in(path);
  if (!in) fail(1, 1, "cannot open the path file '" + path + "'");

  // Channel of each column: 0 = time, 1..3 = x, y, z [m], 4..6 = rx, ry, rz; scale to SI.
  const std::vector<std::string> names = dims == 2 ? std::vector<std::string>{"time", "x", "y", "rz"}
                                                   : std::vector<std::string>{"time", "x", "y", "z", "rx", "ry", "rz"};
  std::vector<int> channel;
  std::vector<double> scale;
  std::string line;
  int line_no = 0;
  bool header = false;
  spec.times.clear();
  spec.displacement.clear();
  spec.angles.clear();
  while (std::getline(in, line)) {
    ++line_no;
    if (skipped(line)) continue;
    const std::vector<Field> fields = split(line);
    if (!header) {
      header = true;
      std::vector<bool> seen(7, false);
      for (const Field& f : fields) {
        const std::size_t open = f.text.find('['), close = f.text.rfind(']');
        std::string name = f.text.substr(0, open);
        while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
        const std::string unit =
            open != std::string::npos && close != std::string::npos && close > open ? f.text.substr(open + 1, close - open - 1) : "";
        int c = -1;
        const char* all[7] = {"time", "x", "y", "z", "rx", "ry", "rz"};
        for (int k = 0; k < 7; ++k)
          if (name == all[k]) c = k;
        bool allowed = false;
        for (const auto& n : names) allowed = allowed || n == name;
        if (!allowed) {
          std::string list;
          for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
          fail(line_no, f.column, "unknown column '" + f.text + "' in the path header; a " + std::to_string(dims) +
                                      "D path has the columns " + list + " ('name [unit]')");
        }
        if (seen[std::size_t(c)]) fail(line_no, f.column, "column '" + name + "' is given twice");
        seen[std::size_t(c)] = true;
        double s = 1;
        if (c == 0) {
          if (unit != "s") fail(line_no, f.column, "column 'time' must be in seconds: 'time [s]', got '" + f.text + "'");
        } else if (c <= 3) {
          if (unit != "m") fail(line_no, f.column, "column '" + name + "' must be in metres: '" + name + " [m]', got '" + f.text + "'");
        } else if (unit == "deg") {
          s = std::numbers::pi / 180;
        } else if (unit != "rad") {
          fail(line_no, f.column, "column '" + name + "' must be in degrees or radians: '" + name + " [deg]' or '" + name +
                                      " [rad]', got '" + f.text + "'");
        }
        channel.push_back(c);
        scale.push_back(s);
      }
      if (!seen[0]) fail(line_no, 1, "the path header needs a column 'time [s]'");
      continue;
    }
    if (fields.size() != channel.size())
      fail(line_no, 1, "expected " + std::to_string(channel.size()) + " values (one per header column), got " +
                           std::to_string(fields.size()));
    double t = 0;
    fsi::Vec3d d{0, 0, 0}, a{0, 0, 0};
    for (std::size_t j = 0; j < fields.size(); ++j) {
      const Field& f = fields[j];
      std::string_view s = f.text;
      if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
      double x = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
      if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x))
        fail(line_no, f.column, "expected a number, got '" + f.text + "'");
      const int c = channel[j];
      x *= scale[j];
      if (c == 0) t = x;
      else if (c <= 3) d[std::size_t(c - 1)] = x;
      else a[std::size_t(c - 4)] = x;
    }
    std::size_t jt = 0;
    while (channel[jt] != 0) ++jt;
    if (!spec.times.empty() && !(t > spec.times.back()))
      fail(line_no, fields[jt].column, "sample times must increase strictly: t = " + fields[jt].text +
                                          " s does not follow the previous t = " +
                                          [&] { std::ostringstream o; o << spec.times.back(); return o.str(); }() + " s");
    spec.times.push_back(t);
    spec.displacement.push_back(d);
    spec.angles.push_back(a);
  }
  if (!header) fail(1, 1, "the path file is empty; expected a header such as 'time [s], x [m], y [m]' and samples");
  if (spec.times.size() < 2)
    fail(line_no, 1, "a path needs at least 2 samples, the file has " + std::to_string(spec.times.size()));
}

}  // namespace turbid::tools
