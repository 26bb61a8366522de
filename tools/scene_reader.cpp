// The YAML scene reader. It walks the yaml-cpp node tree by hand rather than with as<T>(), because
// every value must be checked against the schema and every error must point at the line and column
// of the offending key or value. Checks that relate several items (a fluid inside a container, an
// unknown material) run while reading, after the items they refer to, so they can still point at
// the YAML node. The first error stops the read: a scene either parses completely or not at all.
#include "tools/scene_reader.hpp"
#include "tools/yaml_syntax.hpp"

#include "fsi/prescribed_path.hpp"
#include "fsi/bullet_world.hpp"
#include "sph/physics_params.hpp"
#include "tools/path_csv.hpp"

#include <yaml-cpp/yaml.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace turbid::tools {
namespace {

using fsi::Vec3d;

constexpr const char* kAxisName[3] = {"x", "y", "z"};
constexpr const char* kFaceName[6] = {"-x", "+x", "-y", "+y", "-z", "+z"};

std::string to_lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Optimal string alignment distance (Levenshtein plus swaps of adjacent letters), so that each of
// the common typos (a letter missing, extra, wrong or swapped) counts as one edit.
int edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

// The allowed word that `word` was most likely meant to be: within two edits (ignoring case), or
// one of the two a prefix of the other. Nothing when no guess is close enough to help; a guess
// that replaces most of a very short word is not a guess but noise.
std::optional<std::string> closest(std::string_view word, const std::vector<std::string>& allowed) {
  const std::string w = to_lower(word);
  std::optional<std::string> best;
  int best_distance = 3;
  for (const std::string& candidate : allowed) {
    const std::string c = to_lower(candidate);
    int d = edit_distance(w, c);
    if (d > 2 || d >= static_cast<int>(w.size())) {
      const bool prefix = std::min(w.size(), c.size()) >= 2 && (c.starts_with(w) || w.starts_with(c));
      if (!prefix) continue;
      d = 2;
    }
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  return best;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& allowed) {
  const auto guess = closest(word, allowed);
  return guess ? "; did you mean '" + *guess + "'?" : std::string();
}

std::string join(const std::vector<std::string>& words, std::string_view sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i) out += sep;
    out += words[i];
  }
  return out;
}

// "'a' or 'b'" / "one of 'a', 'b', 'c'"
std::string choices_text(const std::vector<std::string>& options) {
  std::vector<std::string> quoted;
  for (const auto& o : options) quoted.push_back("'" + o + "'");
  if (quoted.size() == 2) return quoted[0] + " or " + quoted[1];
  return "one of " + join(quoted);
}

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(12) << v;
  return s.str();
}

// The most particles a scene can hold: ids are 32-bit.
constexpr double kMaxParticles = 4294967295.0;

// The least memory a particle takes (its fields, before neighbour lists), to refuse a scene that
// cannot fit before allocating it [bytes]; `turbid check` prints the scene's own figure.
constexpr double kMinBytesPerParticle = 100.0;

// Particles a scene would build, from its stated geometry alone (upper bounds: bounding boxes of
// fluid blocks and structures, whole wall layers).
struct ParticleEstimate {
  double fluid = 0, walls = 0, structures = 0, reserved = 0;
  double total() const { return fluid + walls + structures + reserved; }
};

ParticleEstimate estimate_particles(const fsi::Scene& s) {
  ParticleEstimate e;
  const int d = s.dimensions;
  const double dx = s.particle_spacing;
  const auto cells = [&](double length) { return std::max(1.0, std::floor(length / dx + 0.5)); };
  const int default_layers = std::max(1, int(std::ceil(2.0 * s.smoothing_ratio - 1e-9)));
  for (const auto& f : s.fluids) {
    double n = 1;
    for (int k = 0; k < d; ++k) n *= cells(f.box.max[k] - f.box.min[k]);
    e.fluid += n;
  }
  for (const auto& w : s.walls) {
    const double layers = w.layers > 0 ? w.layers : default_layers;
    if (w.kind == fsi::WallSpec::Kind::polyline) {
      double length = 0;
      for (std::size_t i = 0; i + 1 < w.points.size(); ++i)
        length += std::hypot(w.points[i + 1][0] - w.points[i][0], w.points[i + 1][1] - w.points[i][1]);
      if (w.closed && w.points.size() > 2)
        length += std::hypot(w.points.front()[0] - w.points.back()[0], w.points.front()[1] - w.points.back()[1]);
      e.walls += cells(length) * layers * (d == 3 ? cells(w.span[1] - w.span[0]) : 1.0);
      continue;
    }
    double inner = 1, outer = 1;
    for (int k = 0; k < d; ++k) {
      const double n = cells(w.box.max[k] - w.box.min[k]);
      inner *= n;
      outer *= n + 2 * layers;
    }
    e.walls += w.kind == fsi::WallSpec::Kind::container ? outer - inner : inner;
  }
  for (const auto& st : s.structures) {
    double extent[3] = {0, 0, 0};  // a bounding box of the shape
    for (int k = 0; k < 3; ++k) {
      switch (st.shape) {
        case fsi::StructureSpec::Shape::box: extent[k] = st.size[std::size_t(k)]; break;
        case fsi::StructureSpec::Shape::sphere: extent[k] = 2 * st.radius; break;
        case fsi::StructureSpec::Shape::cylinder: extent[k] = std::max(2 * st.radius, st.length); break;
        case fsi::StructureSpec::Shape::mesh: extent[k] = 0; break;  // its size is known once loaded
      }
      extent[k] *= st.scale;
    }
    double n = 1;
    for (int k = 0; k < d; ++k) n *= cells(extent[k]);
    e.structures += n;
  }
  if (!s.transitions.empty()) {
    const double start = e.fluid + e.walls + e.structures;
    e.reserved = s.capacity.max_particles > 0 ? std::max(0.0, double(s.capacity.max_particles) - start)
                                              : (s.capacity.factor - 1.0) * start;
  }
  return e;
}

// Physical memory of this machine [bytes], 0 where unknown.
double physical_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && size > 0 ? double(pages) * double(size) : 0.0;
}

// "4 x 1e+308" (2D) or "4 x 1 x 2" (3D): a box's extents along its axes [m].
std::string extent_text(const fsi::Box& b, int dims) {
  std::ostringstream s;
  s << std::setprecision(6);
  for (int k = 0; k < dims; ++k) s << (k ? " x " : "") << (b.max[k] - b.min[k]);
  return s.str();
}

std::string unit_text(std::string_view unit) { return unit.empty() ? std::string() : " [" + std::string(unit) + "]"; }

std::optional<double> parse_number(const YAML::Node& n) {
  if (!n.IsScalar()) return std::nullopt;
  std::string_view s = n.Scalar();
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);  // from_chars has no '+'
  double x = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

std::optional<long long> parse_integer(const YAML::Node& n) {
  if (!n.IsScalar()) return std::nullopt;
  std::string_view s = n.Scalar();
  if (s.size() > 1 && s[0] == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  long long x = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return x;
}

// What was found instead of what was expected, for the "got ..." end of a message.
std::string describe(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "an empty value";
  if (n.IsMap()) return "a map";
  if (n.IsSequence()) {
    const std::size_t k = n.size();
    return "a list of " + std::to_string(k) + (k == 1 ? " item" : " items");
  }
  const std::string& s = n.Scalar();
  if (s.empty()) return "an empty string";
  if (parse_number(n)) return s;
  return "'" + s + "'";
}

// A value to check: its node, where it is, and how messages name it ("'particle_spacing'",
// "item 2 of 'fluids'").
struct Value {
  YAML::Node node;
  YAML::Mark mark;
  std::string name;
};

struct NumberRule {
  std::string text;  // "a positive number"
  std::function<bool(double)> ok;
};

NumberRule any_number() { return {"a number", [](double) { return true; }}; }
NumberRule positive() { return {"a positive number", [](double x) { return x > 0.0; }}; }
NumberRule non_negative() { return {"a number >= 0", [](double x) { return x >= 0.0; }}; }
NumberRule open_closed(double lo, double hi) {
  return {"a number in (" + fmt(lo) + ", " + fmt(hi) + "]", [lo, hi](double x) { return x > lo && x <= hi; }};
}

class Reader;

// A YAML map with its keys indexed, checked for duplicates and (by check_keys) against the keys
// the schema allows, so that a typo is reported as such instead of as a missing key.
class MapView {
 public:
  struct Entry {
    std::string key;
    YAML::Mark key_mark;
    YAML::Node value;
  };

  // `allowed` empty: any key (a map of names, such as 'materials').
  MapView(const Reader& reader, Value value, std::vector<std::string> allowed, bool check_keys_now = true);

  void check_keys() const;
  bool has(std::string_view key) const { return find(key) != nullptr; }
  std::optional<Value> get(std::string_view key) const;
  Value need(std::string_view key) const;
  YAML::Mark key_mark(std::string_view key) const { return find(key)->key_mark; }
  const Value& value() const { return value_; }
  const std::vector<Entry>& entries() const { return entries_; }
  Value entry_value(const Entry& e, std::string name) const;

 private:
  const Entry* find(std::string_view key) const;

  const Reader& reader_;
  Value value_;
  std::vector<std::string> allowed_;
  std::unordered_map<std::string, std::size_t> index_;  // key -> entry: linear time in the keys
  std::vector<Entry> entries_;
};

class Reader {
 public:
  explicit Reader(std::string file, std::string relative_to = {}, SceneOverrides overrides = {})
      : file_(std::move(file)), relative_to_(std::move(relative_to)), overrides_(overrides) {}

  fsi::Scene read(const std::string& yaml_text);

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) const {
    const int line = mark.is_null() || mark.line < 0 ? 1 : mark.line + 1;
    const int column = mark.is_null() || mark.column < 0 ? 1 : mark.column + 1;
    throw SceneError(file_ + ":" + std::to_string(line) + ":" + std::to_string(column) + ": error: " + message);
  }

  fsi::SourceLocation where(const YAML::Mark& mark) const {
    if (mark.is_null()) return {file_, 0, 0};
    return {file_, mark.line + 1, mark.column + 1};
  }

  // --- values ---------------------------------------------------------------------------------

  double number(const Value& v, const NumberRule& rule, std::string_view unit = {}) const {
    const auto x = parse_number(v.node);
    if (!x || !rule.ok(*x))
      fail(v.mark, v.name + " must be " + rule.text + unit_text(unit) + ", got " + describe(v.node));
    return *x;
  }

  int integer(const Value& v, long long min_value, std::string_view requirement) const {
    const auto x = parse_integer(v.node);
    if (!x || *x < min_value || *x > 1000000)
      fail(v.mark, v.name + " must be " + std::string(requirement) + ", got " + describe(v.node));
    return static_cast<int>(*x);
  }

  bool boolean(const Value& v) const {
    if (v.node.IsScalar()) {
      const std::string s = to_lower(v.node.Scalar());
      if (s == "true" || s == "yes" || s == "on") return true;
      if (s == "false" || s == "no" || s == "off") return false;
    }
    fail(v.mark, v.name + " must be true or false, got " + describe(v.node));
  }

  std::string text(const Value& v, std::string_view what = "a non-empty string") const {
    if (!v.node.IsScalar() || v.node.Scalar().empty())
      fail(v.mark, v.name + " must be " + std::string(what) + ", got " + describe(v.node));
    return v.node.Scalar();
  }

  std::size_t choice(const Value& v, const std::vector<std::string>& options, std::string_view note = {}) const {
    if (v.node.IsScalar()) {
      const auto it = std::find(options.begin(), options.end(), v.node.Scalar());
      if (it != options.end()) return static_cast<std::size_t>(it - options.begin());
    }
    std::string message = v.name + " must be " + choices_text(options) + ", got " + describe(v.node);
    // A note says why the value is wrong; a guess at a near spelling would then only distract.
    if (!note.empty())
      message += " (" + std::string(note) + ")";
    else if (v.node.IsScalar())
      message += did_you_mean(v.node.Scalar(), options);
    fail(v.mark, message);
  }

  std::vector<Value> list(const Value& v) const {
    if (!v.node.IsSequence()) fail(v.mark, v.name + " must be a list, got " + describe(v.node));
    std::vector<Value> items;
    for (std::size_t i = 0; i < v.node.size(); ++i) {
      const YAML::Node item = v.node[i];
      const YAML::Mark mark = item.IsNull() || item.Mark().is_null() ? v.mark : item.Mark();
      items.push_back({item, mark, "item " + std::to_string(i + 1) + " of " + v.name});
    }
    return items;
  }

  // A point or vector: exactly `dims` numbers; 2D points get z = 0.
  Vec3d point(const Value& v, int dims, std::string_view unit) const {
    const std::string shape = dims == 2 ? "[x, y]" : "[x, y, z]";
    if (!v.node.IsSequence() || static_cast<int>(v.node.size()) != dims)
      fail(v.mark, v.name + " must be a list of " + std::to_string(dims) + " numbers " + shape +
                       (unit.empty() ? std::string() : " in " + std::string(unit)) + " in a " + std::to_string(dims) +
                       "D scene, got " + describe(v.node));
    Vec3d p{0, 0, 0};
    for (int k = 0; k < dims; ++k) {
      const YAML::Node c = v.node[static_cast<std::size_t>(k)];
      const YAML::Mark mark = c.IsNull() || c.Mark().is_null() ? v.mark : c.Mark();
      p[static_cast<std::size_t>(k)] =
          number({c, mark, "component " + std::string(kAxisName[k]) + " of " + v.name}, any_number(), unit);
    }
    return p;
  }

  // A vertex of a polygon or polyline: [x, y] in 2D; in 3D [x, z], a point of the cross-section in
  // the vertical x-z plane that 'span' extrudes across y. Stored as (first, second, 0) either way.
  Vec3d section_point(const Value& v, int dims) const {
    if (dims == 2) return point(v, 2, "m");
    if (!v.node.IsSequence() || v.node.size() != 2)
      fail(v.mark, v.name + " must be a list of 2 numbers [x, z] in m (in 3D a polygon or polyline is a cross-section "
                            "in the x-z plane, extruded across y by 'span'), got " + describe(v.node));
    Vec3d p{0, 0, 0};
    for (std::size_t k = 0; k < 2; ++k) {
      const YAML::Node c = v.node[k];
      const YAML::Mark mark = c.IsNull() || c.Mark().is_null() ? v.mark : c.Mark();
      p[k] = number({c, mark, "component " + std::string(k == 0 ? "x" : "z") + " of " + v.name}, any_number(), "m");
    }
    return p;
  }

  // The y extent of an extruded cross-section (3D): [y_min, y_max] with y_min < y_max. `map` holds
  // the shape's keys; `shape` names it in messages. In 2D 'span' is refused, in 3D required.
  std::array<double, 2> span(const MapView& map, int dims, const std::string& shape) const {
    if (dims == 2) {
      if (map.has("span"))
        fail(map.key_mark("span"), "'span' applies only to 3D scenes (the y extent of an extruded " + shape +
                                       "); a 2D " + shape + " is already in the scene's plane");
      return {0, 0};
    }
    if (!map.has("span"))
      fail(map.value().mark, "a 3D " + shape + " is a cross-section in the x-z plane extruded across y: " +
                                 map.value().name + " needs 'span: [y_min, y_max]' [m]");
    const Value sv = map.need("span");
    if (!sv.node.IsSequence() || sv.node.size() != 2)
      fail(sv.mark, "'span' must be a list of 2 numbers [y_min, y_max] in m, got " + describe(sv.node));
    std::array<double, 2> r{};
    for (std::size_t k = 0; k < 2; ++k) {
      const YAML::Node c = sv.node[k];
      const YAML::Mark mark = c.IsNull() || c.Mark().is_null() ? sv.mark : c.Mark();
      r[k] = number({c, mark, std::string(k == 0 ? "y_min" : "y_max") + " of 'span'"}, any_number(), "m");
    }
    if (!(r[0] < r[1]))
      fail(sv.mark, "'span' needs y_min < y_max, got y_min = " + fmt(r[0]) + " and y_max = " + fmt(r[1]));
    return r;
  }

  // A flow direction along an axis: one of -x, +x, -y, +y (, -z, +z).
  fsi::VelocityProfile direction(const Value& v, int dims) const {
    fsi::VelocityProfile p;
    const std::size_t k = choice(v, std::vector<std::string>(kFaceName, kFaceName + 2 * dims));
    p.given = true;
    p.axis = int(k / 2);
    p.sign = k % 2 == 0 ? -1 : +1;
    return p;
  }

  // {direction: +x, profile: uniform | parabolic, mean: U}; without `with_speed` only the direction.
  fsi::VelocityProfile profile(const MapView& m, int dims, bool with_speed) const {
    fsi::VelocityProfile p = direction(m.need("direction"), dims);
    if (with_speed) {
      if (auto pr = m.get("profile")) p.parabolic = choice(*pr, {"uniform", "parabolic"}) == 1;
      p.mean = number(m.need("mean"), non_negative(), "m/s");
    }
    return p;
  }

  fsi::Box box(const Value& v, int dims) const {
    MapView m(*this, v, {"min", "max"});
    fsi::Box b;
    b.min = point(m.need("min"), dims, "m");
    b.max = point(m.need("max"), dims, "m");
    return b;
  }

  void require_ordered(const Value& v, const fsi::Box& b, int dims) const {
    for (int k = 0; k < dims; ++k) {
      if (!(b.min[k] < b.max[k]))
        fail(v.mark, v.name + " needs min < max on every axis, got min " + kAxisName[k] + " = " + fmt(b.min[k]) +
                         " and max " + kAxisName[k] + " = " + fmt(b.max[k]));
    }
  }

  const std::string& file() const { return file_; }

 private:
  void read_numerics(const Value& v, fsi::NumericsSpec& n) const;
  void read_materials(const Value& v, fsi::Scene& scene) const;
  void read_walls(const Value& v, fsi::Scene& scene, std::vector<YAML::Mark>& wall_marks) const;
  void read_fluids(const Value& v, fsi::Scene& scene, const std::vector<YAML::Mark>& wall_marks) const;
  void read_structures(const Value& v, fsi::Scene& scene) const;
  void read_motion(const MapView& m, int dims, fsi::StructureSpec& st) const;
  void read_contact(const Value& v, fsi::ContactMaterialSpec& c, bool rigid_contacts = false) const;
  void read_constraints(const Value& v, fsi::Scene& scene) const;
  fsi::ConstraintEndSpec read_constraint_end(const Value& v, const fsi::Scene& scene) const;
  void read_path(const MapView& m, const fsi::Scene& scene, fsi::StructureSpec& st) const;
  void read_open_boundaries(const Value& v, fsi::Scene& scene) const;
  void read_probes(const Value& v, fsi::Scene& scene) const;
  void read_output(const Value& v, fsi::OutputSpec& out) const;
  void read_transitions(const Value& v, fsi::Scene& scene) const;
  void read_capacity(const Value& v, fsi::CapacitySpec& c) const;

  std::string file_;
  std::string relative_to_;
  SceneOverrides overrides_;  // directory of relative mesh paths; empty: the scene file's
};

// --- MapView ------------------------------------------------------------------------------------

MapView::MapView(const Reader& reader, Value value, std::vector<std::string> allowed, bool check_keys_now)
    : reader_(reader), value_(std::move(value)), allowed_(std::move(allowed)) {
  if (!value_.node.IsMap()) {
    std::string keys = allowed_.empty() ? std::string() : " with keys " + join(allowed_);
    reader_.fail(value_.mark, value_.name + " must be a map" + keys + ", got " + describe(value_.node));
  }
  for (auto it = value_.node.begin(); it != value_.node.end(); ++it) {
    const YAML::Node& k = it->first;
    if (!k.IsScalar())
      reader_.fail(k.Mark(), "keys in " + value_.name + " must be plain names, got " + describe(k));
    const std::string key = k.Scalar();
    if (const Entry* first = find(key))
      reader_.fail(k.Mark(), "duplicate key '" + key + "' in " + value_.name + " (first given at line " +
                                 std::to_string(first->key_mark.line + 1) + ")");
    index_.emplace(key, entries_.size());
    entries_.push_back({key, k.Mark(), it->second});
  }
  if (check_keys_now) check_keys();
}

void MapView::check_keys() const {
  if (allowed_.empty()) return;
  for (const Entry& e : entries_) {
    if (std::find(allowed_.begin(), allowed_.end(), e.key) != allowed_.end()) continue;
    std::string message = "unknown key '" + e.key + "' in " + value_.name;
    const auto guess = closest(e.key, allowed_);
    if (guess)
      message += "; did you mean '" + *guess + "'?";
    else
      message += " (expected one of: " + join(allowed_) + ")";
    reader_.fail(e.key_mark, message);
  }
}

const MapView::Entry* MapView::find(std::string_view key) const {
  const auto it = index_.find(std::string(key));
  return it == index_.end() ? nullptr : &entries_[it->second];
}

Value MapView::entry_value(const Entry& e, std::string name) const {
  // An empty value (`key:` and nothing) has its mark on the next token; point at the key instead.
  const YAML::Mark mark = e.value.IsNull() || e.value.Mark().is_null() ? e.key_mark : e.value.Mark();
  return {e.value, mark, std::move(name)};
}

std::optional<Value> MapView::get(std::string_view key) const {
  const Entry* e = find(key);
  if (!e) return std::nullopt;
  return entry_value(*e, "'" + std::string(key) + "'");
}

Value MapView::need(std::string_view key) const {
  const Entry* e = find(key);
  if (!e) reader_.fail(value_.mark, "missing required key '" + std::string(key) + "' in " + value_.name);
  return entry_value(*e, "'" + std::string(key) + "'");
}

// --- the schema ---------------------------------------------------------------------------------

const std::vector<std::string> kTopKeys = {"name",   "dimensions", "resolution", "time",   "gravity",
                                           "numerics", "materials", "walls",     "structures", "fluids",
                                           "open_boundaries", "probes", "output", "domain", "transitions",
                                           "capacity", "constraints"};

fsi::Scene Reader::read(const std::string& yaml_text) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(yaml_text);
  } catch (const YAML::Exception& e) {
    // yaml-cpp often gives up a line after the mistake; point at the bracket or quote left open.
    if (const auto hint = explain_yaml_syntax_error(yaml_text, e.mark.line, e.mark.column, e.msg)) {
      YAML::Mark m = e.mark;
      m.line = hint->line;
      m.column = hint->column;
      fail(m, "invalid YAML: " + hint->message);
    }
    fail(e.mark, "invalid YAML: " + e.msg);
  }
  if (documents.empty() || (documents.size() == 1 && documents[0].IsNull()))
    fail(YAML::Mark::null_mark(), "the scene file is empty; expected a map with the keys " + join(kTopKeys));
  if (documents.size() > 1)
    fail(documents[1].Mark(), "the scene file holds more than one YAML document (a '---' line); expected one");

  fsi::Scene scene;
  scene.source_file = file_;
  {
    // absolute() of the file first: a bare "scene.yaml" has an empty parent path.
    std::error_code ec;
    const std::filesystem::path base = relative_to_.empty()
                                           ? std::filesystem::absolute(file_, ec).parent_path()
                                           : std::filesystem::absolute(relative_to_, ec);
    scene.base_directory = base.lexically_normal().string();
  }
  try {
    const YAML::Node& doc = documents[0];
    Value root{doc, doc.Mark(), "the scene"};
    if (!doc.IsMap())
      fail(root.mark, "the scene must be a map with the keys " + join(kTopKeys) + ", got " + describe(doc));
    MapView top(*this, root, kTopKeys);

    scene.name = text(top.need("name"));
    {
      const Value v = top.need("dimensions");
      const auto d = parse_integer(v.node);
      if (!d || (*d != 2 && *d != 3)) fail(v.mark, "'dimensions' must be 2 or 3, got " + describe(v.node));
      scene.dimensions = static_cast<int>(*d);
    }
    const int dims = scene.dimensions;
    YAML::Mark spacing_mark;
    {
      MapView res(*this, top.need("resolution"), {"particle_spacing", "smoothing_ratio"});
      spacing_mark = res.need("particle_spacing").mark;
      scene.particle_spacing = number(res.need("particle_spacing"), positive(), "m");
      if (overrides_.spacing) scene.particle_spacing = *overrides_.spacing;
      if (auto v = res.get("smoothing_ratio")) scene.smoothing_ratio = number(*v, open_closed(0.5, 3.0));
    }
    {
      MapView time(*this, top.need("time"), {"end", "cfl"});
      scene.end_time = number(time.need("end"), positive(), "s");
      if (overrides_.end_time) scene.end_time = *overrides_.end_time;
      if (auto v = time.get("cfl")) scene.numerics.cfl = number(*v, open_closed(0.0, 1.0));
    }
    scene.gravity = Vec3d{0, 0, 0};
    scene.gravity[static_cast<std::size_t>(dims - 1)] = -9.81;
    if (auto v = top.get("gravity")) scene.gravity = point(*v, dims, "m/s^2");
    if (auto v = top.get("numerics")) read_numerics(*v, scene.numerics);
    read_materials(top.need("materials"), scene);
    if (auto v = top.get("domain")) {
      MapView dm(*this, *v, {"min", "max", "periodic"});
      fsi::Box b;
      b.min = point(dm.need("min"), dims, "m");
      b.max = point(dm.need("max"), dims, "m");
      require_ordered(*v, b, dims);
      scene.domain = b;
      if (auto pv = dm.get("periodic")) {
        // Particles leaving through one face of a periodic axis come back through the other.
        for (const Value& a : list(*pv)) {
          const std::size_t k = choice(a, std::vector<std::string>(kAxisName, kAxisName + dims));
          scene.periodic[k] = true;
        }
      }
    }
    std::vector<YAML::Mark> wall_marks;
    if (auto v = top.get("walls")) read_walls(*v, scene, wall_marks);
    if (auto v = top.get("structures")) read_structures(*v, scene);
    if (auto v = top.get("constraints")) read_constraints(*v, scene);
    if (auto v = top.get("open_boundaries")) read_open_boundaries(*v, scene);
    read_fluids(top.need("fluids"), scene, wall_marks);
    if (auto v = top.get("probes")) read_probes(*v, scene);
    if (auto v = top.get("transitions")) read_transitions(*v, scene);
    if (auto v = top.get("capacity")) {
      if (!top.has("transitions"))
        fail(top.key_mark("capacity"), "'capacity' reserves room for particles that transitions create, but the "
                                       "scene has no 'transitions'");
      read_capacity(*v, scene.capacity);
    }
    {
      // Every particle the scene would build, before anything is allocated (issue #27 item 3): a
      // spacing that implies 1e12 of them once ended in std::bad_alloc with no location.
      const ParticleEstimate e = estimate_particles(scene);
      const double memory = physical_memory_bytes();
      if (!(e.total() <= kMaxParticles) || (memory > 0 && e.total() * kMinBytesPerParticle > memory)) {
        std::ostringstream os;
        os << std::setprecision(3) << "at particle_spacing = " << fmt(scene.particle_spacing) << " m the scene would hold about "
           << e.total() << " particles (fluid " << e.fluid << ", walls " << e.walls << ", structures " << e.structures;
        if (e.reserved > 0) os << ", reserved for daughters " << e.reserved;
        os << "), ";
        if (!(e.total() <= kMaxParticles))
          os << "more than the 4294967295 (2^32 - 1) a scene can hold";
        else
          os << e.total() * kMinBytesPerParticle / 1073741824.0 << " GiB at " << kMinBytesPerParticle
             << " bytes a particle or more, more than this machine's " << memory / 1073741824.0 << " GiB";
        os << "; use a larger spacing or a smaller scene";
        fail(spacing_mark, os.str());
      }
    }
    const auto output = top.get("output");
    if (output) read_output(*output, scene.output);
    if (overrides_.checkpoint_every) scene.output.checkpoint_every = *overrides_.checkpoint_every;
    if (const std::string problem = schedule_problem(scene.end_time, scene.output); !problem.empty())
      fail(output ? output->mark : top.key_mark("time"), problem);
  } catch (const YAML::Exception& e) {
    // Walking a parsed tree should not throw; if yaml-cpp does, keep the promised message form.
    fail(e.mark, "cannot read the scene: " + e.msg);
  }
  return scene;
}

void Reader::read_numerics(const Value& v, fsi::NumericsSpec& n) const {
  MapView m(*this, v, {"kernel", "density_diffusion", "viscosity", "boundary", "shifting", "min_time_step",
                                "max_density_variation", "interface_correction", "split_relaxation",
                                "max_fluid_behind_walls"});
  // Density diffusion between materials: the seed paper's ghost density (eq. 3), or none.
  if (auto ic = m.get("interface_correction"))
    n.interface_correction = choice(*ic, {"ghost_density", "none"}) == 0;
  // Jacobi steps of the relaxation after each split (sph/splitting.hpp); 0 switches it off.
  if (auto sr = m.get("split_relaxation")) {
    n.split_relaxation = integer(*sr, 0, "an integer from 0 to 100 (relaxation steps after a split)");
    if (n.split_relaxation > 100)
      fail(sr->mark, "'split_relaxation' must be an integer from 0 to 100 (relaxation steps after a split), got " +
                         std::to_string(n.split_relaxation));
  }
  if (auto bv = m.get("boundary")) {
    MapView b(*this, *bv, {"type", "velocity", "impermeable", "wall_function"});
    n.boundary = choice(b.need("type"), {"dbc", "mdbc"}) == 0 ? fsi::BoundaryKind::dbc : fsi::BoundaryKind::mdbc;
    if (auto vel = b.get("velocity")) n.no_slip = choice(*vel, {"no_slip", "wall"}) == 0;
    if (auto imp = b.get("impermeable")) n.impermeable = boolean(*imp);
    // `wall_function: {roughness: k_s}`: the log law's wall shear (docs/choices.md, "Wall friction").
    if (auto wf = b.get("wall_function")) {
      MapView w(*this, *wf, {"roughness"});
      n.wall_function = true;
      n.wall_function_where = where(wf->mark);
      if (auto ks = w.get("roughness")) n.wall_roughness = number(*ks, non_negative(), "m");
    }
  }
  if (auto k = m.get("kernel"))
    n.kernel = choice(*k, {"wendland_c2", "cubic_spline"}) == 0 ? sph::KernelKind::wendland_c2
                                                                 : sph::KernelKind::cubic_spline;
  if (auto dv = m.get("density_diffusion")) {
    MapView d(*this, *dv, {"type", "delta"});
    if (auto t = d.get("type"))
      n.diffusion = static_cast<fsi::DiffusionKind>(choice(*t, {"none", "molteni", "antuono", "fourtakas"}));
    if (auto delta = d.get("delta")) {
      if (n.diffusion == fsi::DiffusionKind::none)
        fail(d.key_mark("delta"), "'delta' has no effect when the density diffusion 'type' is 'none'; remove it");
      n.diffusion_delta = number(*delta, non_negative());
    }
  }
  if (auto vv = m.get("viscosity")) {
    MapView visc(*this, *vv, {"type", "alpha", "integration", "stress", "walls"});
    if (auto t = visc.get("type"))
      n.viscosity = choice(*t, {"artificial", "laminar"}) == 0 ? fsi::ViscosityKind::artificial
                                                               : fsi::ViscosityKind::laminar;
    if (auto alpha = visc.get("alpha")) {
      if (n.viscosity == fsi::ViscosityKind::laminar)
        fail(visc.key_mark("alpha"),
             "'alpha' applies only to 'artificial' viscosity; 'laminar' uses each material's 'viscosity'");
      n.artificial_viscosity = number(*alpha, non_negative());
    }
    // `walls: normal`: with walls and structures the artificial viscosity sees only the approach
    // along the wall's normal (docs/choices.md, "Artificial viscosity at walls"); `pair`: the pair's.
    if (auto wv = visc.get("walls")) {
      if (n.viscosity == fsi::ViscosityKind::laminar)
        fail(visc.key_mark("walls"), "'walls' applies only to 'artificial' viscosity");
      n.artificial_wall_normal = choice(*wv, {"normal", "pair"}) == 0;
    }
    if (auto integ = visc.get("integration")) {
      if (n.viscosity != fsi::ViscosityKind::laminar)
        fail(visc.key_mark("integration"), "'integration' applies only to 'laminar' viscosity");
      const int k = choice(*integ, {"auto", "explicit", "implicit"});
      n.viscous_integration = k == 0 ? fsi::ViscousIntegration::automatic
                                     : (k == 1 ? fsi::ViscousIntegration::explicit_ : fsi::ViscousIntegration::implicit);
    }
    if (auto st = visc.get("stress")) {
      if (n.viscosity != fsi::ViscosityKind::laminar)
        fail(visc.key_mark("stress"), "'stress' applies only to 'laminar' viscosity");
      const fsi::ViscousStress kinds[] = {fsi::ViscousStress::automatic, fsi::ViscousStress::full,
                                          fsi::ViscousStress::laplacian, fsi::ViscousStress::central};
      n.viscous_stress = kinds[choice(*st, {"auto", "full", "laplacian", "central"})];
    }
  }
  if (auto sv = m.get("shifting")) {
    // Particle shifting (Lind et al. 2012; Skillen et al. 2013): A of about 2 keeps the particles
    // evenly spread where the flow pulls them apart (wakes, internal flows).
    MapView s(*this, *sv, {"coefficient", "free_surface_threshold"});
    n.shifting_coefficient = number(s.need("coefficient"), positive());
    if (auto t = s.get("free_surface_threshold")) n.shifting_surface_threshold = number(*t, non_negative());
  }
  if (auto t = m.get("min_time_step")) n.min_time_step = number(*t, positive(), "s");
  // |rho / rho0 - 1| above this stops the run as a blow-up.
  if (auto t = m.get("max_density_variation")) n.density_ratio_limit = number(*t, positive());
  // More fluid particles than this behind a wall or structure surface at an output stops the run.
  if (auto t = m.get("max_fluid_behind_walls")) {
    n.max_fluid_behind_walls = std::uint64_t(integer(*t, 0, "a whole number of particles from 0 to 1000000"));
    n.max_fluid_behind_walls_where = where(t->mark);
  }
}

// transitions: [{from, to, when: {effective_shear_stress_above}, where, split, levels}]
void Reader::read_transitions(const Value& v, fsi::Scene& scene) const {
  std::vector<std::string> names;
  for (const auto& m : scene.materials) names.push_back(m.name);
  const auto material = [&](const Value& mv, const std::string& item) -> const fsi::MaterialSpec& {
    const std::string name = text(mv);
    for (const auto& m : scene.materials)
      if (m.name == name) return m;
    fail(mv.mark, "unknown material '" + name + "' in " + item + did_you_mean(name, names) +
                      " (defined materials: " + join(names) + ")");
  };
  const std::vector<Value> items = list(v);
  if (items.empty()) fail(v.mark, "'transitions' must list at least one transition (or leave the key out)");
  if (items.size() > 4) fail(items[4].mark, "at most 4 transitions are supported");
  for (const Value& item : items) {
    MapView m(*this, item, {"from", "to", "when", "where", "split", "levels"});
    fsi::TransitionSpec t;
    t.where = where(item.mark);
    const Value fv = m.need("from"), tv = m.need("to");
    const fsi::MaterialSpec& from = material(fv, item.name);
    const fsi::MaterialSpec& to = material(tv, item.name);
    t.from = from.name;
    t.to = to.name;
    if (t.from == t.to) fail(tv.mark, "'to' must name another material than 'from' ('" + t.from + "')");
    if (from.density != to.density)
      fail(tv.mark, "material '" + to.name + "' has density " + fmt(to.density) + " kg/m^3 but '" +
                        from.name + "' has " + fmt(from.density) +
                        " kg/m^3: splitting conserves density, so a transition needs equal reference densities");
    for (const auto& other : scene.transitions)
      if (other.from == t.from) fail(fv.mark, "material '" + t.from + "' already has a transition");
    MapView when(*this, m.need("when"), {"effective_shear_stress_above"});
    t.shear_stress_threshold = number(when.need("effective_shear_stress_above"), non_negative(), "Pa");
    if (auto w = m.get("where")) t.interface_only = choice(*w, {"interface", "anywhere"}) == 0;
    if (auto sp = m.get("split")) choice(*sp, {"cubic"}, "2^D daughters at the sub-cube centres");
    if (auto lv = m.get("levels")) t.levels = integer(*lv, 1, "an integer from 1 to 4 (times a particle may split)");
    if (t.levels > 4) fail(m.get("levels")->mark, "'levels' must be an integer from 1 to 4 (times a particle may split), got " + std::to_string(t.levels));
    scene.transitions.push_back(t);
  }
}

// capacity: {max_particles: N} or {factor: F}, on_full: warn | error
void Reader::read_capacity(const Value& v, fsi::CapacitySpec& c) const {
  MapView m(*this, v, {"max_particles", "factor", "on_full"});
  c.where = where(v.mark);
  if (m.has("max_particles") && m.has("factor"))
    fail(m.key_mark("factor"), "'capacity' takes 'max_particles' or 'factor', not both");
  if (auto mp = m.get("max_particles")) c.max_particles = std::size_t(integer(*mp, 1, "a whole number of particles >= 1"));
  if (auto f = m.get("factor")) c.factor = number(*f, {"a number >= 1", [](double x) { return x >= 1.0; }});
  if (auto of = m.get("on_full")) c.error_when_full = choice(*of, {"warn", "error"}) == 1;
}

void Reader::read_materials(const Value& v, fsi::Scene& scene) const {
  MapView all(*this, v, {});
  if (all.entries().empty())
    fail(v.mark, "'materials' must define at least one material, e.g. 'water: {density: 1000}'");
  for (const auto& e : all.entries()) {
    if (e.key.empty()) fail(e.key_mark, "a material needs a non-empty name");
    const Value item = all.entry_value(e, "material '" + e.key + "'");
    fsi::MaterialSpec mat;
    mat.name = e.key;
    mat.where = where(e.key_mark);
    // The model first: which keys are allowed depends on it.
    std::size_t model = 0;
    std::optional<Value> model_value;
    if (item.node.IsMap()) {
      MapView peek(*this, item, {}, false);
      if ((model_value = peek.get("model")))
        model = choice(*model_value, {"newtonian", "bingham", "herschel_bulkley"});
    }
    mat.model = model == 0 ? "newtonian" : model == 1 ? "bingham" : "herschel_bulkley";
    std::vector<std::string> keys = {"model", "density", "viscosity", "sound_speed", "gamma", "background_pressure"};
    if (model == 1) keys.insert(keys.end(), {"yield_stress", "papanastasiou_exponent", "max_viscosity"});
    if (model == 2) {
      keys.erase(std::find(keys.begin(), keys.end(), "viscosity"));
      keys.insert(keys.end(), {"yield_stress", "consistency", "flow_index", "papanastasiou_exponent", "max_viscosity"});
    }
    MapView m(*this, item, keys);
    mat.density = number(m.need("density"), positive(), "kg/m^3");
    if (model == 1) {
      mat.viscosity = number(m.need("viscosity"), non_negative(), "Pa s");  // plastic viscosity mu_B
    } else if (auto x = m.get("viscosity")) {
      mat.viscosity = number(*x, non_negative(), "Pa s");
    }
    if (model != 0) {
      mat.yield_stress = number(m.need("yield_stress"), non_negative(), "Pa");
      if (model == 2) {
        mat.consistency = number(m.need("consistency"), non_negative(), "Pa s^n");
        mat.flow_index = number(m.need("flow_index"), positive());
        mat.viscosity = 0;
      }
      if (auto x = m.get("papanastasiou_exponent")) {
        mat.papanastasiou_exponent = number(*x, positive(), "s");
      } else if (mat.yield_stress > 0) {
        fail(m.value().mark, "material '" + e.key + "' has a yield stress and needs 'papanastasiou_exponent' m [s] "
                             "(the regularisation mu_eff = tau_y (1 - exp(-m gamma_dot)) / gamma_dot; m of 100-1000 s "
                             "is typical)");
      }
      if (auto x = m.get("max_viscosity")) mat.max_viscosity = number(*x, positive(), "Pa s");
      if (scene.numerics.viscosity != fsi::ViscosityKind::laminar)
        fail(model_value->mark, "material model '" + mat.model + "' needs the laminar viscosity term: add "
                                "'viscosity: {type: laminar}' under 'numerics'");
    }
    if (auto x = m.get("sound_speed")) mat.sound_speed = number(*x, positive(), "m/s");
    if (auto x = m.get("gamma")) mat.gamma = number(*x, positive());
    if (auto x = m.get("background_pressure")) mat.background_pressure = number(*x, any_number(), "Pa");
    scene.materials.push_back(mat);
  }
}

void Reader::read_walls(const Value& v, fsi::Scene& scene, std::vector<YAML::Mark>& wall_marks) const {
  const int dims = scene.dimensions;
  const std::vector<std::string> shapes = {"box", "solid_box", "polyline"};
  for (const Value& item : list(v)) {
    MapView m(*this, item, {"box", "solid_box", "polyline", "open", "layers", "slip"});
    std::vector<std::string> present;
    for (const auto& s : shapes)
      if (m.has(s)) present.push_back(s);
    if (present.empty())
      fail(item.mark, item.name + " needs exactly one of 'box' (a container), 'solid_box' (an obstacle) or "
                                  "'polyline', found none");
    if (present.size() > 1)
      fail(m.key_mark(present[1]), item.name + " has both '" + present[0] + "' and '" + present[1] +
                                       "'; give exactly one wall shape per item");
    fsi::WallSpec wall;
    wall.where = where(item.mark);
    const std::string& shape = present[0];
    if (m.has("open") && shape != "box")
      fail(m.key_mark("open"), "'open' applies only to a container ('box') wall, not to a '" + shape + "'");
    if (shape == "box" || shape == "solid_box") {
      wall.kind = shape == "box" ? fsi::WallSpec::Kind::container : fsi::WallSpec::Kind::solid_box;
      const Value bv = m.need(shape);
      wall.box = box(bv, dims);
      require_ordered(bv, wall.box, dims);
    } else {
      wall.kind = fsi::WallSpec::Kind::polyline;
      MapView pl(*this, m.need("polyline"), {"points", "closed", "side", "span"});
      wall.span = span(pl, dims, "polyline");
      if (auto c = pl.get("closed")) wall.closed = boolean(*c);
      if (auto s = pl.get("side")) wall.side = choice(*s, {"right", "left"}) == 0 ? -1 : +1;
      const Value pv = pl.need("points");
      const std::vector<Value> points = list(pv);
      const std::size_t needed = wall.closed ? 3 : 2;
      if (points.size() < needed)
        fail(pv.mark, "'points' of a " + std::string(wall.closed ? "closed " : "") + "polyline needs at least " +
                          std::to_string(needed) + " points, got " + describe(pv.node));
      for (std::size_t i = 0; i < points.size(); ++i) {
        Value p = points[i];
        p.name = "point " + std::to_string(i + 1) + " of 'points'";
        wall.points.push_back(section_point(p, dims));
        if (i > 0 && wall.points[i] == wall.points[i - 1])
          fail(p.mark, p.name + " repeats the point before it; a segment needs two distinct points");
      }
    }
    if (auto o = m.get("open")) {
      std::vector<std::string> faces(kFaceName, kFaceName + 2 * dims);
      for (const Value& f : list(*o)) {
        Value face = f;
        face.name = "a face in 'open'";
        const bool z_in_2d = dims == 2 && f.node.IsScalar() && (f.node.Scalar() == "-z" || f.node.Scalar() == "+z");
        const std::size_t k = choice(face, faces, z_in_2d ? "a 2D scene has no z faces" : "");
        if (wall.open[k]) fail(f.mark, "face '" + faces[k] + "' is listed twice in 'open'");
        wall.open[k] = true;
      }
    }
    if (auto l = m.get("layers")) wall.layers = integer(*l, 1, "an integer >= 1");
    if (auto sl = m.get("slip")) {
      wall.free_slip = choice(*sl, {"no_slip", "free"}) == 1;
      if (wall.free_slip && scene.numerics.viscosity != fsi::ViscosityKind::laminar)
        fail(sl->mark, "'slip: free' acts on the laminar viscosity term; this scene uses artificial viscosity");
    }
    scene.walls.push_back(wall);
    wall_marks.push_back(item.mark);
  }
}

void Reader::read_fluids(const Value& v, fsi::Scene& scene, const std::vector<YAML::Mark>& wall_marks) const {
  double fluid_sites = 0;  // lattice sites over the blocks' bounding boxes so far
  const int dims = scene.dimensions;
  const double dx = scene.particle_spacing;
  const double tol = 1e-9 * dx;
  std::vector<std::string> material_names;
  for (const auto& m : scene.materials) material_names.push_back(m.name);

  const std::vector<Value> items = list(v);
  if (items.empty()) fail(v.mark, "'fluids' must list at least one fluid block");
  for (const Value& item : items) {
    MapView m(*this, item, {"material", "box", "polygon", "span", "initial_velocity"});
    fsi::FluidBlock block;
    block.where = where(item.mark);
    const Value mv = m.need("material");
    block.material = text(mv);
    if (std::find(material_names.begin(), material_names.end(), block.material) == material_names.end())
      fail(mv.mark, "unknown material '" + block.material + "' in " + item.name +
                        did_you_mean(block.material, material_names) + " (defined materials: " +
                        join(material_names) + ")");
    if (m.has("box") && m.has("polygon"))
      fail(m.key_mark("polygon"), "a fluid block has both 'box' and 'polygon'; give one shape");
    if (m.has("span") && !m.has("polygon"))
      fail(m.key_mark("span"), "'span' applies only to a fluid 'polygon' (the y extent of its extrusion in 3D)");
    if (auto pv = m.get("polygon")) {
      // A region bounded by a polygon (for example a slide on a slope); in 3D a cross-section in
      // the x-z plane extruded across y over 'span'. Checked below as its bounding box.
      block.span = span(m, dims, "polygon");
      const std::vector<Value> pts = list(*pv);
      if (pts.size() < 3) fail(pv->mark, "a fluid 'polygon' needs at least 3 points, got " + std::to_string(pts.size()));
      const std::size_t v = dims == 3 ? 2 : 1;  // the box axis of the section's second coordinate
      fsi::Box bb{{1e300, 1e300, 0}, {-1e300, -1e300, 0}};
      if (dims == 3) bb = {{1e300, block.span[0], 1e300}, {-1e300, block.span[1], -1e300}};
      for (const Value& q : pts) {
        block.polygon.push_back(section_point(q, dims));
        const Vec3d& p = block.polygon.back();
        bb.min[0] = std::min(bb.min[0], p[0]);
        bb.max[0] = std::max(bb.max[0], p[0]);
        bb.min[v] = std::min(bb.min[v], p[1]);
        bb.max[v] = std::max(bb.max[v], p[1]);
      }
      block.box = bb;
    }
    const Value bv = block.polygon.empty() ? m.need("box") : *m.get("polygon");
    if (block.polygon.empty()) block.box = box(bv, dims);
    const fsi::Box& b = block.box;
    for (int k = 0; k < dims; ++k) {
      if (b.min[k] > b.max[k]) require_ordered(bv, b, dims);
      if (b.min[k] == b.max[k])
        fail(bv.mark, "empty fluid region: the fluid 'box' has zero extent along " + std::string(kAxisName[k]) +
                          " (min = max = " + fmt(b.min[k]) + ")");
    }
    for (int k = 0; k < dims; ++k) {
      const double extent = b.max[k] - b.min[k];
      if (extent < dx - tol)
        fail(bv.mark, "the fluid 'box' is " + fmt(extent) + " m wide along " + kAxisName[k] +
                          ", less than particle_spacing = " + fmt(dx) +
                          " m, so it would hold fewer than one particle per axis");
    }
    {
      // The lattice over the block's bounding box is what building the particles walks: bound it
      // before anything loops over it (a vertex at 1e308 once made 'turbid check' spin for minutes).
      // Particle ids are 32-bit, so no scene can hold more than 2^32 - 1 particles in all.
      double sites = 1;
      for (int k = 0; k < dims; ++k) sites *= std::floor((b.max[k] - b.min[k]) / dx) + 1;
      fluid_sites += sites;
      const double memory = physical_memory_bytes();
      const bool too_many = !(fluid_sites <= kMaxParticles);
      if (too_many || (memory > 0 && fluid_sites * kMinBytesPerParticle > memory)) {
        std::ostringstream os;
        os << std::setprecision(3);
        if (std::isfinite(fluid_sites)) os << "about " << fluid_sites;
        else os << "more than 1e308";
        os << " particles at particle_spacing = " << fmt(dx) << " m"
           << (scene.fluids.empty() ? "" : " with the blocks before it") << ", more than ";
        if (too_many) os << "the 4294967295 (2^32 - 1) a scene can hold";
        else os << "this machine's memory holds (" << fluid_sites * kMinBytesPerParticle / 1073741824.0 << " GiB at "
                << kMinBytesPerParticle << " bytes a particle or more, against " << memory / 1073741824.0 << " GiB)";
        fail(bv.mark, "the fluid " + std::string(block.polygon.empty() ? "'box'" : "'polygon'") + " spans " +
                          extent_text(b, dims) + " m: " + os.str() + "; check the coordinates or the spacing");
      }
    }
    for (std::size_t w = 0; w < scene.walls.size(); ++w) {
      const fsi::WallSpec& wall = scene.walls[w];
      if (wall.kind == fsi::WallSpec::Kind::polyline) continue;
      const fsi::Box& c = wall.box;
      bool overlaps = true;
      for (int k = 0; k < dims; ++k) overlaps = overlaps && b.min[k] < c.max[k] - tol && c.min[k] < b.max[k] - tol;
      if (!overlaps) continue;
      const std::string wall_name = "item " + std::to_string(w + 1) + " of 'walls' (line " +
                                    std::to_string(wall_marks[w].line + 1) + ")";
      if (wall.kind == fsi::WallSpec::Kind::solid_box)
        fail(bv.mark, "the fluid 'box' overlaps the 'solid_box' of " + wall_name +
                          "; fluid and wall particles would fill the same space");
      // A container: fluid that reaches into it must stay inside, except through an open face.
      for (int k = 0; k < dims; ++k) {
        const std::string axis = kAxisName[k];
        if (!wall.open[2 * k] && b.min[k] < c.min[k] - tol)
          fail(bv.mark, "the fluid 'box' pokes out of the container 'box' of " + wall_name + " through its -" + axis +
                            " face (fluid min " + axis + " = " + fmt(b.min[k]) + " < container min " + axis + " = " +
                            fmt(c.min[k]) + "); a fluid block must lie inside the container");
        if (!wall.open[2 * k + 1] && b.max[k] > c.max[k] + tol)
          fail(bv.mark, "the fluid 'box' pokes out of the container 'box' of " + wall_name + " through its +" + axis +
                            " face (fluid max " + axis + " = " + fmt(b.max[k]) + " > container max " + axis + " = " +
                            fmt(c.max[k]) + "); a fluid block must lie inside the container");
      }
    }
    if (scene.domain) {
      const fsi::Box& d = *scene.domain;
      for (int k = 0; k < dims; ++k)
        if (b.min[k] < d.min[k] - tol || b.max[k] > d.max[k] + tol)
          fail(bv.mark, std::string("the fluid 'box' reaches outside 'domain' along ") + kAxisName[k] + " (fluid " +
                            fmt(b.min[k]) + " to " + fmt(b.max[k]) + ", domain " + fmt(d.min[k]) + " to " +
                            fmt(d.max[k]) + "); its particles would be removed at the start");
    }
    if (auto iv = m.get("initial_velocity")) {
      MapView pv(*this, *iv, {"direction", "profile", "mean"});
      block.initial_velocity = profile(pv, dims, true);
    }
    scene.fluids.push_back(block);
  }
}

void Reader::read_structures(const Value& v, fsi::Scene& scene) const {
  const int dims = scene.dimensions;
  const std::vector<std::string> shapes = {"box", "sphere", "cylinder", "mesh"};
  std::map<std::string, int> first_line;
  for (const Value& item : list(v)) {
    MapView m(*this, item,
              {"name", "box", "sphere", "cylinder", "mesh", "position", "rotation", "scale", "layers",
               "reference_point", "coefficients", "motion", "density", "mass", "centre_of_mass", "inertia", "lock",
               "contact", "path"});
    fsi::StructureSpec st;
    st.where = where(item.mark);
    const Value nv = m.need("name");
    st.name = text(nv);
    if (st.name.find_first_of(",\"\n\r ") != std::string::npos)
      fail(nv.mark, "structure name '" + st.name + "' must not contain spaces, commas, quotes or line breaks (it "
                        "names the columns of forces.csv); use letters, digits, '_' or '-'");
    if (const auto it = first_line.find(st.name); it != first_line.end())
      fail(nv.mark, "duplicate structure name '" + st.name + "' (first used at line " + std::to_string(it->second) +
                        "); structure names must be unique");
    first_line[st.name] = nv.mark.line + 1;
    if (scene.structures.size() >= std::size_t(sph::kMaxBodies))
      fail(item.mark, "at most " + std::to_string(sph::kMaxBodies) + " structures are supported");

    std::vector<std::string> present;
    for (const auto& sh : shapes)
      if (m.has(sh)) present.push_back(sh);
    if (present.empty())
      fail(item.mark, item.name + " needs exactly one shape: 'box', 'sphere', 'cylinder' or 'mesh', found none");
    if (present.size() > 1)
      fail(m.key_mark(present[1]), item.name + " has both '" + present[0] + "' and '" + present[1] +
                                       "'; give exactly one shape per structure");
    const std::string& shape = present[0];
    const Value sv = m.need(shape);
    if (shape == "box") {
      st.shape = fsi::StructureSpec::Shape::box;
      MapView b(*this, sv, {"size"});
      const Value size = b.need("size");
      st.size = point(size, dims, "m");
      for (int k = 0; k < dims; ++k)
        if (!(st.size[std::size_t(k)] > 0))
          fail(size.mark, "every component of 'size' must be positive [m], got " + describe(size.node));
    } else if (shape == "sphere") {
      st.shape = fsi::StructureSpec::Shape::sphere;
      MapView b(*this, sv, {"radius"});
      st.radius = number(b.need("radius"), positive(), "m");
    } else if (shape == "cylinder") {
      st.shape = fsi::StructureSpec::Shape::cylinder;
      MapView b(*this, sv, dims == 3 ? std::vector<std::string>{"radius", "length"} : std::vector<std::string>{"radius"},
                false);
      if (dims == 2 && b.has("length"))
        fail(b.key_mark("length"), "a 2D cylinder is a circle: 'length' does not apply (the scene is per metre of depth)");
      b.check_keys();
      st.radius = number(b.need("radius"), positive(), "m");
      if (dims == 3) st.length = number(b.need("length"), positive(), "m");
    } else {
      st.shape = fsi::StructureSpec::Shape::mesh;
      MapView b(*this, sv, {"file"});
      const Value fv = b.need("file");
      st.file = text(fv, "a file name (STL, OBJ or PLY)");
      std::filesystem::path path(st.file);
      if (path.is_relative()) path = std::filesystem::path(scene.base_directory) / path;
      st.resolved_file = path.lexically_normal().string();
      std::error_code ec;
      if (!std::filesystem::is_regular_file(st.resolved_file, ec))
        fail(fv.mark, "mesh file '" + st.file + "' not found (looked for " + st.resolved_file +
                          "; relative paths are relative to the scene file)");
    }
    if (auto x = m.get("position")) st.position = point(*x, dims, "m");
    if (auto x = m.get("rotation")) {
      if (dims == 2) {
        st.rotation_deg[2] = number(*x, any_number(), "deg");
      } else {
        st.rotation_deg = point(*x, 3, "deg");
      }
    }
    if (auto x = m.get("scale")) st.scale = number(*x, positive());
    if (auto x = m.get("layers")) st.layers = integer(*x, 1, "an integer >= 1");
    st.reference_point = st.position;
    if (auto x = m.get("reference_point")) st.reference_point = point(*x, dims, "m");
    read_motion(m, dims, st);
    if (auto cv = m.get("contact")) read_contact(*cv, st.contact, st.motion == fsi::StructureSpec::Motion::bullet);
    read_path(m, scene, st);
    if (auto cv = m.get("coefficients")) {
      MapView c(*this, *cv, {"flow_direction", "lift_direction", "velocity", "density", "length", "area"}, false);
      if (dims == 2 && c.has("area"))
        fail(c.key_mark("area"), "'area' applies to 3D scenes; in 2D the coefficients use 'length' (per metre of depth)");
      c.check_keys();
      st.has_coefficients = true;
      auto unit_vector = [&](const Value& val) {
        Vec3d d = point(val, dims, "");
        const double n = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (!(n > 0)) fail(val.mark, val.name + " must not be the zero vector");
        for (auto& x : d) x /= n;
        return d;
      };
      const Value fd = c.need("flow_direction");
      st.flow_direction = unit_vector(fd);
      if (auto l = c.get("lift_direction")) {
        st.lift_direction = unit_vector(*l);
      } else if (dims == 2) {
        st.lift_direction = {-st.flow_direction[1], st.flow_direction[0], 0};  // +90 degrees in the plane
      } else {
        fail(cv->mark, "'coefficients' in a 3D scene needs 'lift_direction' (a unit vector perpendicular to "
                       "'flow_direction')");
      }
      const double dot = st.flow_direction[0] * st.lift_direction[0] + st.flow_direction[1] * st.lift_direction[1] +
                         st.flow_direction[2] * st.lift_direction[2];
      if (std::abs(dot) > 1e-6)
        fail(c.key_mark(c.has("lift_direction") ? "lift_direction" : "flow_direction"),
             "'lift_direction' must be perpendicular to 'flow_direction' (their dot product is " + fmt(dot) + ")");
      st.reference_velocity = number(c.need("velocity"), positive(), "m/s");
      st.reference_density = number(c.need("density"), positive(), "kg/m^3");
      st.reference_length = number(c.need("length"), positive(), "m");
      if (dims == 3) st.reference_area = number(c.need("area"), positive(), "m^2");
    }
    scene.structures.push_back(st);
  }
}

// motion: fixed | free | bullet (refused with a clear message when this build has no Bullet)
// (| prescribed, refused until it exists) and a free or bullet body's mass properties and locks. Keys that only a free body uses are refused on a fixed one, so that a
// forgotten 'motion: free' does not pass silently.
void Reader::read_motion(const MapView& m, int dims, fsi::StructureSpec& st) const {
  const std::vector<std::string> body_keys = {"density", "mass", "centre_of_mass", "inertia", "lock"};
  if (auto mv = m.get("motion")) {
    const std::size_t k = choice(*mv, {"fixed", "free", "prescribed", "bullet"});
    if (k == 2) st.motion = fsi::StructureSpec::Motion::prescribed;
    if (k == 3 && !fsi::bullet_available()) fail(mv->mark, std::string("'motion: bullet': ") + fsi::kNoBulletMessage);
    if (k == 1) st.motion = fsi::StructureSpec::Motion::free;
    if (k == 3) st.motion = fsi::StructureSpec::Motion::bullet;
  }
  if (st.motion == fsi::StructureSpec::Motion::fixed) {
    for (const auto& key : body_keys)
      if (m.has(key))
        fail(m.key_mark(key), "'" + key + "' applies to a moving structure; structure '" + st.name +
                                  "' is fixed (add 'motion: free')");
    return;
  }
  if (st.motion == fsi::StructureSpec::Motion::prescribed) {
    for (const auto& key : body_keys)
      if (m.has(key))
        fail(m.key_mark(key), "'" + key + "' applies to a free structure; structure '" + st.name +
                                  "' is prescribed: it follows its 'path' whatever its mass");
    return;
  }
  const std::string moving = st.motion == fsi::StructureSpec::Motion::bullet ? "bullet" : "free";
  if (m.has("reference_point"))
    fail(m.key_mark("reference_point"), "a " + moving + " structure's torques are about its centre of mass, which "
                                        "moves with it: 'reference_point' does not apply to 'motion: " + moving + "'");
  const bool has_density = m.has("density"), has_mass = m.has("mass");
  if (has_density && has_mass)
    fail(m.key_mark("mass"), "give either 'density' or 'mass' for " + moving + " structure '" + st.name + "', not both");
  if (!has_density && !has_mass)
    fail(m.key_mark("motion"), moving + " structure '" + st.name + "' needs 'density' [kg/m^3] (mass, centre and inertia "
                               "from its shape) or 'mass' [" + std::string(dims == 2 ? "kg/m" : "kg") + "]");
  if (has_density) st.density = number(m.need("density"), positive(), "kg/m^3");
  if (has_mass) st.mass = number(m.need("mass"), positive(), dims == 2 ? "kg/m" : "kg");
  if (auto c = m.get("centre_of_mass")) {
    st.has_centre_of_mass = true;
    st.centre_of_mass = point(*c, dims, "m");
  }
  if (auto iv = m.get("inertia")) {
    st.has_inertia = true;
    if (dims == 2) {
      // A lamina turns about z only: I_zz per metre of depth.
      st.inertia[8] = number(*iv, positive(), "kg m^2/m");
    } else if (iv->node.IsSequence() && iv->node.size() == 3 && !iv->node[0].IsSequence()) {
      const Vec3d d = point(*iv, 3, "kg m^2");
      for (int a = 0; a < 3; ++a) {
        if (!(d[std::size_t(a)] > 0))
          fail(iv->mark, "the principal moments in 'inertia' must be positive [kg m^2], got " + describe(iv->node));
        st.inertia[std::size_t(4 * a)] = d[std::size_t(a)];
      }
    } else if (iv->node.IsSequence() && iv->node.size() == 3) {
      for (std::size_t r = 0; r < 3; ++r) {
        const YAML::Node row = iv->node[r];
        const Vec3d rv = point({row, row.Mark().is_null() ? iv->mark : row.Mark(), "row " + std::to_string(r + 1) +
                                                                                       " of 'inertia'"},
                               3, "kg m^2");
        for (std::size_t c = 0; c < 3; ++c) st.inertia[3 * r + c] = rv[c];
      }
      for (std::size_t r = 0; r < 3; ++r)
        for (std::size_t c = r + 1; c < 3; ++c)
          if (std::abs(st.inertia[3 * r + c] - st.inertia[3 * c + r]) >
              1e-12 * std::max(std::abs(st.inertia[3 * r + c]), std::abs(st.inertia[3 * c + r])))
            fail(iv->mark, "'inertia' must be a symmetric tensor: row " + std::to_string(r + 1) + " column " +
                               std::to_string(c + 1) + " differs from row " + std::to_string(c + 1) + " column " +
                               std::to_string(r + 1));
    } else {
      fail(iv->mark, "'inertia' must be the principal moments [Ixx, Iyy, Izz] or a 3 x 3 tensor [[..], [..], [..]] "
                     "in kg m^2 about the centre of mass, got " + describe(iv->node));
    }
  }
  if (auto lv = m.get("lock")) {
    const std::vector<std::string> dofs = dims == 2 ? std::vector<std::string>{"x", "y", "rz"}
                                                    : std::vector<std::string>{"x", "y", "z", "rx", "ry", "rz"};
    for (const Value& d : list(*lv)) {
      const std::size_t k = choice(d, dofs, dims == 2 ? "a 2D body moves in x and y and turns about z" : "");
      const std::string& name = dofs[k];
      if (name[0] == 'r') st.lock_rotation[std::size_t(name[1] - 'x')] = true;
      else st.lock_translation[std::size_t(name[0] - 'x')] = true;
    }
  }
}

// contact: {youngs_modulus, poisson_ratio, restitution, friction}: the DEM contact material of a
// structure (fsi/body_contacts.hpp). On a moving structure it turns its contacts on; on a fixed one
// it is the obstacle's material (without it a fixed structure is rigid). Bullet's contacts are rigid
// (fsi/bullet_world.hpp): a bullet body's Young's modulus is optional and unused.
void Reader::read_contact(const Value& v, fsi::ContactMaterialSpec& c, bool rigid_contacts) const {
  MapView m(*this, v, {"youngs_modulus", "poisson_ratio", "restitution", "friction"});
  c.given = true;
  c.where = where(v.mark);
  if (rigid_contacts) {
    if (auto x = m.get("youngs_modulus")) c.youngs_modulus = number(*x, positive(), "Pa");
  } else {
    c.youngs_modulus = number(m.need("youngs_modulus"), positive(), "Pa");
  }
  if (auto x = m.get("poisson_ratio"))
    c.poisson_ratio = number(*x, {"a number in [0, 0.5]", [](double p) { return p >= 0 && p <= 0.5; }});
  c.restitution = number(m.need("restitution"), open_closed(0.0, 1.0));
  c.friction = number(m.need("friction"), non_negative());
}

// One end of a constraint: {structure: name, point: [..]} (a point of a moving structure, world
// position at t = 0) or {anchor: [..]} (fixed in the world).
fsi::ConstraintEndSpec Reader::read_constraint_end(const Value& v, const fsi::Scene& scene) const {
  const int dims = scene.dimensions;
  MapView m(*this, v, {"structure", "point", "anchor"});
  fsi::ConstraintEndSpec end;
  if (m.has("structure") == m.has("anchor"))
    fail(v.mark, v.name + " needs either 'structure' (with 'point') or 'anchor', " +
                     std::string(m.has("anchor") ? "not both" : "found neither"));
  if (auto av = m.get("anchor")) {
    if (m.has("point"))
      fail(m.key_mark("point"), "'point' applies to a structure end; an 'anchor' is itself the point [m]");
    end.point = point(*av, dims, "m");
    return end;
  }
  const Value sv = m.need("structure");
  const std::string name = text(sv);
  std::vector<std::string> names;
  for (const auto& st : scene.structures) names.push_back(st.name);
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end())
    fail(sv.mark, "unknown structure '" + name + "'" + did_you_mean(name, names) +
                      (names.empty() ? std::string(" (the scene has no structures)")
                                     : " (defined structures: " + join(names) + ")"));
  end.structure = int(it - names.begin());
  const fsi::StructureSpec& st = scene.structures[std::size_t(end.structure)];
  if (st.motion != fsi::StructureSpec::Motion::free && st.motion != fsi::StructureSpec::Motion::bullet)
    fail(sv.mark, "structure '" + name + "' is " +
                      (st.motion == fsi::StructureSpec::Motion::fixed ? "fixed" : "prescribed") +
                      ": a constraint ties moving structures (motion: free or bullet); tie it to an 'anchor' instead");
  end.point = point(m.need("point"), dims, "m");
  return end;
}

// constraints: springs and hinges between moving structures and fixed anchors (fsi/scene.hpp).
void Reader::read_constraints(const Value& v, fsi::Scene& scene) const {
  const int dims = scene.dimensions;
  const std::vector<Value> items = list(v);
  if (items.empty()) fail(v.mark, "'constraints' must list at least one constraint (or leave the key out)");
  std::map<std::string, int> first_line;
  const std::string per_depth = dims == 2 ? " per metre of depth" : "";
  for (const Value& item : items) {
    MapView m(*this, item, {"type", "name", "a", "b", "stiffness", "damping", "rest_length", "axis"}, false);
    fsi::ConstraintSpec c;
    c.where = where(item.mark);
    const Value tv = m.need("type");
    c.type = choice(tv, {"spring", "hinge"}) == 0 ? fsi::ConstraintSpec::Type::spring : fsi::ConstraintSpec::Type::hinge;
    const bool spring = c.type == fsi::ConstraintSpec::Type::spring;
    if (spring && m.has("axis")) fail(m.key_mark("axis"), "'axis' applies to a hinge, not to a spring");
    if (!spring)
      for (const char* key : {"stiffness", "damping", "rest_length"})
        if (m.has(key))
          fail(m.key_mark(key), "'" + std::string(key) + "' applies to a spring; a hinge holds its two points "
                                "together and leaves only the turn about its axis free");
    m.check_keys();
    c.name = (spring ? "spring_" : "hinge_") + std::to_string(scene.constraints.size() + 1);
    if (auto nv = m.get("name")) {
      c.name = text(*nv);
      if (const auto it = first_line.find(c.name); it != first_line.end())
        fail(nv->mark, "duplicate constraint name '" + c.name + "' (first used at line " +
                           std::to_string(it->second) + "); constraint names must be unique");
      first_line[c.name] = nv->mark.line + 1;
    }
    const Value av = m.need("a"), bv = m.need("b");
    c.a = read_constraint_end(av, scene);
    c.b = read_constraint_end(bv, scene);
    if (c.a.structure < 0 && c.b.structure < 0)
      fail(item.mark, "constraint '" + c.name + "' ties two anchors; at least one end must be a structure");
    if (c.a.structure >= 0 && c.a.structure == c.b.structure)
      fail(bv.mark, "constraint '" + c.name + "' ties structure '" + scene.structures[std::size_t(c.a.structure)].name +
                        "' to itself");
    if (spring) {
      c.stiffness = number(m.need("stiffness"), non_negative(), "N/m" + per_depth);
      if (auto x = m.get("damping")) c.damping = number(*x, non_negative(), "N s/m" + per_depth);
      if (!(c.stiffness > 0 || c.damping > 0))
        fail(m.key_mark("stiffness"), "spring '" + c.name + "' has neither stiffness nor damping");
      if (auto x = m.get("rest_length")) c.rest_length = number(*x, non_negative(), "m");
    } else if (dims == 2) {
      if (m.has("axis"))
        fail(m.key_mark("axis"), "a 2D hinge turns about z, the only axis of a planar body; 'axis' does not apply");
      c.axis = {0, 0, 1};
    } else {
      const Value xv = m.need("axis");
      Vec3d a = point(xv, 3, "");
      const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
      if (!(n > 0)) fail(xv.mark, "'axis' must not be the zero vector");
      for (auto& x : a) x /= n;
      c.axis = a;
      // The built-in integrator holds a hinge as a stiff pivot plus rotation locks about world axes
      // (docs/choices.md); a hinge between two bodies, or about a tilted axis, needs Bullet.
      const auto moves_free = [&](int s) {
        return s >= 0 && scene.structures[std::size_t(s)].motion == fsi::StructureSpec::Motion::free;
      };
      if (moves_free(c.a.structure) || moves_free(c.b.structure)) {
        const bool world_axis = std::abs(a[0]) == 1 || std::abs(a[1]) == 1 || std::abs(a[2]) == 1;
        if (c.a.structure >= 0 && c.b.structure >= 0)
          fail(item.mark, "hinge '" + c.name + "' joins two structures: the built-in integrator (motion: free) "
                          "holds a 3D hinge only to an 'anchor'; use 'motion: bullet' for hinges between bodies");
        if (!world_axis)
          fail(xv.mark, "hinge '" + c.name + "': the built-in integrator (motion: free) holds a 3D hinge about the "
                        "x, y or z axis only (it locks the other two rotations); use 'motion: bullet' for a tilted axis");
      }
    }
    scene.constraints.push_back(c);
  }
}

// motion: prescribed: the structure's 'path' (fsi/prescribed_path.hpp), exactly one of
//   velocity: [vx, vy(, vz)] [m/s] and/or angular_velocity: wz (3D [wx, wy, wz]) [deg/s];
//   oscillation: {amplitude: [m], angular_amplitude: [deg], period: [s], phase: [deg]};
//   samples: rows [t, x, y, rz] (3D [t, x, y, z, rx, ry, rz]) in s, m, deg;
//   file: a CSV (tools/path_csv.hpp), relative to the scene file like meshes;
// with samples and file also interpolation: spline (default) | linear. Displacements are from the
// scene's 'position', rotations about the reference point; the path must start there at t = 0.
void Reader::read_path(const MapView& m, const fsi::Scene& scene, fsi::StructureSpec& st) const {
  const int dims = scene.dimensions;
  if (st.motion != fsi::StructureSpec::Motion::prescribed) {
    if (m.has("path"))
      fail(m.key_mark("path"), "'path' applies to 'motion: prescribed'; structure '" + st.name + "' is " +
                                   (st.motion == fsi::StructureSpec::Motion::fixed ? "fixed" : "not prescribed"));
    return;
  }
  if (!m.has("path"))
    fail(m.key_mark("motion"), "prescribed structure '" + st.name + "' needs a 'path': 'velocity' (and/or "
                               "'angular_velocity'), 'oscillation', 'samples' or 'file'");
  const Value pv = m.need("path");
  MapView p(*this, pv, {"velocity", "angular_velocity", "oscillation", "samples", "file", "interpolation"});
  fsi::PrescribedPathSpec& path = st.path;
  path.where = where(pv.mark);
  const double d2r = std::acos(-1.0) / 180.0;
  std::vector<std::string> kinds;
  for (const char* k : {"velocity", "angular_velocity", "oscillation", "samples", "file"})
    if (p.has(k) && !(std::string(k) == "angular_velocity" && p.has("velocity"))) kinds.push_back(k);
  if (kinds.empty())
    fail(pv.mark, "'path' needs one of 'velocity' (and/or 'angular_velocity'), 'oscillation', 'samples' or 'file'");
  if (kinds.size() > 1)
    fail(p.key_mark(kinds[1]), "'path' has both '" + kinds[0] + "' and '" + kinds[1] + "'; give one kind of path");
  const std::string& kind = kinds[0];
  const auto angles = [&](const Value& v, std::string_view unit) {
    fsi::Vec3d a{0, 0, 0};
    if (dims == 2) a[2] = number(v, any_number(), unit);
    else a = point(v, 3, unit);
    for (auto& x : a) x *= d2r;
    return a;
  };
  if (p.has("interpolation") && kind != "samples" && kind != "file")
    fail(p.key_mark("interpolation"), "'interpolation' applies to a path of 'samples' or a 'file'");
  if (kind == "velocity" || kind == "angular_velocity") {
    path.kind = fsi::PrescribedPathSpec::Kind::velocity;
    if (auto v = p.get("velocity")) path.velocity = point(*v, dims, "m/s");
    if (auto w = p.get("angular_velocity")) path.angular_velocity = angles(*w, "deg/s");
  } else if (kind == "oscillation") {
    path.kind = fsi::PrescribedPathSpec::Kind::oscillation;
    const Value ov = p.need("oscillation");
    MapView o(*this, ov, {"amplitude", "angular_amplitude", "period", "phase"});
    if (!o.has("amplitude") && !o.has("angular_amplitude"))
      fail(ov.mark, "'oscillation' needs 'amplitude' [m] and/or 'angular_amplitude' [deg]");
    if (auto a = o.get("amplitude")) path.amplitude = point(*a, dims, "m");
    if (auto a = o.get("angular_amplitude")) path.angular_amplitude = angles(*a, "deg");
    path.period = number(o.need("period"), positive(), "s");
    if (auto ph = o.get("phase")) path.phase = number(*ph, any_number(), "deg") * d2r;
  } else {
    path.kind = fsi::PrescribedPathSpec::Kind::samples;
    if (auto iv = p.get("interpolation"))
      path.interpolation = choice(*iv, {"spline", "linear"}) == 0 ? fsi::PrescribedPathSpec::Interpolation::spline
                                                                  : fsi::PrescribedPathSpec::Interpolation::linear;
    if (kind == "samples") {
      const std::size_t n = dims == 2 ? 4 : 7;
      const std::string shape = dims == 2 ? "[t, x, y, rz] in s, m, m, deg" : "[t, x, y, z, rx, ry, rz] in s, m, m, m, deg, deg, deg";
      const std::vector<Value> rows = list(p.need("samples"));
      if (rows.size() < 2)
        fail(p.need("samples").mark, "'samples' needs at least 2 rows " + shape + ", got " + std::to_string(rows.size()));
      for (const Value& row : rows) {
        if (!row.node.IsSequence() || row.node.size() != n)
          fail(row.mark, row.name + " must be a list of " + std::to_string(n) + " numbers " + shape + ", got " +
                             describe(row.node));
        std::vector<double> x(n);
        for (std::size_t k = 0; k < n; ++k) {
          const YAML::Node c = row.node[k];
          x[k] = number({c, c.Mark().is_null() ? row.mark : c.Mark(), "value " + std::to_string(k + 1) + " of " + row.name},
                        any_number());
        }
        if (!path.times.empty() && !(x[0] > path.times.back()))
          fail(row.mark, "sample times must increase strictly: " + row.name + " has t = " + fmt(x[0]) +
                             " s after t = " + fmt(path.times.back()) + " s");
        path.times.push_back(x[0]);
        if (dims == 2) {
          path.displacement.push_back({x[1], x[2], 0});
          path.angles.push_back({0, 0, x[3] * d2r});
        } else {
          path.displacement.push_back({x[1], x[2], x[3]});
          path.angles.push_back({x[4] * d2r, x[5] * d2r, x[6] * d2r});
        }
      }
    } else {
      const Value fv = p.need("file");
      path.source = text(fv, "a CSV file name");
      std::filesystem::path file(path.source);
      if (file.is_relative()) file = std::filesystem::path(scene.base_directory) / file;
      const std::string resolved = file.lexically_normal().string();
      std::error_code ec;
      if (!std::filesystem::is_regular_file(resolved, ec))
        fail(fv.mark, "path file '" + path.source + "' not found (looked for " + resolved +
                          "; relative paths are relative to the scene file)");
      read_path_csv(resolved, resolved, dims, path);
    }
  }
  // The particles and the fluid around them are built where the scene puts the structure.
  fsi::PathState s0;
  try {
    s0 = fsi::PrescribedPath(path).at(0.0);
  } catch (const std::exception& e) {
    fail(pv.mark, e.what());
  }
  const double moved = s0.displacement.norm(), turned = (s0.rotation - Eigen::Matrix3d::Identity()).norm();
  if (moved > 1e-9 || turned > 1e-9)
    fail(pv.mark, "the path of structure '" + st.name + "' must start where the scene puts it: at t = 0 it is " +
                      "displaced by " + fmt(moved) + " m and turned by " + fmt(std::acos(std::clamp((s0.rotation.trace() - 1) / 2, -1.0, 1.0)) / d2r) +
                      " deg; give displacements and angles relative to 'position' and 'rotation' (zero at t = 0)");
}

void Reader::read_open_boundaries(const Value& v, fsi::Scene& scene) const {
  const int dims = scene.dimensions;
  std::vector<std::string> material_names;
  for (const auto& m : scene.materials) material_names.push_back(m.name);
  for (const Value& item : list(v)) {
    MapView m(*this, item, {"name", "type", "box", "direction", "velocity", "material"});
    fsi::OpenBoundarySpec ob;
    ob.where = where(item.mark);
    ob.name = text(m.need("name"));
    ob.inlet = choice(m.need("type"), {"inlet", "outlet"}) == 0;
    const Value bv = m.need("box");
    ob.box = box(bv, dims);
    require_ordered(bv, ob.box, dims);
    ob.velocity = direction(m.need("direction"), dims);
    if (ob.inlet) {
      MapView pv(*this, m.need("velocity"), {"profile", "mean"});
      if (auto pr = pv.get("profile")) ob.velocity.parabolic = choice(*pr, {"uniform", "parabolic"}) == 1;
      ob.velocity.mean = number(pv.need("mean"), positive(), "m/s");
      ob.material = scene.materials.front().name;
      if (auto mv = m.get("material")) {
        ob.material = text(*mv);
        if (std::find(material_names.begin(), material_names.end(), ob.material) == material_names.end())
          fail(mv->mark, "unknown material '" + ob.material + "'" + did_you_mean(ob.material, material_names) +
                             " (defined materials: " + join(material_names) + ")");
      }
    } else {
      for (const char* key : {"velocity", "material"})
        if (m.has(key))
          fail(m.key_mark(key), "'" + std::string(key) + "' applies only to an inlet; an outlet takes the fluid's "
                                "velocity and holds the pressure at the background pressure");
    }
    const double thickness = ob.box.max[std::size_t(ob.velocity.axis)] - ob.box.min[std::size_t(ob.velocity.axis)];
    const double needed = 2.0 * scene.smoothing_ratio * scene.particle_spacing;
    if (thickness < needed - 1e-9 * needed)
      fail(bv.mark, "the " + std::string(ob.inlet ? "inlet" : "outlet") + " zone is " + fmt(thickness) +
                        " m thick along the flow, less than the kernel support 2h = " + fmt(needed) +
                        " m; fluid next to it would miss neighbours");
    if (scene.open_boundaries.size() >= std::size_t(sph::kMaxZones))
      fail(item.mark, "at most " + std::to_string(sph::kMaxZones) + " open boundaries are supported");
    scene.open_boundaries.push_back(ob);
  }
}

void Reader::read_probes(const Value& v, fsi::Scene& scene) const {
  const int dims = scene.dimensions;
  std::vector<std::string> material_names;
  for (const auto& m : scene.materials) material_names.push_back(m.name);
  const std::vector<std::string> types = {"front_position", "pressure", "max_speed", "kinetic_energy",
                                          "fluid_particles", "surface_elevation", "material_mass", "highest_particle",
                                          "wall_load"};
  std::map<std::string, int> first_line;
  for (const Value& item : list(v)) {
    MapView m(*this, item, {"name", "type", "material", "axis", "point", "at", "min_kernel_sum", "sensor"});
    fsi::ProbeSpec probe;
    probe.where = where(item.mark);
    const Value nv = m.need("name");
    probe.name = text(nv);
    if (const auto bad = probe.name.find_first_of(",\"\n\r"); bad != std::string::npos) {
      const char c = probe.name[bad];
      const std::string what = c == ',' ? "a comma" : c == '"' ? "a double quote" : "a line break";
      fail(nv.mark, "probe name '" + probe.name + "' contains " + what +
                        " and cannot be a CSV column header; use letters, digits, '_' or '-'");
    }
    if (const auto it = first_line.find(probe.name); it != first_line.end())
      fail(nv.mark, "duplicate probe name '" + probe.name + "' (first used at line " + std::to_string(it->second) +
                        "); probe names must be unique");
    first_line[probe.name] = nv.mark.line + 1;

    const Value tv = m.need("type");
    const std::size_t t = choice(tv, types);
    probe.type = static_cast<fsi::ProbeSpec::Type>(t);
    std::vector<std::string> uses;
    if (probe.type == fsi::ProbeSpec::Type::front_position) uses = {"material", "axis"};
    const bool station = probe.type == fsi::ProbeSpec::Type::surface_elevation ||
                         probe.type == fsi::ProbeSpec::Type::highest_particle;
    if (probe.type == fsi::ProbeSpec::Type::pressure) uses = {"point", "min_kernel_sum", "sensor"};
    if (probe.type == fsi::ProbeSpec::Type::wall_load) {
      uses = {"point", "sensor"};
      m.need("sensor");  // the face is the sensor
    }
    if (station) uses = {"material", "at"};
    if (probe.type == fsi::ProbeSpec::Type::material_mass) {
      uses = {"material"};
      m.need("material");
    }
    for (const char* key : {"material", "axis", "point", "at", "min_kernel_sum", "sensor"})
      if (m.has(key) && std::find(uses.begin(), uses.end(), key) == uses.end())
        fail(m.key_mark(key), "'" + std::string(key) + "' does not apply to a '" + types[t] + "' probe");

    if (auto mv = m.get("material")) {
      probe.material = text(*mv);
      if (std::find(material_names.begin(), material_names.end(), probe.material) == material_names.end())
        fail(mv->mark, "unknown material '" + probe.material + "' in probe '" + probe.name + "'" +
                           did_you_mean(probe.material, material_names) + " (defined materials: " +
                           join(material_names) + ")");
    }
    if (auto av = m.get("axis")) {
      std::vector<std::string> axes(kAxisName, kAxisName + dims);
      const bool z_in_2d = dims == 2 && av->node.IsScalar() && av->node.Scalar() == "z";
      probe.axis = static_cast<int>(choice(*av, axes, z_in_2d ? "a 2D scene has no z axis" : ""));
    }
    if (probe.type == fsi::ProbeSpec::Type::pressure || probe.type == fsi::ProbeSpec::Type::wall_load)
      probe.point = point(m.need("point"), dims, "m");
    if (auto kv = m.get("min_kernel_sum")) {
      probe.min_kernel_sum = number(*kv, non_negative());
      if (probe.min_kernel_sum >= 1)
        fail(kv->mark, "'min_kernel_sum' is a fraction of the full kernel sum (1 inside the fluid), below 1; got " +
                           fmt(probe.min_kernel_sum));
    }
    if (auto sv = m.get("sensor")) {
      // A wall sensor's face: {diameter: D [m], normal: [..]} (the normal need not be unit length).
      MapView sm(*this, *sv, {"diameter", "normal"});
      probe.sensor_diameter = number(sm.need("diameter"), positive(), "m");
      const Value nv = sm.need("normal");
      probe.sensor_normal = point(nv, dims, "");
      double len2 = 0;
      for (double c : probe.sensor_normal) len2 += c * c;
      if (!(len2 > 0) || !std::isfinite(len2)) fail(nv.mark, "the sensor's 'normal' must be a non-zero vector");
    }
    if (station) {
      // The elevation is measured along the last axis (y in 2D, z in 3D), the one the default
      // gravity points down; `at` gives the station's other coordinates. A scene whose gravity
      // does not point mostly down that axis has no such vertical, so the probe is refused.
      const int up = dims - 1;
      const Vec3d& g = scene.gravity;
      const bool down = g[std::size_t(up)] < 0 && std::abs(g[std::size_t(up)]) >= std::abs(g[0]) &&
                        std::abs(g[std::size_t(up)]) >= std::abs(g[1]) && std::abs(g[std::size_t(up)]) >= std::abs(g[2]);
      if (!down)
        fail(tv.mark, "a '" + types[t] + "' probe measures along " + std::string(kAxisName[up]) +
                          " and needs gravity pointing mainly down that axis, got gravity [" + fmt(g[0]) + ", " +
                          fmt(g[1]) + (dims == 3 ? ", " + fmt(g[2]) : std::string()) + "]");
      probe.axis = up;
      const Value at = m.need("at");
      if (dims == 2) {
        probe.point[0] = number({at.node, at.mark, "'at' (the station's x)"}, any_number(), "m");
      } else {
        Value a = at;
        a.name = "'at' (the station's [x, y])";
        if (!at.node.IsSequence() || at.node.size() != 2)
          fail(at.mark, a.name + " must be a list of 2 numbers [x, y] in m, got " + describe(at.node));
        const Vec3d xy = point(a, 2, "m");
        probe.point = {xy[0], xy[1], 0.0};
      }
    }
    scene.probes.push_back(probe);
  }
}

void Reader::read_output(const Value& v, fsi::OutputSpec& out) const {
  MapView m(*this, v, {"every", "vtk", "checkpoint_every", "forces_every", "probes_every"});
  // forces.csv and probes.csv rows: an interval in seconds, or `step` for a row after every time
  // step (an impact peak lasts a few steps; issue #25 item 4).
  const auto interval_or_step = [&](const Value& x, double& every, bool& each_step) {
    if (x.node.IsScalar() && x.node.Scalar() == "step") {
      each_step = true;
      return;
    }
    every = number(x, {"'step' or a number >= 0", non_negative().ok}, "s");
  };
  if (auto x = m.get("forces_every")) interval_or_step(*x, out.forces_every, out.forces_each_step);
  if (auto x = m.get("probes_every")) interval_or_step(*x, out.probes_every, out.probes_each_step);
  if (auto x = m.get("every")) out.every = number(*x, non_negative(), "s");
  if (auto x = m.get("vtk")) out.vtk = boolean(*x);
  if (auto x = m.get("checkpoint_every")) out.checkpoint_every = number(*x, non_negative(), "s");
}

}  // namespace

std::string schedule_problem(double end, const fsi::OutputSpec& out) {
  struct Item {
    double every;
    double most;
    const char* key;
    const char* what;
  };
  const Item items[] = {{out.every, 1e6, "output: every", "ParaView frames"},
                        {out.forces_every, 1e8, "output: forces_every", "force rows"},
                        {out.probes_every, 1e8, "output: probes_every", "probe rows"},
                        {out.checkpoint_every, 1e5, "checkpoint_every", "checkpoints"}};
  for (const Item& it : items) {
    if (!(it.every > 0) || end / it.every <= it.most) continue;
    std::ostringstream os;
    os << std::setprecision(3) << "'" << it.key << "' = " << it.every << " s over an end time of " << end
       << " s asks for " << end / it.every << " " << it.what << ", more than " << it.most
       << "; give at least " << end / it.most << " s (0 for none)";
    return os.str();
  }
  return {};
}

fsi::Scene read_scene_string(const std::string& yaml_text, const std::string& file_name_for_messages) {
  return Reader(file_name_for_messages).read(yaml_text);
}

fsi::Scene read_scene_file(const std::string& path, const std::string& relative_to, const SceneOverrides& overrides) {
  // The command-line values themselves: the same ranges as the scene's keys.
  const auto refuse = [](const char* option, double v, const char* range) {
    std::ostringstream os;
    os << std::setprecision(12) << "turbid: " << option << " " << v << ": must be " << range;
    throw OptionError(os.str());
  };
  if (overrides.spacing && !(*overrides.spacing > 0 && std::isfinite(*overrides.spacing)))
    refuse("--spacing", *overrides.spacing, "a positive length [m]");
  if (overrides.end_time && !(*overrides.end_time > 0 && std::isfinite(*overrides.end_time)))
    refuse("--end", *overrides.end_time, "a positive time [s]");
  if (overrides.checkpoint_every && !(*overrides.checkpoint_every >= 0 && std::isfinite(*overrides.checkpoint_every)))
    refuse("--checkpoint-every", *overrides.checkpoint_every, "a time >= 0 [s] (0 for none)");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw SceneError(path + ":1:1: error: this is a directory, not a scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw SceneError(path + ":1:1: error: cannot open the scene file (" +
                     (err ? std::string(std::strerror(err)) : std::string("unknown reason")) + ")");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw SceneError(path + ":1:1: error: cannot read the scene file");
  if (!overrides.any()) return Reader(path, relative_to).read(text.str());
  try {
    return Reader(path, relative_to, overrides).read(text.str());
  } catch (const SceneError& e) {
    std::ostringstream os;
    os << std::setprecision(12) << e.what() << " (with";
    if (overrides.spacing) os << " --spacing " << *overrides.spacing;
    if (overrides.end_time) os << " --end " << *overrides.end_time;
    if (overrides.checkpoint_every) os << " --checkpoint-every " << *overrides.checkpoint_every;
    os << " from the command line)";
    throw SceneError(os.str());
  }
}

}  // namespace turbid::tools
