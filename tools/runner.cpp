// `turbid run` behind the command line; see runner.hpp.
#include "tools/runner.hpp"

#include <unistd.h>

#include <csignal>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "fsi/bullet_world.hpp"
#include "fsi/forces.hpp"
#include "fsi/probes.hpp"
#include "fsi/simulation.hpp"
#include "tools/checkpoint.hpp"
#include "tools/csv_writer.hpp"
#include "tools/run_report.hpp"
#include "tools/scene_reader.hpp"
#include "tools/vtk_writer.hpp"

namespace turbid::tools {
namespace fs = std::filesystem;

namespace {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const long t = long(s + 0.5);
  char buf[32];
  if (t >= 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%02ld:%02ld", t / 60, t % 60);
  return buf;
}

// A number with `digits` significant digits, for what `turbid check` prints (0.6754, not 0.675400013).
std::string sig(double v, int digits = 4) {
  std::ostringstream o;
  o << std::setprecision(digits) << v;
  return o.str();
}

// The progress line names fluid behind walls only when there is some (the last output's count).
std::string behind_text(std::size_t count) {
  return count == 0 ? std::string() : " | " + std::to_string(count) + " behind walls";
}

double fluid_mass(const fsi::Simulation& sim) {
  const auto& s = sim.store();
  const auto* m = s.data<float>(sim.fields().mass);
  const auto* kind = s.data<std::uint8_t>(sim.fields().kind);
  double total = 0;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] == 0) total += m[i];
  return total;
}

// Linear momentum sum m_i v_i of the fluid particles [kg m/s; per metre of depth in 2D], one
// component per dimension, accumulated in double in index order. Walls and structures do not move
// (fixed bodies only), so this is the momentum of everything that moves.
std::vector<double> fluid_momentum(const fsi::Simulation& sim) {
  const auto& s = sim.store();
  const int d = sim.scene().dimensions;
  const auto* m = s.data<float>(sim.fields().mass);
  const auto* v = s.data<float>(sim.fields().velocity);
  const auto* kind = s.data<std::uint8_t>(sim.fields().kind);
  std::vector<double> p(std::size_t(d), 0.0);
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] == 0)
      for (int k = 0; k < d; ++k) p[std::size_t(k)] += double(m[i]) * double(v[i * std::size_t(d) + std::size_t(k)]);
  return p;
}

// Free bodies' exact state for a checkpoint: position, orientation, velocity, angular momentum and
// the fluid load of the last force pass (the first kick after a resume needs it), and for a bullet
// body Bullet's own exact state (fsi/bullet_world.hpp, exact_state), as JSON numbers,
// which nlohmann writes with enough digits to read back the same doubles.
nlohmann::json body_states(const fsi::Simulation& sim) {
  nlohmann::json list = nlohmann::json::array();
  const fsi::BodyCoupling& c = *sim.bodies();
  const auto vec = [](const Eigen::Vector3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); };
  for (std::size_t k = 0; k < c.structure_count(); ++k) {
    if (!c.is_free(k)) continue;
    const fsi::RigidBody& b = c.body(k);
    const Eigen::Quaterniond& q = b.orientation();
    list.push_back({{"structure", sim.scene().structures[k].name},
                    {"position", vec(b.position())},
                    {"orientation", nlohmann::json::array({q.w(), q.x(), q.y(), q.z()})},
                    {"velocity", vec(b.velocity())},
                    {"angular_momentum", vec(b.angular_momentum())},
                    {"fluid_force", vec(c.fluid_load(k).force)},
                    {"fluid_torque", vec(c.fluid_load(k).torque)},
                    {"contact_force", vec(c.contact_load(k).force)},
                    {"contact_torque", vec(c.contact_load(k).torque)}});
    if (c.is_bullet(k)) list.back()["bullet_state"] = c.bullet()->exact_state(k);
  }
  return list;
}

// The DEM contacts open at the checkpoint: key (body, sphere, obstacle kind, obstacle, obstacle
// sphere) and the tangential spring's elongation, which the next substeps continue from.
nlohmann::json contact_states(const fsi::Simulation& sim) {
  nlohmann::json list = nlohmann::json::array();
  const fsi::BodyContacts* contacts = sim.bodies()->contacts();
  if (!contacts) return list;
  for (const auto& [key, spring] : contacts->springs()) {
    const Eigen::Vector3d& e = spring.elongation;
    list.push_back(nlohmann::json::array({key[0], key[1], key[2], key[3], key[4], e[0], e[1], e[2]}));
  }
  return list;
}

void restore_body_states(fsi::Simulation& sim, const nlohmann::json& state, const std::filesystem::path& dir) {
  if (!sim.bodies()) return;
  fsi::BodyCoupling& c = *sim.bodies();
  if (!state.contains("bodies"))
    throw std::runtime_error(dir.string() + ": the checkpoint has no rigid-body states, but the scene has free structures");
  const auto vec = [](const nlohmann::json& j) { return Eigen::Vector3d(j.at(0), j.at(1), j.at(2)); };
  for (std::size_t k = 0; k < c.structure_count(); ++k) {
    if (!c.is_free(k)) continue;
    const std::string& name = sim.scene().structures[k].name;
    const nlohmann::json* found = nullptr;
    for (const auto& b : state.at("bodies"))
      if (b.at("structure").get<std::string>() == name) found = &b;
    if (!found) throw std::runtime_error(dir.string() + ": the checkpoint has no state for free structure '" + name + "'");
    const nlohmann::json& b = *found;
    const auto& q = b.at("orientation");
    c.body(k).restore_state(vec(b.at("position")), Eigen::Quaterniond(q.at(0), q.at(1), q.at(2), q.at(3)),
                            vec(b.at("velocity")), vec(b.at("angular_momentum")));
    fsi::Wrench w;
    w.force = vec(b.at("fluid_force"));
    w.torque = vec(b.at("fluid_torque"));
    c.restore_fluid_load(k, w);
    if (b.contains("contact_force")) {
      fsi::Wrench touch;
      touch.force = vec(b.at("contact_force"));
      touch.torque = vec(b.at("contact_torque"));
      c.restore_contact_load(k, touch);
    }
  }
  if (fsi::BodyContacts* contacts = c.contacts()) {
    std::map<fsi::ContactKey, fsi::TangentialSpring> springs;
    if (state.contains("contacts"))
      for (const auto& e : state.at("contacts")) {
        fsi::ContactKey key;
        for (std::size_t i = 0; i < 5; ++i) key[i] = e.at(i).get<int>();
        springs[key].elongation = Eigen::Vector3d(e.at(5).get<double>(), e.at(6).get<double>(), e.at(7).get<double>());
      }
    contacts->restore_springs(std::move(springs));
  }
  c.restored();  // bullet bodies take their mirrors' restored state, then Bullet's exact one where saved
  for (std::size_t k = 0; k < c.structure_count(); ++k) {
    if (!c.is_bullet(k)) continue;
    for (const auto& b : state.at("bodies"))
      if (b.at("structure").get<std::string>() == sim.scene().structures[k].name && b.contains("bullet_state"))
        c.bullet()->restore_exact_state(k, b.at("bullet_state").get<std::vector<double>>());
  }
}

// Mass and particle count of each material's fluid particles (scene order).
struct MaterialTotals {
  std::vector<double> mass;
  std::vector<std::size_t> particles;
};
MaterialTotals material_totals(const fsi::Simulation& sim) {
  const auto& s = sim.store();
  const auto* m = s.data<float>(sim.fields().mass);
  const auto* kind = s.data<std::uint8_t>(sim.fields().kind);
  const auto* mat = s.data<std::uint8_t>(sim.fields().material);
  const std::size_t n = sim.scene().materials.size();
  MaterialTotals t{std::vector<double>(n, 0.0), std::vector<std::size_t>(n, 0)};
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] == 0 && mat[i] < n) {
      t.mass[mat[i]] += m[i];
      ++t.particles[mat[i]];
    }
  return t;
}

// The run's state block: every key the resume reads, of the type it reads, so that an edited or
// damaged value is named with its file and key (not a bare json type_error).
void check_run_state(const nlohmann::json& state, const fs::path& file) {
  const auto bad = [&](const fs::path& f, const std::string& what) {
    throw std::runtime_error("checkpoint '" + f.string() + "': " + what);
  };
  if (!state.is_object()) bad(file, "'state' must be an object, got " + std::string(state.type_name()));
  struct Key {
    const char* name;
    bool required;
    bool count;  // a non-negative integer; else any number
  };
  const Key keys[] = {{"time", true, false},           {"steps", true, true},           {"removed", true, true},
                      {"output_index", true, true},    {"checkpoint_index", true, true}, {"particle_steps", true, true},
                      {"particle_spacing", true, false}, {"end_time", true, false},      {"wall_seconds", false, false},
                      {"inflow", false, true},         {"outflow", false, true},        {"splits", false, true},
                      {"daughters", false, true},      {"splits_refused", false, true},
                      {"smallest_smoothing_length", false, false}, {"checkpoint_every", false, false},
                      {"fluid_particle_steps", false, true}, {"wall_put_backs", false, true},
                      {"wall_constraint_impulse_x", false, false}, {"wall_constraint_impulse_y", false, false},
                      {"wall_constraint_impulse_z", false, false}, {"wall_constraint_energy", false, false}};
  for (const Key& k : keys) {
    if (!state.contains(k.name)) {
      if (k.required) bad(file, "'state' has no '" + std::string(k.name) + "'");
      continue;
    }
    const nlohmann::json& v = state[k.name];
    const bool ok = k.count ? v.is_number_unsigned() : v.is_number();
    if (!ok)
      bad(file, "'state." + std::string(k.name) + "' must be " + (k.count ? "a non-negative integer" : "a number") +
                    ", got " + v.dump() + " (" + v.type_name() + ")");
  }
  for (const char* k : {"scene_directory"})
    if (state.contains(k) && !state[k].is_string())
      bad(file, "'state." + std::string(k) + "' must be a string, got " + state[k].dump());
  if (state.contains("inputs") && !state["inputs"].is_object())
    bad(file, "'state.inputs' must be an object of file hashes, got " + state["inputs"].dump());
}

// What a run that died while writing leaves in its directory: half-written files (`*.tmp-PID`,
// tools/atomic_file), a half-written `checkpoint.tmp/`, and `checkpoint.old/` once `checkpoint/` is
// complete (while `checkpoint/` is missing, `checkpoint.old/` is the checkpoint and stays).
void remove_leftovers(const fs::path& out) {
  std::error_code ec;
  for (const fs::path& d : {out, out / "checkpoint"}) {
    if (!fs::is_directory(d, ec)) continue;
    std::vector<fs::path> stale;
    for (const auto& e : fs::directory_iterator(d, ec))
      if (e.path().filename().string().find(".tmp-") != std::string::npos) stale.push_back(e.path());
    for (const auto& p : stale) fs::remove_all(p, ec);
  }
  fs::remove_all(out / "checkpoint.tmp", ec);
  if (fs::exists(out / "checkpoint" / "checkpoint.json", ec)) fs::remove_all(out / "checkpoint.old", ec);
}

// FNV-1a (64 bit) of a file's bytes as 16 hex digits: tells a changed input from the one a
// checkpoint was written with (a change detector, not a defence against tampering).
std::string file_hash(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read '" + file.string() + "'");
  std::uint64_t h = 14695981039346656037ull;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h ^= static_cast<unsigned char>(buf[i]);
      h *= 1099511628211ull;
    }
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

// The files a run's physics comes from: its scene.yaml and every mesh and path CSV it names, each
// with its hash, keyed by the name the scene gives it.
nlohmann::json input_hashes(const fs::path& scene_yaml, const fsi::Scene& scene) {
  nlohmann::json j = nlohmann::json::object();
  j["scene.yaml"] = file_hash(scene_yaml);
  for (const auto& st : scene.structures) {
    if (!st.resolved_file.empty()) j[st.file] = file_hash(st.resolved_file);
    if (!st.path.source.empty()) {
      fs::path q = st.path.source;
      if (q.is_relative() && !fs::exists(q) && !scene.base_directory.empty()) q = fs::path(scene.base_directory) / q;
      j[st.path.source] = file_hash(q);
    }
  }
  return j;
}

// Ctrl-C (SIGINT) and SIGTERM during a run: the first asks the run to stop after the current step
// with a checkpoint and run.json; a second ends the process at once (exit 128 + signal).
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void on_stop_signal(int signo) {
  if (g_stop_signal != 0) {
    static const char msg[] = "\nturbid: second signal, exiting now without a checkpoint\n";
    [[maybe_unused]] const auto n = write(STDERR_FILENO, msg, sizeof msg - 1);
    _exit(128 + signo);
  }
  g_stop_signal = signo;
}

// Installs the handlers for one run and puts the previous ones back after it.
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;
  int received() const { return g_stop_signal; }

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

class Writers final : public fsi::Observer {
 public:
  Writers(const fs::path& out, const fsi::Scene& scene, std::optional<double> resume_time, bool progress)
      : out_(out), progress_(progress), tty_(isatty(fileno(stderr)) != 0) {
    std::vector<std::string> names;
    // Each column names its unit, as forces.csv does ("front [m]", "p1 [Pa]").
    for (const auto& p : scene.probes)
      names.push_back(p.name + " [" + fsi::probe_unit(p.type, scene.dimensions) + "]");
    probes_.emplace(out / "probes.csv", names, resume_time, "time [s]");
    if (!scene.structures.empty()) forces_.emplace(out / "forces.csv", fsi::force_columns(scene), resume_time, "time [s]");
    if (scene.output.vtk) {
      vtk_.emplace(out, scene.dimensions);
      if (resume_time) vtk_->resume_after(*resume_time);
    }
  }

  void on_output(fsi::Simulation& sim) override {
    // Fluid behind walls: said once when first seen (and whenever it grows past twice what was
    // said), whatever the progress setting; the scene's max_fluid_behind_walls stops the run.
    const auto& behind = sim.fluid_behind_walls();
    most_behind_ = std::max(most_behind_, behind.count);
    if (behind.count > 0 && behind.count > 2 * behind_told_) {
      std::fprintf(stderr, "%swarning: t = %.4g s: %zu fluid particles behind a wall or structure surface "
                   "(%zu walls, %zu structures; the deepest %.2g spacings); set numerics: "
                   "max_fluid_behind_walls to stop the run past a count\n", tty_ && progress_ ? "\n" : "",
                   sim.time(), behind.count, behind.below_walls, behind.inside_structures,
                   behind.deepest / sim.scene().particle_spacing);
      behind_told_ = behind.count;
    }
    // The impermeable-wall pass is a safety net (issue #47 item 2): said when it works hard, past
    // 1e-4 put-backs per fluid particle-step over the run so far (ten times the goal for every
    // scene), and again whenever the rate doubles; run.json has the run's rate.
    const std::uint64_t put_backs = sim.wall_put_backs(), particle_steps = sim.fluid_particle_steps();
    if (put_backs >= 100 && particle_steps > 0) {
      const double rate = double(put_backs) / double(particle_steps);
      if (rate > kPutBackWarning && rate > 2 * put_back_rate_told_) {
        std::fprintf(stderr, "%swarning: t = %.4g s: the impermeable-wall pass put fluid back on a wall or structure "
                     "surface %llu times, %.2g per fluid particle-step (more than %.0e): the walls do not hold the "
                     "fluid by its pressure alone; docs/choices.md (impermeable walls) says where that comes from\n",
                     tty_ && progress_ ? "\n" : "", sim.time(), static_cast<unsigned long long>(put_backs), rate,
                     kPutBackWarning);
        put_back_rate_told_ = rate;
      }
    }
    if (vtk_) vtk_->write(sim.store(), sim.time());
  }

  void on_probes(fsi::Simulation& sim) override { probes_->append(sim.time(), sim.probe_values()); }

  void on_forces(fsi::Simulation& sim) override {
    if (forces_) forces_->append(sim.time(), fsi::force_row(sim.scene(), sim.structure_loads(), sim.body_kinematics()));
  }

  void on_checkpoint(fsi::Simulation& sim) override { save_checkpoint(sim); }

  bool stop_requested() const override {
    if (g_stop_signal != 0 && progress_ && tty_) std::fprintf(stderr, "\n");
    return g_stop_signal != 0;
  }

  void on_progress(const fsi::Simulation& sim) override {
    // Splits refused for lack of room: said once per new batch, whatever the progress setting.
    if (sim.split_totals().refused > refused_told_) {
      std::fprintf(stderr, "%swarning: t = %.4g s: %zu splits refused so far, the particle store is full (%zu); "
                   "raise 'capacity' in the scene\n", tty_ && progress_ ? "\n" : "", sim.time(),
                   sim.split_totals().refused, sim.store().capacity());
      refused_told_ = sim.split_totals().refused;
    }
    if (!progress_) return;
    const double frac = sim.time() / sim.end_time();
    const double elapsed = sim.wall_seconds() - wall_at_start_;
    // This process's rate (after a resume the steps before it ran in another process's time).
    const double rate = elapsed > 0 ? double(sim.particle_steps() - particle_steps_at_start_) / elapsed : 0.0;
    const double done = sim.time() - time_at_start_;
    const double left = std::max(0.0, sim.end_time() - sim.time());
    const double eta = left == 0 ? 0.0 : done > 0 ? elapsed * left / done : NAN;
    char line[256];
    std::snprintf(line, sizeof line, "t = %.4g / %.4g s (%3.0f%%) | step %llu | dt %.2e s | %.3g particle-steps/s | ETA %s%s",
                  sim.time(), sim.end_time(), 100 * frac, static_cast<unsigned long long>(sim.steps()),
                  sim.last_time_step(), rate, format_duration(eta).c_str(),
                  behind_text(sim.fluid_behind_walls().count).c_str());
    if (tty_) {
      std::fprintf(stderr, "\r%-110s", line);
    } else if (sim.wall_seconds() - last_plain_ >= 10.0 || sim.time() >= sim.end_time()) {
      std::fprintf(stderr, "%s\n", line);
      last_plain_ = sim.wall_seconds();
    }
    std::fflush(stderr);
  }

  void on_finish(fsi::Simulation&) override {
    if (progress_ && tty_) std::fprintf(stderr, "\n");
  }

  void save_checkpoint(fsi::Simulation& sim) {
    nlohmann::json state;
    state["time"] = sim.time();
    state["steps"] = sim.steps();
    state["removed"] = sim.removed();
    state["output_index"] = sim.output_index();
    state["checkpoint_index"] = sim.checkpoint_index();
    state["particle_steps"] = sim.particle_steps();
    state["fluid_particle_steps"] = sim.fluid_particle_steps();
    state["wall_put_backs"] = sim.wall_put_backs();
    const sph::WallConstraintTotals constraint = sim.wall_constraint_totals();
    state["wall_constraint_impulse_x"] = constraint.impulse[0];
    state["wall_constraint_impulse_y"] = constraint.impulse[1];
    state["wall_constraint_impulse_z"] = constraint.impulse[2];
    state["wall_constraint_energy"] = constraint.energy;
    state["inflow"] = sim.inflow();
    state["outflow"] = sim.outflow();
    if (!sim.scene().transitions.empty()) {
      const auto& c = sim.split_totals();
      state["splits"] = c.splits;
      state["daughters"] = c.daughters;
      state["splits_refused"] = c.refused;
      state["smallest_smoothing_length"] = c.smallest_h;
    }
    state["wall_seconds"] = sim.wall_seconds();
    state["checkpoint_every"] = sim.scene().output.checkpoint_every;  // a --checkpoint-every outlives the resume
    state["inputs"] = inputs_;  // hashes of the scene and its files: a resume refuses changed physics
    state["particle_spacing"] = sim.scene().particle_spacing;
    state["end_time"] = sim.scene().end_time;
    // Meshes named relative to the scene file are found from here when the run is resumed.
    state["scene_directory"] = sim.scene().base_directory;
    if (sim.bodies()) state["bodies"] = body_states(sim);
    if (sim.bodies() && sim.bodies()->contacts()) state["contacts"] = contact_states(sim);
    write_checkpoint(out_ / "checkpoint", sim.store(), state);
  }

  void set_inputs(nlohmann::json inputs) { inputs_ = std::move(inputs); }
  std::size_t most_behind_walls() const { return most_behind_; }

  void start_clock(const fsi::Simulation& sim) {
    wall_at_start_ = sim.wall_seconds();
    particle_steps_at_start_ = sim.particle_steps();
    time_at_start_ = sim.time();
  }

 private:
  fs::path out_;
  bool progress_;
  bool tty_;
  std::size_t most_behind_ = 0;
  std::size_t behind_told_ = 0;
  double last_plain_ = 0;
  std::size_t refused_told_ = 0;  // splits refused that a warning has reported
  static constexpr double kPutBackWarning = 1e-4;
  double put_back_rate_told_ = 0;  // the put-back rate a warning has reported
  double wall_at_start_ = 0, time_at_start_ = 0;
  std::uint64_t particle_steps_at_start_ = 0;
  nlohmann::json inputs_ = nlohmann::json::object();
  std::optional<CsvSeriesWriter> probes_;
  std::optional<CsvSeriesWriter> forces_;
  std::optional<VtkSeriesWriter> vtk_;
};

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

}  // namespace

SceneOverrides overrides_of(const RunRequest& r) {
  SceneOverrides o;
  o.spacing = r.spacing;
  o.end_time = r.end_time;
  o.checkpoint_every = r.checkpoint_every;
  return o;
}

void apply_overrides(fsi::Scene& scene, const RunRequest& r) {
  if (r.spacing) {
    if (!(*r.spacing > 0)) throw OptionError("turbid: --spacing must be a positive length [m]");
    scene.particle_spacing = *r.spacing;
  }
  if (r.end_time) {
    if (!(*r.end_time > 0)) throw OptionError("turbid: --end must be a positive time [s]");
    scene.end_time = *r.end_time;
  }
  if (r.checkpoint_every) {
    if (!(*r.checkpoint_every >= 0)) throw OptionError("turbid: --checkpoint-every must be >= 0 [s] (0 for none)");
    scene.output.checkpoint_every = *r.checkpoint_every;
  }
  if (r.end_time || r.checkpoint_every) {
    const std::string problem = schedule_problem(scene.end_time, scene.output);
    if (!problem.empty()) throw OptionError("turbid: with the command-line options, " + problem);
  }
}

std::string describe_scene(const fsi::Scene& scene) {
  fsi::RunOptions opts;
  opts.backend = "cpu";
  fsi::Simulation sim(scene, opts);
  const auto& s = sim.summary();
  std::ostringstream os;
  const std::size_t total = s.fluid_particles + s.wall_particles + s.structure_particles + s.buffer_particles;
  os << "scene            " << scene.name << " (" << scene.dimensions << "D)\n";
  os << "spacing          " << scene.particle_spacing << " m, h = " << s.smoothing_length << " m\n";
  os << "particles        " << total << " (fluid " << s.fluid_particles << ", wall " << s.wall_particles;
  if (s.structure_particles > 0) os << ", structure " << s.structure_particles;
  if (s.buffer_particles > 0) os << ", open-boundary buffer " << s.buffer_particles;
  os << ")\n";
  os << "wall treatment   " << (scene.numerics.boundary == fsi::BoundaryKind::mdbc ? "mDBC" : "DBC")
     << (sim.params().wall_no_slip ? " (no-slip: mirrored velocity)" : " (wall velocity)");
  if (sim.params().wall_viscosity_normal) os << ", artificial viscosity on the approach along the wall's normal";
  if (scene.numerics.wall_function) os << ", log-law wall function (k_s = " << scene.numerics.wall_roughness << " m)";
  os << "\n";
  const bool two_d = scene.dimensions == 2;
  for (const auto& st : s.structures)
    os << "  structure " << st.name << ": " << st.particles << " particles, surface "
       << st.surface_area << (two_d ? " m (perimeter)" : " m^2") << ", volume " << st.volume
       << (two_d ? " m^2 (area)" : " m^3") << "\n";
  for (const auto& st : scene.structures) {
    if (st.motion != fsi::StructureSpec::Motion::prescribed) continue;
    const auto& p = st.path;
    const auto vec = [&](const fsi::Vec3d& v, double scale) {
      std::ostringstream o;
      o << "(" << v[0] * scale << ", " << v[1] * scale;
      if (!two_d) o << ", " << v[2] * scale;
      o << ")";
      return o.str();
    };
    const double deg = 180.0 / 3.14159265358979323846;
    const auto num = [](double x) {
      std::ostringstream o;
      o << x;
      return o.str();
    };
    os << "  prescribed " << st.name << ": ";
    if (p.kind == fsi::PrescribedPathSpec::Kind::velocity) {
      os << "velocity " << vec(p.velocity, 1) << " m/s, angular velocity "
         << (two_d ? num(p.angular_velocity[2] * deg) : vec(p.angular_velocity, deg)) << " deg/s";
    } else if (p.kind == fsi::PrescribedPathSpec::Kind::oscillation) {
      os << "oscillation, amplitude " << vec(p.amplitude, 1) << " m, angular amplitude "
         << (two_d ? num(p.angular_amplitude[2] * deg) : vec(p.angular_amplitude, deg)) << " deg, period "
         << p.period << " s, phase " << p.phase * deg << " deg";
    } else {
      os << p.times.size() << " samples over [" << p.times.front() << ", " << p.times.back() << "] s, "
         << (p.interpolation == fsi::PrescribedPathSpec::Interpolation::spline ? "clamped spline" : "linear")
         << (p.source.empty() ? std::string(" (inline)") : " (from " + p.source + ")");
    }
    os << "; about (" << st.reference_point[0] << ", " << st.reference_point[1];
    if (!two_d) os << ", " << st.reference_point[2];
    os << ") m\n";
  }
  for (const auto& fb : s.free_bodies) {
    const auto& mp = fb.mass_properties;
    const auto& st = scene.structures[fb.structure];
    os << (st.motion == fsi::StructureSpec::Motion::bullet ? "  bullet body " : "  free body ") << fb.name
       << ": mass " << mp.mass << (two_d ? " kg/m" : " kg") << ", centre of mass ("
       << mp.centre_of_mass[0] << ", " << mp.centre_of_mass[1];
    if (!two_d) os << ", " << mp.centre_of_mass[2];
    os << ") m";
    if (two_d) {
      os << ", inertia I_zz " << mp.inertia(2, 2) << " kg m^2/m";
    } else {
      os << ", inertia [[" << mp.inertia(0, 0) << ", " << mp.inertia(0, 1) << ", " << mp.inertia(0, 2) << "], ["
         << mp.inertia(1, 0) << ", " << mp.inertia(1, 1) << ", " << mp.inertia(1, 2) << "], [" << mp.inertia(2, 0)
         << ", " << mp.inertia(2, 1) << ", " << mp.inertia(2, 2) << "]] kg m^2";
    }
    if (st.density > 0) os << " (density " << st.density << " kg/m^3";
    else os << " (given mass";
    os << (st.has_centre_of_mass ? ", given centre" : "") << (st.has_inertia ? ", given inertia" : "") << ")";
    std::string locks;
    for (int a = 0; a < 3; ++a) {
      if (st.lock_translation[std::size_t(a)]) locks += std::string(locks.empty() ? "" : ", ") + "xyz"[a];
    }
    for (int a = 0; a < 3; ++a)
      if (st.lock_rotation[std::size_t(a)]) locks += std::string(locks.empty() ? "" : ", ") + "r" + "xyz"[a];
    if (!locks.empty()) os << ", locked " << locks;
    os << "\n";
    const auto& c = st.contact;
    if (!c.given) {
      os << "    contacts: none (no 'contact' material)\n";
    } else if (st.motion == fsi::StructureSpec::Motion::bullet) {
      os << "    contacts: Bullet's rigid contacts, restitution " << c.restitution << ", friction " << c.friction
         << " (walls, fixed and prescribed structures, other bullet bodies)\n";
    } else {
      os << "    contacts: DEM Hertz, E " << c.youngs_modulus << " Pa, Poisson " << c.poisson_ratio << ", restitution "
         << c.restitution << ", friction " << c.friction << " (walls, fixed and prescribed structures, other free bodies)\n";
    }
  }
  {
    bool free_touch = false, bullet_touch = false;
    for (const auto& st : scene.structures) {
      if (!st.contact.given) continue;
      free_touch = free_touch || st.motion == fsi::StructureSpec::Motion::free;
      bullet_touch = bullet_touch || st.motion == fsi::StructureSpec::Motion::bullet;
    }
    if (free_touch && bullet_touch)
      os << "  note: free and bullet bodies do not touch each other (each kind only its own kind and the obstacles)\n";
  }
  for (const auto& ob : scene.open_boundaries)
    os << "  " << (ob.inlet ? "inlet " : "outlet ") << ob.name << ": flow along "
       << (ob.velocity.sign > 0 ? "+" : "-") << "xyz"[ob.velocity.axis]
       << (ob.inlet ? (ob.velocity.parabolic ? ", parabolic profile, mean " : ", uniform ") : "")
       << (ob.inlet ? sig(ob.velocity.mean) + " m/s" : std::string(", pressure = background pressure"))
       << "\n";
  if (s.fluid_removed_by_structures > 0)
    os << "  fluid lattice points left out inside structures: " << s.fluid_removed_by_structures
       << " (the part of their cells outside the structures, " << s.fluid_volume_restored << (two_d ? " m^2" : " m^3")
       << ", goes to the nearest fluid particles)\n";
  if (s.fluid_removed_by_walls > 0)
    os << "  fluid lattice points left out in the cells of box walls: " << s.fluid_removed_by_walls << "\n";
  // Every fluid block and box wall as stated and as built (whole cells from the min corner).
  if (!s.extents.empty())
    os << "  as stated (built: a block's own particles, after structures and earlier blocks took theirs; a wall's "
          "whole cells):\n";
  for (const auto& e : s.extents) {
    os << "  " << e.what << " (line " << e.where.line << "):";
    for (int k = 0; k < scene.dimensions; ++k) {
      os << " " << "xyz"[k] << " " << sig(e.stated.min[k], 6) << " to " << sig(e.stated.max[k], 6);
      const double tol = 1e-6 * scene.particle_spacing;
      if (std::abs(e.built.min[k] - e.stated.min[k]) > tol || std::abs(e.built.max[k] - e.stated.max[k]) > tol)
        os << " (built " << sig(e.built.min[k], 6) << " to " << sig(e.built.max[k], 6) << ")";
      os << ",";
    }
    os << " " << (e.what == "container" ? "inside " : "") << "volume " << sig(e.stated_volume);
    if (std::abs(e.built_volume - e.stated_volume) > 1e-6 * e.stated_volume) {
      char pct[32];
      std::snprintf(pct, sizeof pct, "%+.1f%%", 100 * (e.built_volume / e.stated_volume - 1));
      os << " (built " << sig(e.built_volume) << ", " << pct << ")";
    }
    os << (two_d ? " m^2\n" : " m^3\n");
  }
  const sph::PhysicsParams params = fsi::physics_params(scene);
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    const auto& mat = scene.materials[m];
    os << "  material " << mat.name << ": " << s.particles_per_material[m] << " particles, sound speed "
       << s.sound_speed[m] << " m/s, " << mat.model;
    const bool laminar = scene.numerics.viscosity == fsi::ViscosityKind::laminar;
    const std::string terms = std::string(params.materials[m].implicit_viscosity ? "implicit" : "explicit") +
                              (params.materials[m].full_stress      ? ", full stress"
                               : params.materials[m].central_stress ? ", central pair form"
                                                                    : ", Laplacian form");
    if (mat.model == "newtonian") {
      os << ", viscosity " << mat.viscosity << " Pa s";
      if (laminar && mat.viscosity > 0) os << ", viscous terms " << terms;
      os << "\n";
      continue;
    }
    os << " (yield stress " << mat.yield_stress << " Pa, "
       << (mat.model == "bingham" ? "plastic viscosity " + sig(mat.viscosity) + " Pa s"
                                  : "K " + sig(mat.consistency) + " Pa s^n, n " + sig(mat.flow_index))
       << ", m " << mat.papanastasiou_exponent << " s), ";
    const double bound = params.materials[m].rheology.bound();
    if (mat.max_viscosity > 0) os << "effective viscosity capped at " << mat.max_viscosity << " Pa s (stated)";
    else if (std::isfinite(bound)) os << "largest effective viscosity " << bound << " Pa s (at rest)";
    else os << "effective viscosity unbounded (power law)";
    os << ", viscous terms " << terms << "\n";
  }
  os << "domain           [" << s.domain.min[0] << ", " << s.domain.max[0] << "] x [" << s.domain.min[1] << ", "
     << s.domain.max[1] << "]";
  if (scene.dimensions == 3) os << " x [" << s.domain.min[2] << ", " << s.domain.max[2] << "]";
  os << " m";
  for (int k = 0; k < scene.dimensions; ++k)
    if (s.domain.periodic[k]) os << ", periodic along " << "xyz"[k];
  os << "\n";
  for (const auto& t : scene.transitions)
    os << "transition       " << t.from << " -> " << t.to << " where sqrt(J2) > " << t.shear_stress_threshold
       << " Pa, " << (t.interface_only ? "at interfaces" : "anywhere") << ", " << (1 << scene.dimensions)
       << " daughters (h/2), up to " << t.levels << (t.levels == 1 ? " level" : " levels") << "\n";
  const std::size_t capacity = fsi::particle_capacity(scene, total);
  const sph::CpuMemory& c = s.cpu_memory;
  const double mib = double(capacity) * double(c.total()) / (1024.0 * 1024.0);
  os << "memory           " << c.total() << " bytes/particle on the CPU (fields " << c.fields << ", neighbour list "
     << c.neighbour_list << ", sort " << c.sort;
  if (c.splitting) os << ", splitting " << c.splitting;
  if (c.implicit) os << ", implicit viscosity " << c.implicit;
  os << "), about " << sig(mib, 3) << " MiB";
  if (capacity > total)
    os << " for the " << capacity << " particles reserved (" << (capacity - total) << " for daughters; on_full: "
       << (scene.capacity.error_when_full ? "error" : "warn") << ")";
  {
    // The largest run of this scene's kind this machine holds (its physical memory, all of it).
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    if (pages > 0 && page > 0) {
      const double bytes = double(pages) * double(page);
      os << "; this machine's " << sig(bytes / double(1ull << 30), 3) << " GiB hold about "
         << sig(bytes / double(c.total()) / 1e6, 2) << " million particles";
    }
  }
  os << "\n";
  {
    const sph::DeviceMemory& d = s.device_memory;
    const double dev_mib = double(capacity) * double(d.total()) / (1024.0 * 1024.0);
    os << "device memory    " << d.total() << " bytes/particle on a GPU, about " << sig(dev_mib, 3) << " MiB (fields "
       << d.fields << ", sort " << d.sort;
    if (d.splitting) os << ", splitting " << d.splitting;
    if (d.open_boundaries) os << ", open boundaries " << d.open_boundaries;
    if (d.structures) os << ", structures " << d.structures;
    if (d.implicit) os << ", implicit viscosity " << d.implicit;
    os << ")\n";
  }
  os << "end time         " << scene.end_time << " s, output every " << scene.output.every << " s\n";
  for (const auto& w : s.warnings) os << w << "\n";
  return os.str();
}

// Inputs outside their usual ranges, for a run that blew up within its first steps (issue #27 item
// 2): there the cause is an input, not the flow, and the blown-up particle alone does not say which.
std::string early_blow_up_suspects(const fsi::Scene& scene) {
  std::vector<std::string> out;
  const auto num = [](double v) {
    std::ostringstream os;
    os << std::setprecision(4) << v;
    return os.str();
  };
  const auto& n = scene.numerics;
  if (n.diffusion != fsi::DiffusionKind::none && n.diffusion_delta > 0.5)
    out.push_back("numerics: density_diffusion: delta = " + num(n.diffusion_delta) +
                  " (usually 0.1; the term is explicit, and far above 1 it is unstable at the acoustic time step)");
  if (n.viscosity == fsi::ViscosityKind::artificial && n.artificial_viscosity > 1.0)
    out.push_back("numerics: viscosity: alpha = " + num(n.artificial_viscosity) + " (usually 0.01 to 0.1)");
  if (n.cfl > 0.4) out.push_back("time: cfl = " + num(n.cfl) + " (usually 0.2)");
  if (n.density_ratio_limit < 0.05)
    out.push_back("numerics: max_density_variation = " + num(n.density_ratio_limit) +
                  " (the run stops at that relative density change; a start-up transient can reach a few percent)");
  const double g = std::hypot(scene.gravity[0], scene.gravity[1], scene.gravity[2]);
  if (g > 50) out.push_back("gravity: |g| = " + num(g) + " m/s^2 (" + num(g / 9.81) + " times the Earth's)");
  double lo = 1e300, hi = 0;
  for (const auto& m : scene.materials) {
    lo = std::min(lo, m.density);
    hi = std::max(hi, m.density);
  }
  if (scene.materials.size() > 1 && hi > 10 * lo)
    out.push_back("materials: rest densities from " + num(lo) + " to " + num(hi) +
                  " kg/m^3 (a ratio above 10 needs a smaller time step than the sound speed alone gives)");
  for (const auto& st : scene.structures)
    if (st.motion == fsi::StructureSpec::Motion::free && st.density > 0 && st.density < 0.1 * lo)
      out.push_back("structure '" + st.name + "' (line " + std::to_string(st.where.line) + "): density " +
                    num(st.density) + " kg/m^3, under a tenth of the fluid's (a body that light in explicit "
                                      "coupling is unstable)");
  if (out.empty())
    return "no input is outside its usual range; look at the sound speed against the flow's speed and at the "
           "particle named above";
  std::string s = "check these inputs, outside their usual ranges: ";
  for (std::size_t i = 0; i < out.size(); ++i) s += (i ? "; " : "") + out[i];
  return s;
}

nlohmann::json run_scene(const RunRequest& request) {
  fsi::Scene scene;
  nlohmann::json ck_state;
  fs::path out = request.out;
  std::optional<double> resume_time;
  if (request.resume) {
    const fs::path dir = *request.resume;
    if (out.empty()) out = dir;
    const fs::path saved_scene = dir / "scene.yaml";
    if (!fs::exists(saved_scene))
      throw std::runtime_error(saved_scene.string() + ": not found (is " + dir.string() + " a turbid run directory?)");
    ck_state = read_checkpoint_state(dir / "checkpoint");
    check_run_state(ck_state, dir / "checkpoint" / "checkpoint.json");
    scene = read_scene_file(saved_scene.string(), ck_state.value("scene_directory", std::string()));
    scene.particle_spacing = ck_state.at("particle_spacing").get<double>();
    scene.end_time = ck_state.at("end_time").get<double>();
    resume_time = ck_state.at("time").get<double>();
    if (ck_state.contains("checkpoint_every")) scene.output.checkpoint_every = ck_state["checkpoint_every"].get<double>();
    if (ck_state.contains("inputs")) {
      // The physics must be the checkpoint's: an edited scene.yaml (a sound speed, a wall) or mesh
      // once resumed silently with different physics.
      const nlohmann::json now = input_hashes(saved_scene, scene);
      for (const auto& [name, hash] : ck_state["inputs"].items()) {
        const std::string current = now.contains(name) ? now[name].get<std::string>() : std::string("(not named now)");
        if (current != hash)
          throw std::runtime_error("cannot resume " + dir.string() + ": '" + name +
                                   "' is not the file its checkpoint was written with (hash " + hash.get<std::string>() +
                                   ", now " + current + "); the run would go on with different physics. Put it back "
                                   "as it was, or start a new run");
      }
      for (const auto& [name, hash] : now.items())
        if (!ck_state["inputs"].contains(name))
          throw std::runtime_error("cannot resume " + dir.string() + ": the scene now names '" + name +
                                   "', which its checkpoint was not written with; put scene.yaml back as it was, or "
                                   "start a new run");
    }
    // A resume's scene was checked when the run started; --end and --checkpoint-every on it are
    // checked here (and the end against the checkpoint's time below).
    apply_overrides(scene, request);
  } else {
    // A new run's overrides go in before the scene's checks, which they meet like the scene's own.
    scene = read_scene_file(request.scene_file.string(), {}, overrides_of(request));
  }
  if (resume_time && !(scene.end_time > *resume_time)) {
    // Nothing to run: say so and leave the run directory (and its run.json) as it is.
    std::ostringstream os;
    os << std::setprecision(6);
    if (request.end_time)
      os << "--end " << scene.end_time << " s is not past the time of the checkpoint in " << request.resume->string()
         << " (t = " << *resume_time << " s); give a later end time";
    else
      os << "the run in " << request.resume->string() << " already reached its end time (t = " << *resume_time
         << " s): nothing to resume; add --end T with T > " << *resume_time << " s to continue it further";
    throw std::invalid_argument(os.str());
  }
  if (resume_time) {
    // A run that completed (its run.json says so) up to the end asked for: nothing to do either.
    std::ifstream in(*request.resume / "run.json");
    const nlohmann::json last = in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
    if (last.is_object() && last.value("status", std::string()) == "completed" &&
        last.value("simulated_time", 0.0) >= scene.end_time) {
      std::ostringstream os;
      os << std::setprecision(6) << "the run in " << request.resume->string() << " already finished at t = "
         << last.value("simulated_time", 0.0) << " s (its run.json): nothing to resume up to " << scene.end_time
         << " s; add --end T with a later T to continue it from its checkpoint (t = " << *resume_time << " s)";
      throw std::invalid_argument(os.str());
    }
  }
  fs::create_directories(out);
  remove_leftovers(out);
  if (!request.resume) {
    // Keep the scene beside its results so that a run can be resumed and reproduced.
    const std::string text = read_text(request.scene_file);
    std::ofstream copy(out / "scene.yaml", std::ios::binary);
    copy << text;
    copy.close();
    if (!copy) throw std::runtime_error("cannot write " + (out / "scene.yaml").string() + " (disk full or not writable?)");
  } else if (fs::absolute(out) != fs::absolute(*request.resume)) {
    fs::copy_file(*request.resume / "scene.yaml", out / "scene.yaml", fs::copy_options::overwrite_existing);
  }

  fsi::RunOptions opts;
  opts.backend = request.backend;
  opts.threads = request.threads;
  fsi::Simulation sim(scene, opts);
  const std::size_t initial_particles = sim.store().size();
  const double mass_start = fluid_mass(sim);
  const std::vector<double> momentum_start = fluid_momentum(sim);
  const MaterialTotals materials_start = material_totals(sim);
  Writers writers(out, sim.scene(), resume_time, request.progress);
  writers.set_inputs(request.resume && ck_state.contains("inputs") ? ck_state["inputs"]
                                                                  : input_hashes(out / "scene.yaml", sim.scene()));
  if (request.progress) {
    std::string gpu;
    const bool on_gpu = sim.backend_name() == "cuda" && sph::cuda_device_count(&gpu) > 0;
    std::fprintf(stderr, "turbid: %s, %zu particles (%zu fluid, %zu wall, %zu structure), backend %s%s%s, writing to %s\n",
                 scene.name.c_str(), initial_particles, sim.summary().fluid_particles, sim.summary().wall_particles,
                 sim.summary().structure_particles,
                 sim.backend_name().c_str(), on_gpu ? " on " : "",
                 on_gpu ? gpu.c_str() : (" with " + std::to_string(sim.threads()) + " threads").c_str(),
                 out.string().c_str());
  }
  // Layout warnings (fsi::WorldSummary::warnings) go to stderr whether or not progress is shown.
  for (const auto& w : sim.summary().warnings) std::fprintf(stderr, "%s\n", w.c_str());

  nlohmann::json report;
  report["scene"] = scene.name;
  report["dimensions"] = scene.dimensions;
  report["particle_spacing"] = scene.particle_spacing;
  report["smoothing_length"] = sim.summary().smoothing_length;
  report["fluid_particles"] = sim.summary().fluid_particles;
  report["wall_particles"] = sim.summary().wall_particles;
  if (!scene.structures.empty()) {
    report["structure_particles"] = sim.summary().structure_particles;
    nlohmann::json list = nlohmann::json::array();
    for (const auto& st : sim.summary().structures)
      list.push_back({{"name", st.name}, {"particles", st.particles}, {"surface_area", st.surface_area},
                      {"volume", st.volume}});
    report["structures"] = list;
  }
  report["backend"] = sim.backend_name();
  // The velocity the viscous terms see at walls: the fluid's mirrored at ghost nodes or the wall's own.
  report["wall_treatment"] = {{"type", scene.numerics.boundary == fsi::BoundaryKind::mdbc ? "mdbc" : "dbc"},
                              {"velocity", sim.params().wall_no_slip ? "no_slip" : "wall"}};
  if (sim.params().viscosity == sph::Viscosity::artificial)
    report["wall_treatment"]["artificial_viscosity_approach"] = sim.params().wall_viscosity_normal ? "normal" : "pair";
  if (scene.numerics.wall_function)
    report["wall_treatment"]["wall_function"] = {{"law", "log"}, {"roughness_m", scene.numerics.wall_roughness}};
  report["threads"] = sim.threads();
  {
    // The OpenMP wait the run had (turbid sets passive with a spin of 300 when neither is given;
    // docs/performance.md, "OpenMP on a shared machine").
    const char* policy = std::getenv("OMP_WAIT_POLICY");
    report["omp_wait_policy"] = policy ? policy : "default";
    const char* spin = std::getenv("GOMP_SPINCOUNT");
    report["gomp_spincount"] = spin ? spin : "default";
  }
  report["git_revision"] = TURBID_GIT_REVISION;
  report["version"] = TURBID_VERSION;
  report["units"] = {{"simulated_time", "s"}, {"wall_seconds", "s"}, {"particle_steps_per_second", "1/s"},
                     {"fluid_particle_steps_per_second", "1/s"}, {"fluid_behind_walls_deepest_m", "m"},
                     {"fluid_mass", scene.dimensions == 2 ? "kg/m" : "kg"},
                     {"mass_start", scene.dimensions == 2 ? "kg/m" : "kg"},
                     {"mass_end", scene.dimensions == 2 ? "kg/m" : "kg"},
                     {"fluid_momentum", scene.dimensions == 2 ? "kg m/s per m" : "kg m/s"},
                     {"surface_area", scene.dimensions == 2 ? "m" : "m^2"},
                     {"volume", scene.dimensions == 2 ? "m^2" : "m^3"}};
  std::string status = "completed";
  struct {
    double time = 0;
    std::uint64_t steps = 0, particle_steps = 0;
    double wall_seconds = 0;
  } segment_start;
  try {
    if (request.resume) {
      const auto state = read_checkpoint(*request.resume / "checkpoint", sim.store());
      sim.resume(state.at("time").get<double>(), state.at("steps").get<std::uint64_t>(),
                 state.at("removed").get<std::uint64_t>(), state.at("output_index").get<std::uint64_t>(),
                 state.at("checkpoint_index").get<std::uint64_t>(), state.at("particle_steps").get<std::uint64_t>(),
                 state.value("wall_seconds", 0.0));
      sim.restore_open_boundary_counts(state.value("inflow", std::uint64_t(0)), state.value("outflow", std::uint64_t(0)));
      sim.restore_fluid_particle_steps(state.value("fluid_particle_steps", std::uint64_t(0)));
      sim.restore_wall_put_backs(state.value("wall_put_backs", std::uint64_t(0)));
      sph::WallConstraintTotals constraint;
      constraint.impulse[0] = state.value("wall_constraint_impulse_x", 0.0);
      constraint.impulse[1] = state.value("wall_constraint_impulse_y", 0.0);
      constraint.impulse[2] = state.value("wall_constraint_impulse_z", 0.0);
      constraint.energy = state.value("wall_constraint_energy", 0.0);
      sim.restore_wall_constraint_totals(constraint);
      sph::SplitCounts splits;
      splits.splits = state.value("splits", std::size_t(0));
      splits.daughters = state.value("daughters", std::size_t(0));
      splits.refused = state.value("splits_refused", std::size_t(0));
      splits.smallest_h = state.value("smallest_smoothing_length", 0.0);
      sim.restore_split_totals(splits);
      restore_body_states(sim, state, *request.resume / "checkpoint");
    } else {
      sim.start();
    }
    writers.start_clock(sim);
    segment_start = {sim.time(), sim.steps(), sim.particle_steps(), sim.wall_seconds()};
    const StopSignals signals;
    sim.run(writers);
    if (sim.interrupted()) {
      status = "interrupted";
      report["signal"] = signals.received() == SIGINT ? "SIGINT" : "SIGTERM";
      report["signal_number"] = signals.received();
      report["checkpoint"] = (out / "checkpoint").string();
    }
  } catch (const sph::BlowUp& e) {
    status = "blow-up";
    report["error"] = e.what();
    // Within the first steps the cause is an input: name the ones outside their usual ranges.
    if (sim.steps() <= 20)
      report["error"] = std::string(e.what()) + "; it happened within the first 20 steps, so " +
                        early_blow_up_suspects(scene);
  } catch (const std::exception& e) {
    // A failed write (a full disk, an output path taken by a directory), or a run-time refusal such
    // as a constraint too stiff for the body substeps: the run ends here with run.json saying so
    // (issue #27 item 6); the checkpoint before it, if any, still resumes.
    status = "failed";
    report["error"] = e.what();
  }
  sim.sync_to_host();
  const double mass_end = fluid_mass(sim);
  report["status"] = status;
  report["particles"] = initial_particles;
  report["particles_end"] = sim.store().size();
  report["removed_particles"] = sim.removed();
  // Fluid behind a wall or structure surface at the last output (fsi/wall_penetration.hpp), and
  // the most seen at any output of this process.
  report["fluid_behind_walls"] = sim.fluid_behind_walls().count;
  report["fluid_behind_walls_deepest_m"] = sim.fluid_behind_walls().deepest;
  report["fluid_behind_walls_max"] = writers.most_behind_walls();
  // What impermeable walls did to get there: fluid particles put back on a wall's surface, summed
  // over every drift (a particle counts once per drift).
  report["fluid_put_back_on_walls"] = sim.wall_put_backs();
  // The same per fluid particle-step: the measure of issue #47 item 2 (goal: below 1e-5).
  report["fluid_put_backs_per_particle_step"] =
      sim.fluid_particle_steps() > 0 ? double(sim.wall_put_backs()) / double(sim.fluid_particle_steps()) : 0.0;
  // And what they took from the fluid: the momentum walls and structures received for it (booked
  // on their particles, so forces.csv and moving bodies include it) and the kinetic energy.
  {
    const sph::WallConstraintTotals constraint = sim.wall_constraint_totals();
    nlohmann::json impulse = nlohmann::json::array();
    for (int a = 0; a < scene.dimensions; ++a) impulse.push_back(constraint.impulse[a]);
    report["wall_constraint_impulse"] = impulse;
    report["wall_constraint_energy"] = constraint.energy;
  }
  if (!scene.open_boundaries.empty()) {
    report["buffer_particles"] = sim.summary().buffer_particles;
    report["inflow_particles"] = sim.inflow();
    report["outflow_particles"] = sim.outflow();
  }
  if (!scene.transitions.empty()) {
    const auto& c = sim.split_totals();
    report["capacity"] = sim.store().capacity();
    report["splits"] = c.splits;
    report["daughters_created"] = c.daughters;
    report["splits_refused"] = c.refused;
    // Share of the step time the splitting takes (flag pass every step; insertion, relaxation and
    // rebuild in steps with splits), this process only.
    report["split_wall_seconds"] = sim.split_seconds();
    report["split_share_of_step_time"] = sim.step_seconds() > 0 ? sim.split_seconds() / sim.step_seconds() : 0.0;
  }
  if (sim.params().implicit_viscosity) {
    // Implicit viscosity (sph/implicit_viscosity.hpp): conjugate-gradient iterations per solve (two
    // solves per step), this process only (a resumed run counts from the resume).
    const auto& sv = sim.solver();
    report["viscous_solves"] = sv.viscous_solves();
    report["viscous_iterations_mean_per_solve"] =
        sv.viscous_solves() > 0 ? double(sv.viscous_iterations()) / double(sv.viscous_solves()) : 0.0;
    report["viscous_iterations_max_per_solve"] = sv.viscous_iterations_max();
    report["viscous_unconverged_solves"] = sv.viscous_unconverged();
  }
  report["steps"] = sim.steps();
  report["simulated_time"] = sim.time();
  report["wall_seconds"] = sim.wall_seconds();
  report["particle_steps_per_second"] = sim.particle_steps_per_second();
  // The same with fluid particles only (walls, structures and buffers left out): what a scene's
  // fluid costs, comparable between scenes whose walls differ (issue #24 item 3).
  report["fluid_particle_steps_per_second"] = sim.fluid_particle_steps_per_second();
  if (request.resume) {
    // The whole run's figures above count the segments before the checkpoint too (their wall time
    // is stored in it); this segment's own, this process only:
    const double seg_wall = sim.wall_seconds() - segment_start.wall_seconds;
    const std::uint64_t seg_ps = sim.particle_steps() - segment_start.particle_steps;
    report["segment"] = {{"from_time", segment_start.time},
                         {"steps", sim.steps() - segment_start.steps},
                         {"wall_seconds", seg_wall},
                         {"particle_steps_per_second", seg_wall > 0 ? double(seg_ps) / seg_wall : 0.0}};
  }
  report["fluid_mass_start"] = mass_start;
  report["fluid_mass_end"] = mass_end;
  report["fluid_mass_relative_change"] = (mass_end - mass_start) / mass_start;
  // The whole system's momentum: the fluid's, since walls and structures are fixed.
  report["fluid_momentum_start"] = momentum_start;
  report["fluid_momentum_end"] = fluid_momentum(sim);
  const MaterialTotals materials_end = material_totals(sim);
  nlohmann::json per_material = nlohmann::json::array();
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    per_material.push_back({{"name", scene.materials[m].name}, {"model", scene.materials[m].model},
                            {"particles_start", materials_start.particles[m]},
                            {"particles_end", materials_end.particles[m]}, {"mass_start", materials_start.mass[m]},
                            {"mass_end", materials_end.mass[m]}});
  report["materials"] = per_material;
  try {
    write_run_json(out / "run.json", report);
  } catch (const std::exception& e) {
    // The disk may be full: the caller still says where the outputs are and how to resume.
    report["run_json_error"] = e.what();
  }
  return report;
}

}  // namespace turbid::tools
