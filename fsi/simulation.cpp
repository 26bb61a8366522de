// Building the particle world and running the time loop; see simulation.hpp.
#include "fsi/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fsi/probes.hpp"
#include "geometry/shapes.hpp"
#include "sph/vec.hpp"

namespace turbid::fsi {
namespace {

double gravity_norm(const Scene& s) {
  return std::sqrt(s.gravity[0] * s.gravity[0] + s.gravity[1] * s.gravity[1] + s.gravity[2] * s.gravity[2]);
}

// Height of a point against gravity [m] (0 without gravity).
double height_of(const Scene& s, const Vec3d& x) {
  const double g = gravity_norm(s);
  if (g == 0) return 0;
  return -(x[0] * s.gravity[0] + x[1] * s.gravity[1] + x[2] * s.gravity[2]) / g;
}

// Lowest and highest point of a box against gravity [m].
struct HeightRange {
  double bottom, top;
  double extent() const { return top - bottom; }
};

HeightRange box_heights(const Scene& s, const Box& b) {
  HeightRange r{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  const int corners = s.dimensions == 2 ? 4 : 8;
  for (int c = 0; c < corners; ++c) {
    Vec3d x{(c & 1) ? b.max[0] : b.min[0], (c & 2) ? b.max[1] : b.min[1], 0.0};
    if (s.dimensions == 3) x[2] = (c & 4) ? b.max[2] : b.min[2];
    r.bottom = std::min(r.bottom, height_of(s, x));
    r.top = std::max(r.top, height_of(s, x));
  }
  return r;
}

geometry::Aabb to_aabb(const Box& b) { return {b.min, b.max}; }

}  // namespace

int wall_layers(const Scene& scene, const WallSpec& wall) {
  if (wall.layers > 0) return wall.layers;
  // Enough layers to fill the kernel support 2h seen from the first fluid row.
  return std::max(1, int(std::ceil(2.0 * scene.smoothing_ratio - 1e-9)));
}

sph::PhysicsParams physics_params(const Scene& scene) {
  sph::PhysicsParams p;
  p.dimensions = scene.dimensions;
  p.kernel = scene.numerics.kernel;
  switch (scene.numerics.diffusion) {
    case DiffusionKind::none: p.diffusion = sph::Diffusion::none; break;
    case DiffusionKind::molteni: p.diffusion = sph::Diffusion::molteni; break;
    case DiffusionKind::antuono: p.diffusion = sph::Diffusion::antuono; break;
    case DiffusionKind::fourtakas: p.diffusion = sph::Diffusion::fourtakas; break;
  }
  p.viscosity = scene.numerics.viscosity == ViscosityKind::laminar ? sph::Viscosity::laminar : sph::Viscosity::artificial;
  p.diffusion_delta = sph::Real(scene.numerics.diffusion_delta);
  p.artificial_viscosity = sph::Real(scene.numerics.artificial_viscosity);
  p.smoothing_length = sph::Real(scene.smoothing_ratio * scene.particle_spacing);
  p.uniform_h = true;
  p.max_smoothing_length = p.smoothing_length;
  for (int k = 0; k < 3; ++k) p.gravity[k] = sph::Real(k < scene.dimensions ? scene.gravity[k] : 0.0);
  if (scene.materials.empty()) throw std::invalid_argument("the scene declares no material");
  if (int(scene.materials.size()) > sph::kMaxMaterials)
    throw std::invalid_argument("at most " + std::to_string(sph::kMaxMaterials) + " materials are supported");
  // Automatic sound speed: 10 x the largest free-fall speed sqrt(2 g H) over the fluid columns,
  // which keeps density variations near 1% (Monaghan 1994).
  double column = 0;
  for (const auto& f : scene.fluids) column = std::max(column, box_heights(scene, f.box).extent());
  const double auto_c0 = std::max(1.0, 10.0 * std::sqrt(2.0 * gravity_norm(scene) * column));
  p.material_count = int(scene.materials.size());
  for (std::size_t m = 0; m < scene.materials.size(); ++m) {
    const auto& ms = scene.materials[m];
    const double c0 = ms.sound_speed > 0 ? ms.sound_speed : auto_c0;
    p.materials[m].eos = sph::TaitEos::make(ms.density, c0, ms.gamma, ms.background_pressure);
    p.materials[m].sound_speed = sph::Real(c0);
    p.materials[m].dynamic_viscosity = sph::Real(ms.viscosity);
  }
  p.wall_material = 0;
  return p;
}

Simulation::Simulation(Scene scene, const RunOptions& options) : scene_(std::move(scene)) {
  params_ = physics_params(scene_);
  ids_ = sph::register_fields(store_, params_);
  build_particles();

  std::unique_ptr<sph::Backend> backend;
  if (options.backend == "cpu") {
    backend = sph::make_cpu_backend(options.threads);
  } else if (options.backend == "cuda") {
    backend = sph::make_cuda_backend();
  } else if (options.backend == "auto") {
    std::string why;
    backend = sph::cuda_device_count(&why) > 0 ? sph::make_cuda_backend() : sph::make_cpu_backend(options.threads);
  } else {
    throw std::invalid_argument("unknown backend '" + options.backend + "' (expected auto, cpu or cuda)");
  }
  backend_name_ = backend->name();
  threads_ = backend->threads();
  sph::TimeStepParams tp;
  tp.cfl = scene_.numerics.cfl;
  tp.viscous_factor = scene_.numerics.viscous_dt_factor;
  tp.min_time_step = scene_.numerics.min_time_step;
  tp.density_ratio_limit = scene_.numerics.density_ratio_limit;
  solver_ = std::make_unique<sph::Solver>(store_, ids_, params_, summary_.domain, tp, std::move(backend));
}

void Simulation::build_particles() {
  const Scene& s = scene_;
  const int d = s.dimensions;
  const double dx = s.particle_spacing;
  const double cell_volume = std::pow(dx, d);
  const double g = gravity_norm(s);

  struct Item {
    geometry::Point x;
    double density;
    std::uint8_t material;
    sph::Kind kind;
  };
  std::vector<Item> items;
  summary_.particles_per_material.assign(s.materials.size(), 0);

  auto material_of = [&](const std::string& name, const SourceLocation& where) {
    for (std::size_t m = 0; m < s.materials.size(); ++m)
      if (s.materials[m].name == name) return std::uint8_t(m);
    std::ostringstream os;
    os << where.file << ":" << where.line << ":" << where.column << ": error: unknown material '" << name << "'";
    throw std::invalid_argument(os.str());
  };

  double global_top = -std::numeric_limits<double>::infinity();
  for (const auto& f : s.fluids) global_top = std::max(global_top, box_heights(s, f.box).top);

  for (const auto& f : s.fluids) {
    const std::uint8_t m = material_of(f.material, f.where);
    const auto& eos = params_.materials[m].eos;
    const HeightRange heights = box_heights(s, f.box);
    const double top = heights.top;
    const double column = heights.extent();
    // Weak compressibility: the hydrostatic density at the bottom must stay near rho0.
    const double bottom_ratio = eos.hydrostatic_density(g, column) / eos.rest_density - 1.0;
    if (bottom_ratio > 0.1) {
      const auto& ms = s.materials[m];
      std::ostringstream os;
      os << ms.where.file << ":" << ms.where.line << ":" << ms.where.column << ": error: material '" << ms.name
         << "': sound speed " << params_.materials[m].sound_speed << " m/s compresses the " << column
         << " m column by " << 100 * bottom_ratio << "% at rest; weakly compressible SPH needs about 1% (sound speed >= "
         << 10 * std::sqrt(2 * g * column) << " m/s, ten times the free-fall speed)";
      throw std::invalid_argument(os.str());
    }
    for (const auto& x : geometry::fill_box(to_aabb(f.box), dx, d)) {
      const double depth = std::max(0.0, top - height_of(s, x));
      items.push_back({x, eos.hydrostatic_density(g, depth), m, sph::Kind::fluid});
      ++summary_.particles_per_material[m];
    }
  }
  summary_.fluid_particles = items.size();

  const auto& wall_eos = params_.materials[params_.wall_material].eos;
  for (const auto& w : s.walls) {
    const int layers = wall_layers(s, w);
    std::vector<geometry::Point> pts;
    switch (w.kind) {
      case WallSpec::Kind::container: pts = geometry::container_walls(to_aabb(w.box), dx, d, layers, w.open); break;
      case WallSpec::Kind::solid_box: pts = geometry::box_shell(to_aabb(w.box), dx, d, w.layers); break;
      case WallSpec::Kind::polyline: pts = geometry::polyline_walls(w.points, w.closed, dx, layers, w.side); break;
    }
    for (const auto& x : pts) {
      // Walls start at the hydrostatic density of the water above them, so the first steps carry
      // no pressure jump between fluid and wall.
      const double depth = std::isfinite(global_top) ? std::max(0.0, global_top - height_of(s, x)) : 0.0;
      items.push_back({x, wall_eos.hydrostatic_density(g, depth), 0, sph::Kind::wall});
    }
  }
  summary_.wall_particles = items.size() - summary_.fluid_particles;
  if (summary_.fluid_particles == 0) throw std::invalid_argument("the scene has no fluid particles");

  // Domain: as given, or the particles' bounding box grown by 10% per side.
  if (s.domain) {
    for (int k = 0; k < 3; ++k) {
      summary_.domain.min[k] = s.domain->min[k];
      summary_.domain.max[k] = s.domain->max[k];
    }
  } else {
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (const auto& it : items)
      for (int k = 0; k < d; ++k) {
        lo[k] = std::min(lo[k], it.x[k]);
        hi[k] = std::max(hi[k], it.x[k]);
      }
    for (int k = 0; k < d; ++k) {
      const double margin = std::max(0.1 * (hi[k] - lo[k]), 4.0 * double(params_.smoothing_length));
      summary_.domain.min[k] = lo[k] - margin;
      summary_.domain.max[k] = hi[k] + margin;
    }
  }

  store_.resize(items.size());
  auto* x = static_cast<sph::Real*>(store_.raw(ids_.position));
  auto* rho = store_.data<sph::Real>(ids_.density);
  auto* mass = store_.data<sph::Real>(ids_.mass);
  auto* h = store_.data<sph::Real>(ids_.smoothing_length);
  auto* mat = store_.data<std::uint8_t>(ids_.material);
  auto* kind = store_.data<std::uint8_t>(ids_.kind);
  auto* id = store_.data<std::uint32_t>(ids_.id);
  for (std::size_t i = 0; i < items.size(); ++i) {
    for (int k = 0; k < d; ++k) x[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].x[k]);
    rho[i] = sph::Real(items[i].density);
    mass[i] = sph::Real(items[i].density * cell_volume);  // V = m / rho = dx^d
    h[i] = params_.smoothing_length;
    mat[i] = items[i].material;
    kind[i] = std::uint8_t(items[i].kind);
    id[i] = std::uint32_t(i);
  }
  summary_.smoothing_length = params_.smoothing_length;
  for (int m = 0; m < params_.material_count; ++m) summary_.sound_speed.push_back(params_.materials[m].sound_speed);
  // Store fields plus the neighbour search's keys, order and permutation scratch.
  summary_.bytes_per_particle = store_.bytes_per_particle() + 12;
}

double Simulation::particle_steps_per_second() const {
  return wall_seconds_ > 0 ? double(particle_steps_) / wall_seconds_ : 0.0;
}

void Simulation::start() { solver_->start(); }

void Simulation::resume(double time, std::uint64_t steps, std::uint64_t removed, std::uint64_t output_index,
                        std::uint64_t checkpoint_index, std::uint64_t particle_steps) {
  solver_->resume(time, steps, removed);
  output_index_ = output_index;
  checkpoint_index_ = checkpoint_index;
  particle_steps_ = particle_steps;
}

void Simulation::step() {
  const double dt = solver_->next_time_step();
  particle_steps_ += store_.size();
  solver_->step(dt);
}

std::vector<double> Simulation::probe_values() {
  sync_to_host();
  return evaluate_probes(scene_, store_, ids_, params_);
}

void Simulation::run(Observer& observer) {
  using clock = std::chrono::steady_clock;
  const double every = scene_.output.every;
  const double ck_every = scene_.output.checkpoint_every;
  // Output k is due at time k * every; the first step at or past that time writes it.
  auto output_due = [&] { return every > 0 ? double(output_index_) * every : 0.0; };
  if (output_index_ == 0 || time() >= output_due()) {
    sync_to_host();
    observer.on_output(*this);
    ++output_index_;
  }
  const auto t0 = clock::now();
  const double wall_before = wall_seconds_;
  auto last_progress = t0;
  while (time() < scene_.end_time) {
    step();
    const auto now = clock::now();
    wall_seconds_ = wall_before + std::chrono::duration<double>(now - t0).count();
    const bool last = time() >= scene_.end_time;
    if ((every > 0 && time() >= output_due()) || last) {
      sync_to_host();
      observer.on_output(*this);
      if (every > 0)
        while (double(output_index_) * every <= time()) ++output_index_;
    }
    if (ck_every > 0 && time() >= double(checkpoint_index_ + 1) * ck_every) {
      while (double(checkpoint_index_ + 1) * ck_every <= time()) ++checkpoint_index_;
      sync_to_host();
      observer.on_checkpoint(*this);
    }
    if (std::chrono::duration<double>(now - last_progress).count() >= 0.5 || last) {
      observer.on_progress(*this);
      last_progress = now;
    }
  }
  sync_to_host();
  observer.on_finish(*this);
}

}  // namespace turbid::fsi
