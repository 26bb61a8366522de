// Building the particle world and running the time loop; see simulation.hpp.
#include "fsi/simulation.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "fsi/bullet_world.hpp"
#include "fsi/probes.hpp"
#include "fsi/scene_interactions.hpp"
#include "geometry/mesh.hpp"
#include "geometry/primitives.hpp"
#include "geometry/shapes.hpp"
#include "geometry/solid.hpp"
#include "sph/boundary_passes.hpp"
#include "sph/vec.hpp"

namespace turbid::fsi {
namespace {

// The part of gravity that builds a hydrostatic pressure: along a periodic axis it is a uniform
// body force that drives the flow (a channel), with no head to balance it.
Vec3d hydrostatic_gravity(const Scene& s) {
  Vec3d g = s.gravity;
  for (std::size_t k = 0; k < 3; ++k)
    if (s.periodic[k]) g[k] = 0;
  return g;
}

double gravity_norm(const Scene& s) {
  const Vec3d g = hydrostatic_gravity(s);
  return std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
}

// Height of a point against (hydrostatic) gravity [m] (0 without gravity).
double height_of(const Scene& s, const Vec3d& x) {
  const double g = gravity_norm(s);
  if (g == 0) return 0;
  const Vec3d gv = hydrostatic_gravity(s);
  return -(x[0] * gv[0] + x[1] * gv[1] + x[2] * gv[2]) / g;
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

// Length of the ray x + t u (t >= 0) inside box b (first d axes; slab method) [m].
double ray_length_in_box(const Vec3d& x, const Vec3d& u, const Box& b, int d) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < d; ++k) {
    if (std::abs(u[k]) < 1e-12) {
      if (x[k] < b.min[k] || x[k] > b.max[k]) return 0;
      continue;
    }
    double ta = (b.min[k] - x[k]) / u[k], tb = (b.max[k] - x[k]) / u[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return std::max(0.0, t1 - t0);
}

// The second axis of a polygon's or polyline's plane: y in 2D; in 3D the cross-section lies in the
// vertical x-z plane and is extruded across y (scene.hpp).
int section_axis(int dims) { return dims == 3 ? 2 : 1; }

// Point strictly inside a 2D polygon (crossing number).
bool inside_polygon(const std::vector<Vec3d>& poly, double x, double y) {
  bool in = false;
  for (std::size_t a = 0, b = poly.size() - 1; a < poly.size(); b = a++) {
    const double ya = poly[a][1], yb = poly[b][1];
    if ((ya > y) != (yb > y) && x < (poly[b][0] - poly[a][0]) * (y - ya) / (yb - ya) + poly[a][0]) in = !in;
  }
  return in;
}

// The fluid block a point belongs to: the first whose region holds it (blocks listed earlier win
// where regions overlap, so a slide can be cut out of the water around it); -1 for none.
bool in_block(const Scene& s, const FluidBlock& f, const Vec3d& x) {
  bool in = true;
  for (int k = 0; k < s.dimensions; ++k) in = in && x[k] >= f.box.min[k] && x[k] <= f.box.max[k];
  return in && (f.polygon.empty() || inside_polygon(f.polygon, x[0], x[section_axis(s.dimensions)]));
}

int block_of(const Scene& s, const Vec3d& x, std::size_t first_n = ~std::size_t(0)) {
  for (std::size_t b = 0; b < s.fluids.size() && b < first_n; ++b)
    if (in_block(s, s.fluids[b], x)) return int(b);
  return -1;
}

// Some fluid regions overlap (a slide cut out of the water around it): their layered start must
// count each point once, for the block that owns it.
bool blocks_overlap(const Scene& s) {
  for (std::size_t a = 0; a < s.fluids.size(); ++a)
    for (std::size_t b = a + 1; b < s.fluids.size(); ++b) {
      bool o = true;
      for (int k = 0; k < s.dimensions; ++k)
        o = o && s.fluids[a].box.min[k] < s.fluids[b].box.max[k] && s.fluids[b].box.min[k] < s.fluids[a].box.max[k];
      if (o) return true;
    }
  return false;
}

// Hydrostatic gauge pressure at x under fluid blocks of several densities (layers) [Pa]: the
// weight of the fluid above x, sum over blocks of rho0 g times the length of the upward vertical
// through x inside the block (physics.md D8: p = rho_w g H_w + rho_s g (z_i - z) in the lower layer).
double layered_pressure(const Scene& s, const sph::PhysicsParams& p, const Vec3d& x,
                        const std::vector<std::uint8_t>& block_material) {
  const double g = gravity_norm(s);
  if (g == 0) return 0;
  const Vec3d gv = hydrostatic_gravity(s);
  const Vec3d up{-gv[0] / g, -gv[1] / g, -gv[2] / g};
  bool polygons = false;
  for (const auto& f : s.fluids) polygons = polygons || !f.polygon.empty();
  double pressure = 0;
  if (!polygons && !blocks_overlap(s)) {
    for (std::size_t b = 0; b < s.fluids.size(); ++b)
      pressure += double(p.materials[block_material[b]].eos.rest_density) * g *
                  ray_length_in_box(x, up, s.fluids[b].box, s.dimensions);
    return pressure;
  }
  // Polygons or overlapping blocks (earlier blocks winning): midpoint rule along the vertical in
  // steps of dx/8 up to the top of all blocks. (In 2D the third components are 0, so the sums
  // below are those of the plane, bit for bit.)
  double top = -1e300;
  const int corners = s.dimensions == 3 ? 8 : 4;
  for (const auto& f : s.fluids)
    for (int c = 0; c < corners; ++c) {
      const Vec3d corner{(c & 1) ? f.box.max[0] : f.box.min[0], (c & 2) ? f.box.max[1] : f.box.min[1],
                         s.dimensions == 3 ? ((c & 4) ? f.box.max[2] : f.box.min[2]) : 0.0};
      top = std::max(top, corner[0] * up[0] + corner[1] * up[1] + corner[2] * up[2]);
    }
  const double length = top - (x[0] * up[0] + x[1] * up[1] + x[2] * up[2]);
  const double step = s.particle_spacing / 8;
  for (double t = 0.5 * step; t < length; t += step) {
    const int b = block_of(s, {x[0] + t * up[0], x[1] + t * up[1], x[2] + t * up[2]});
    if (b >= 0) pressure += double(p.materials[block_material[std::size_t(b)]].eos.rest_density) * g * step;
  }
  return pressure;
}

using geometry::Point;

Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot3(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// mDBC ghost offsets x_g - x_b = 2 (q - x_b), q the nearest point of the wall surface (English et
// al. 2022: the ghost node is the particle mirrored across the boundary).
Point ghost_container(const Box& box, const Point& x, int d) {
  // The container's fluid side is the box; wall particles lie outside it.
  Point n{0, 0, 0};
  for (int k = 0; k < d; ++k) n[k] = 2.0 * (std::clamp(x[k], box.min[k], box.max[k]) - x[k]);
  return n;
}

// hidden[2 k] / hidden[2 k + 1]: the min / max face on axis k rests on another wall (a box on the
// floor of its tank), so no fluid reaches it and it is not a surface.
Point ghost_solid_box(const Box& box, const Point& x, int d, const std::array<bool, 6>& hidden) {
  // Particles fill the box; the nearest exposed face is the surface.
  int best_axis = 0;
  double best = std::numeric_limits<double>::infinity(), target = 0;
  for (int k = 0; k < d; ++k) {
    for (int side = 0; side < 2; ++side) {
      if (hidden[std::size_t(2 * k + side)]) continue;
      const double face = side == 0 ? box.min[k] : box.max[k];
      const double dist = std::abs(face - x[k]);
      if (dist < best) {
        best = dist;
        best_axis = k;
        target = face;
      }
    }
  }
  Point n{0, 0, 0};
  n[best_axis] = 2.0 * (target - x[best_axis]);
  return n;
}

// In 3D the wall is the cross-section's polyline extruded across y: the nearest surface point is
// the nearest point of the polyline in the x-z plane at the particle's own y, so the ghost offset
// has no y component.
Point ghost_polyline(const WallSpec& w, const Point& x3, int d) {
  const int v = section_axis(d);
  const Point x{x3[0], x3[v], 0.0};  // in the section's plane
  double best = std::numeric_limits<double>::infinity();
  Point q_best = x;
  const std::size_t n = w.points.size();
  const std::size_t segments = w.closed ? n : n - 1;
  for (std::size_t s = 0; s < segments; ++s) {
    const Point a = w.points[s], b = w.points[(s + 1) % n];
    const Point ab = sub(b, a);
    const double t = std::clamp(dot3(sub(x, a), ab) / dot3(ab, ab), 0.0, 1.0);
    const Point q{a[0] + t * ab[0], a[1] + t * ab[1], 0.0};
    const Point dq = sub(q, x);
    const double dist = dot3(dq, dq);
    if (dist < best) {
      best = dist;
      q_best = q;
    }
  }
  const Point g{2.0 * (q_best[0] - x[0]), 2.0 * (q_best[1] - x[1]), 0.0};
  return d == 3 ? Point{g[0], 0.0, g[1]} : g;
}

// Initial velocity of a fluid block at x: along the profile's axis, uniform or parabolic across
// the block's transverse extent (mean `mean`), as an inlet prescribes it.
Point profile_velocity(const VelocityProfile& p, const Box& box, const Point& x, int d) {
  Point v{0, 0, 0};
  if (!p.given) return v;
  double u = p.mean;
  if (p.parabolic)
    for (int a = 0; a < d; ++a) {
      if (a == p.axis) continue;
      const double s = std::clamp((x[a] - box.min[a]) / (box.max[a] - box.min[a]), 0.0, 1.0);
      u *= 6.0 * s * (1.0 - s);
    }
  v[p.axis] = p.sign * u;
  return v;
}

geometry::Placement placement_of(const StructureSpec& st) {
  geometry::Placement place;
  place.translation = st.position;
  place.rotation_deg = st.rotation_deg;
  place.scale = st.scale;
  return place;
}

// `mesh`: the structure's mesh, loaded once by the caller (mesh structures only).
geometry::SampledBody sample_structure(const StructureSpec& st, double dx, int dims, int layers,
                                       const geometry::TriangleMesh* mesh = nullptr) {
  const geometry::Placement place = placement_of(st);
  switch (st.shape) {
    case StructureSpec::Shape::box: return geometry::sample_box(st.size, dx, layers, dims, place);
    case StructureSpec::Shape::sphere: return geometry::sample_sphere(st.radius, dx, layers, dims, place);
    case StructureSpec::Shape::cylinder: return geometry::sample_cylinder(st.radius, st.length, dx, layers, dims, place);
    case StructureSpec::Shape::mesh:
      return geometry::sample_mesh(mesh ? *mesh : geometry::load_mesh(st.resolved_file), dx, layers, dims, place);
  }
  return {};
}

MassProperties mass_properties_of(const Scene& scene, const StructureSpec& st, const geometry::TriangleMesh* mesh) {
  const int d = scene.dimensions;
  const geometry::SampledBody filled = sample_structure(st, scene.particle_spacing, d, 0, mesh);
  double volume = 0;
  for (double v : filled.volumes) volume += v;
  if (!(volume > 0)) throw std::invalid_argument("its filled sampling has no volume at this particle spacing");
  const double density = st.density > 0 ? st.density : st.mass / volume;
  MassProperties mp = mass_properties(filled, density, d);
  if (st.mass > 0) mp.mass = st.mass;
  if (st.has_centre_of_mass) {
    // The sampled inertia is about the sampled centre; move it to the given one (parallel axes).
    const Eigen::Vector3d c(st.centre_of_mass[0], st.centre_of_mass[1], d == 3 ? st.centre_of_mass[2] : 0.0);
    const Eigen::Vector3d r = c - mp.centre_of_mass;
    mp.inertia += mp.mass * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    mp.centre_of_mass = c;
  }
  if (st.has_inertia) {
    if (d == 2) {
      // Only I_zz enters planar motion; the lamina's other moments keep their sampled proportions.
      mp.inertia *= st.inertia[8] / mp.inertia(2, 2);
    } else {
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) mp.inertia(a, b) = st.inertia[std::size_t(3 * a + b)];
    }
  }
  return mp;
}

// The solid of a structure, for its exact signed distance (geometry/solid.hpp).
geometry::Solid structure_solid(const StructureSpec& st, int dims, const geometry::TriangleMesh* mesh) {
  const geometry::Placement place = placement_of(st);
  switch (st.shape) {
    case StructureSpec::Shape::box: return geometry::Solid::box(st.size, dims, place);
    case StructureSpec::Shape::sphere: return geometry::Solid::sphere(st.radius, dims, place);
    case StructureSpec::Shape::cylinder: return geometry::Solid::cylinder(st.radius, st.length, dims, place);
    case StructureSpec::Shape::mesh:
      return geometry::Solid::mesh(mesh ? *mesh : geometry::load_mesh(st.resolved_file), dims, place);
  }
  throw std::invalid_argument("unknown structure shape");
}

// Which fluid lattice points lie inside a structure or closer than half a spacing to its surface:
// a point is left out iff its exact signed distance to some structure's solid (negative inside) is
// below dx/2 (1 - 1e-6). The distance is that of the shape itself (box, sphere, cylinder, the mesh's
// triangles), so beyond convex edges and corners it is the distance to the edge or corner.
class StructureCarver {
 public:
  StructureCarver(std::vector<geometry::Solid> solids, double dx) : solids_(std::move(solids)), dx_(dx) {}

  bool blocks(const Point& p) const {
    const double limit = 0.5 * dx_ * (1.0 - 1e-6);
    // Cut-off dx > limit: the early exits of the meshes still decide "< limit" exactly.
    return distance(p, dx_) < limit;
  }

  // The signed distance of p to structure k, exact where it is below `cutoff`.
  double distance_to(std::size_t k, const Point& p, double cutoff) const { return solids_[k].signed_distance(p, cutoff); }

  // The smallest signed distance of p to the structures, exact where it is below `cutoff`.
  double distance(const Point& p, double cutoff) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& s : solids_) best = std::min(best, s.signed_distance(p, cutoff));
    return best;
  }

 private:
  std::vector<geometry::Solid> solids_;
  double dx_;
};

// Lattice carving leaves out whole cells: a lattice point within dx/2 of a structure takes its cell
// with it, also the part of the cell outside the structure, so the fluid would be short of that
// volume (a hole up to dx/2 wider than the body all round: +21% for a 0.15 m cube at dx = 0.02 m
// whose faces fall mid-cell, and that much more buoyancy). Each carved cell is therefore sampled at
// 8^d stratified points; every sample outside all structures hands its share of the cell's volume to the
// nearest kept lattice point of the same fluid block among the carved cell's 3^d neighbours, whose
// particle then stands for its cell plus that part of the gap (mass = rho V); `moments` gets the
// first moment sum V_s y_s of the samples each point receives (the caller moves the particle to the
// centroid of its cell and samples). Returns the volume handed over [m^d]; samples with no kept
// neighbour (a sliver between two structures) are dropped.
double restore_carved_volume(const StructureCarver& carver, const geometry::Aabb& box, double dx, int d,
                             const std::vector<Point>& carved, const std::vector<Point>& kept,
                             const std::vector<double*>& volumes, std::vector<Point>& moments) {
  // Samples per cell edge, a multiple of 4: no sample lies on a face at a quarter or half cell.
  constexpr int kSub = 8;
  auto index_of = [&](const Point& x, int k) { return long(std::floor((x[k] - box.min[k]) / dx)); };
  long n[3] = {1, 1, 1};
  for (int k = 0; k < d; ++k) n[k] = std::max(1L, long(std::llround((box.max[k] - box.min[k]) / dx)) + 1);
  auto key = [&](long i, long j, long k) { return (k * n[1] + j) * n[0] + i; };
  std::unordered_map<long, std::size_t> at;
  at.reserve(kept.size());
  for (std::size_t q = 0; q < kept.size(); ++q)
    at.emplace(key(index_of(kept[q], 0), index_of(kept[q], 1), d == 3 ? index_of(kept[q], 2) : 0), q);
  const double sub_volume = std::pow(dx / kSub, d);
  const double reach = 0.5 * std::sqrt(double(d)) * dx;  // a cell's corner from its centre
  double restored = 0;
  for (const auto& c : carved) {
    if (carver.distance(c, 2 * dx) < -reach) continue;  // the whole cell lies inside a structure
    const long ci = index_of(c, 0), cj = index_of(c, 1), ck = d == 3 ? index_of(c, 2) : 0;
    const int sz = d == 3 ? kSub : 1;
    for (int a = 0; a < kSub; ++a)
      for (int b = 0; b < kSub; ++b)
        for (int e = 0; e < sz; ++e) {
          Point y = c;
          y[0] += ((a + 0.5) / kSub - 0.5) * dx;
          y[1] += ((b + 0.5) / kSub - 0.5) * dx;
          if (d == 3) y[2] += ((e + 0.5) / kSub - 0.5) * dx;
          if (carver.distance(y, dx) <= 0) continue;
          double best = std::numeric_limits<double>::infinity();
          std::size_t owner = kept.size();
          for (long dk = (d == 3 ? -1 : 0); dk <= (d == 3 ? 1 : 0); ++dk)
            for (long dj = -1; dj <= 1; ++dj)
              for (long di = -1; di <= 1; ++di) {
                const auto it = at.find(key(ci + di, cj + dj, ck + dk));
                if (it == at.end()) continue;
                double r2 = 0;
                for (int k = 0; k < d; ++k) r2 += (kept[it->second][k] - y[k]) * (kept[it->second][k] - y[k]);
                if (r2 < best) {
                  best = r2;
                  owner = it->second;
                }
              }
          if (owner == kept.size()) continue;
          *volumes[owner] += sub_volume;
          for (int k = 0; k < d; ++k) moments[owner][k] += sub_volume * y[k];
          restored += sub_volume;
        }
  }
  return restored;
}


// Cells of side dx holding point indices, for "is any point of this set within r of x" (r <= dx).
class PointHash {
 public:
  PointHash(const std::vector<Point>& x, std::size_t first, std::size_t last, double dx, int d)
      : x_(x), dx_(dx), d_(d) {
    for (std::size_t i = first; i < last; ++i) cells_[key(cell(x[i]))].push_back(i);
  }
  bool any_within(const Point& p, double r) const {
    const std::array<long, 3> c = cell(p);
    for (long k = (d_ == 3 ? -1 : 0); k <= (d_ == 3 ? 1 : 0); ++k)
      for (long j = -1; j <= 1; ++j)
        for (long i = -1; i <= 1; ++i) {
          const auto it = cells_.find(key({c[0] + i, c[1] + j, c[2] + k}));
          if (it == cells_.end()) continue;
          for (std::size_t q : it->second) {
            double r2 = 0;
            for (int a = 0; a < d_; ++a) r2 += (x_[q][a] - p[a]) * (x_[q][a] - p[a]);
            if (r2 < r * r) return true;
          }
        }
    return false;
  }

 private:
  std::array<long, 3> cell(const Point& p) const {
    return {long(std::floor(p[0] / dx_)), long(std::floor(p[1] / dx_)), d_ == 3 ? long(std::floor(p[2] / dx_)) : 0L};
  }
  static long long key(const std::array<long, 3>& c) {
    return (static_cast<long long>(c[2] & 0x1fffff) << 42) | (static_cast<long long>(c[1] & 0x1fffff) << 21) |
           static_cast<long long>(c[0] & 0x1fffff);
  }
  const std::vector<Point>& x_;
  double dx_;
  int d_;
  std::unordered_map<long long, std::vector<std::size_t>> cells_;
};

static std::string at_text(const SourceLocation& w, const char* what) {
  std::ostringstream os;
  os << w.file << ":" << w.line << ":" << w.column << ": " << what << ": ";
  return os.str();
}

static bool moves(const StructureSpec& st) { return st.motion != StructureSpec::Motion::fixed; }

// Layout checks on the particles as built (issue #27 item 2): errors (std::invalid_argument,
// located) for what cannot be meant, warnings (returned, located) for what may be. x holds the fluid
// blocks, then the walls, then the structures, in scene order; *_first[k] is where item k starts
// (one more entry at the end).
std::vector<std::string> check_layout(const Scene& s, const sph::Domain& domain, const std::vector<Point>& x,
                                      const std::vector<std::size_t>& block_first,
                                      const std::vector<std::size_t>& wall_first,
                                      const std::vector<std::size_t>& structure_first, const StructureCarver& carver) {
  std::vector<std::string> warnings;
  const int d = s.dimensions;
  const double dx = s.particle_spacing;
  const double touch = 0.5 * dx * (1 - 1e-6);  // closer than this, two particles fill the same space
  const auto wall_name = [&](std::size_t w) {
    return "wall " + std::to_string(w + 1) + " of 'walls' (line " + std::to_string(s.walls[w].where.line) + ")";
  };
  // 1. A structure reaching out of the stated domain loses the particles there at the start.
  if (s.domain)
    for (std::size_t b = 0; b < s.structures.size(); ++b)
      for (int k = 0; k < d; ++k) {
        if (s.periodic[std::size_t(k)]) continue;
        double lo = 1e300, hi = -1e300;
        for (std::size_t i = structure_first[b]; i < structure_first[b + 1]; ++i) {
          lo = std::min(lo, x[i][k]);
          hi = std::max(hi, x[i][k]);
        }
        if (lo < domain.min[k] || hi > domain.max[k]) {
          std::ostringstream os;
          os << at_text(s.structures[b].where, "error") << "structure '" << s.structures[b].name
             << "' reaches outside 'domain' along " << "xyz"[k] << " (its particles span " << lo << " to " << hi
             << " m, the domain " << domain.min[k] << " to " << domain.max[k]
             << " m); the particles outside would be dropped at the start. Move it or widen the domain";
          throw std::invalid_argument(os.str());
        }
      }
  // 2. Structures inside each other, or inside a wall: an error when one of them moves (contacts
  //    and forces would start from an overlap), a warning when both are fixed.
  std::vector<PointHash> walls;  // each wall's particles, hashed once
  if (!s.structures.empty()) {
    walls.reserve(s.walls.size());
    for (std::size_t w = 0; w < s.walls.size(); ++w) walls.emplace_back(x, wall_first[w], wall_first[w + 1], dx, d);
  }
  for (std::size_t a = 0; a < s.structures.size(); ++a) {
    for (std::size_t b = 0; b < s.structures.size(); ++b) {
      if (a == b) continue;
      std::size_t inside = 0;
      for (std::size_t i = structure_first[a]; i < structure_first[a + 1]; ++i)
        if (carver.distance_to(b, x[i], dx) < -touch) ++inside;
      if (inside == 0 || (b < a && !moves(s.structures[a]) && !moves(s.structures[b]))) continue;
      const bool error = moves(s.structures[a]) || moves(s.structures[b]);
      std::ostringstream os;
      os << at_text(s.structures[a].where, error ? "error" : "warning") << "structure '" << s.structures[a].name
         << "' overlaps structure '" << s.structures[b].name << "' (line " << s.structures[b].where.line << "): "
         << inside << " of its particles lie more than dx/2 inside it";
      if (error) {
        os << "; a moving structure must start clear of the others";
        throw std::invalid_argument(os.str());
      }
      os << " (both fixed: the fluid sees their union, forces.csv reports each)";
      warnings.push_back(os.str());
    }
    for (std::size_t w = 0; w < s.walls.size(); ++w) {
      std::size_t inside = 0;
      for (std::size_t i = structure_first[a]; i < structure_first[a + 1]; ++i)
        if (walls[w].any_within(x[i], touch)) ++inside;
      if (inside == 0) continue;
      const bool error = moves(s.structures[a]);
      std::ostringstream os;
      os << at_text(s.structures[a].where, error ? "error" : "warning") << "structure '" << s.structures[a].name
         << "' overlaps " << wall_name(w) << ": " << inside << " of its particles lie within dx/2 of the wall's";
      if (error) {
        os << "; a moving structure must start clear of the walls";
        throw std::invalid_argument(os.str());
      }
      warnings.push_back(os.str());
    }
  }
  // 3. A wall drawn through fluid: wall and fluid particles in the same space.
  for (std::size_t f = 0; f < s.fluids.size(); ++f) {
    const PointHash fluid(x, block_first[f], block_first[f + 1], dx, d);
    for (std::size_t w = 0; w < s.walls.size(); ++w) {
      std::size_t hits = 0;
      for (std::size_t i = wall_first[w]; i < wall_first[w + 1]; ++i)
        if (fluid.any_within(x[i], touch)) ++hits;
      if (hits == 0) continue;
      std::ostringstream os;
      os << at_text(s.walls[w].where, "error") << wall_name(w) << " passes through the fluid of line "
         << s.fluids[f].where.line << ": " << hits
         << " of its particles lie within dx/2 of fluid particles. Keep fluid regions on one side of the wall "
            "(a fluid polygon can follow it)";
      throw std::invalid_argument(os.str());
    }
  }
  // 4. Fluid with nothing beneath it falls out of the scene: along gravity's axis (when it is not
  //    periodic), a fluid particle is held if some wall or structure particle lies below it within
  //    dx sideways. A warning, whole block or part: a falling jet, or particles meant to leave
  //    through the domain's faces, may be what the user wants.
  int down = -1;
  double gmax = 0;
  for (int k = 0; k < d; ++k)
    if (std::abs(s.gravity[std::size_t(k)]) > gmax) {
      gmax = std::abs(s.gravity[std::size_t(k)]);
      down = k;
    }
  if (down >= 0 && !s.periodic[std::size_t(down)]) {
    const double sign = s.gravity[std::size_t(down)] < 0 ? 1.0 : -1.0;  // height = sign * coordinate
    // The lowest solid height per column of side dx across gravity.
    std::unordered_map<long long, double> lowest;
    auto column = [&](const Point& p, long di, long dj) {
      long c[2] = {0, 0};
      int n = 0;
      for (int k = 0; k < d; ++k)
        if (k != down) {
          c[n] = long(std::floor(p[k] / dx)) + (n == 0 ? di : dj);
          ++n;
        }
      return (static_cast<long long>(c[1] & 0xffffffff) << 32) | static_cast<long long>(c[0] & 0xffffffff);
    };
    for (std::size_t i = block_first.back(); i < structure_first.back(); ++i) {
      const double hgt = sign * x[i][down];
      auto [it, fresh] = lowest.emplace(column(x[i], 0, 0), hgt);
      if (!fresh) it->second = std::min(it->second, hgt);
    }
    for (std::size_t f = 0; f < s.fluids.size(); ++f) {
      std::size_t unheld = 0;
      const std::size_t n = block_first[f + 1] - block_first[f];
      for (std::size_t i = block_first[f]; i < block_first[f + 1]; ++i) {
        const double hgt = sign * x[i][down];
        bool held = false;
        for (long di = -1; di <= 1 && !held; ++di)
          for (long dj = (d == 3 ? -1 : 0); dj <= (d == 3 ? 1 : 0) && !held; ++dj) {
            const auto it = lowest.find(column(x[i], di, dj));
            held = it != lowest.end() && it->second < hgt;
          }
        if (!held) ++unheld;
      }
      if (unheld == 0 || n == 0) continue;
      std::ostringstream os;
      const bool all = unheld == n;
      os << at_text(s.fluids[f].where, "warning") << "the fluid of this block has " << (all ? "nothing" : "in part nothing")
         << " beneath it: " << unheld << " of its " << n
         << " particles have no wall or structure below them along gravity, so they fall out of the scene";
      warnings.push_back(os.str());
    }
  }
  return warnings;
}

}  // namespace

int wall_layers(const Scene& scene, const WallSpec& wall) {
  if (wall.layers > 0) return wall.layers;
  // Enough layers to fill the kernel support 2h seen from the first fluid row.
  return std::max(1, int(std::ceil(2.0 * scene.smoothing_ratio - 1e-9)));
}

// "file:line:col: error: material 'name': " for messages about a material.
static std::string material_error(const MaterialSpec& m) {
  std::ostringstream os;
  os << m.where.file << ":" << m.where.line << ":" << m.where.column << ": error: material '" << m.name << "': ";
  return os.str();
}

// Whether a non-Newtonian material's laminar viscous terms are integrated implicitly: as the scene
// says, or (auto) where its largest viscosity mu_max (sph::Rheology::bound, a property of the
// material alone) would put the explicit viscous limit f h^2 rho0 / mu_max below the acoustic one
// CFL h / c0 at the lattice's h (docs/choices.md).
static bool implicit_viscosity(const Scene& scene, const MaterialSpec& ms, const sph::Rheology& r, double c0, double h) {
  const double bound = r.bound();
  switch (scene.numerics.viscous_integration) {
    case ViscousIntegration::implicit: return true;
    case ViscousIntegration::explicit_:
      if (!std::isfinite(bound))
        throw std::invalid_argument(material_error(ms) +
                                    "its viscosity has no upper bound (a power law without 'max_viscosity'), which "
                                    "explicit viscous integration needs; state 'max_viscosity' or use 'integration: implicit'");
      return false;
    case ViscousIntegration::automatic: break;
  }
  if (!std::isfinite(bound)) return true;
  const double viscous = scene.numerics.viscous_dt_factor * h * h * ms.density / bound;
  const double acoustic = scene.numerics.cfl * h / c0;
  return viscous < acoustic;
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
  p.shifting_coefficient = sph::Real(scene.numerics.shifting_coefficient);
  p.shifting_surface_threshold = sph::Real(scene.numerics.shifting_surface_threshold < 0
                                               ? scene.dimensions - 0.5
                                               : scene.numerics.shifting_surface_threshold);
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
    p.materials[m].rheology.consistency = sph::Real(ms.viscosity);
    const bool laminar = scene.numerics.viscosity == ViscosityKind::laminar;
    p.materials[m].central_stress = laminar && scene.numerics.viscous_stress == ViscousStress::central;
    // A Newtonian material is implicit only where the scene asks for every material implicit.
    p.materials[m].implicit_viscosity = laminar && ms.viscosity > 0 &&
                                        scene.numerics.viscous_integration == ViscousIntegration::implicit;
    p.implicit_viscosity = p.implicit_viscosity || p.materials[m].implicit_viscosity;
    if (ms.model != "newtonian") {
      sph::Rheology& r = p.materials[m].rheology;
      r.yield_stress = sph::Real(ms.yield_stress);
      r.consistency = sph::Real(ms.model == "bingham" ? ms.viscosity : ms.consistency);
      r.flow_index = sph::Real(ms.model == "bingham" ? 1.0 : ms.flow_index);
      r.regularisation = sph::Real(ms.papanastasiou_exponent);
      // The material as stated: Papanastasiou's exponent, and a cap only where the scene gives one.
      r.max_viscosity = sph::Real(ms.max_viscosity > 0 ? ms.max_viscosity : 0.0);
      if (r.flow_index < 1 && !(r.regularisation > 0) && !(r.max_viscosity > 0))
        throw std::invalid_argument(material_error(ms) +
                                    "a shear-thinning power law without a yield stress has no viscosity at rest; "
                                    "state 'max_viscosity' [Pa s]");
      const bool implicit = laminar && implicit_viscosity(scene, ms, r, c0, scene.smoothing_ratio * scene.particle_spacing);
      // The explicit viscous time-step limit sees the largest mu_eff possible; an implicit
      // material sets no viscous limit.
      const double bound = r.bound();
      p.materials[m].dynamic_viscosity = sph::Real(std::isfinite(bound) ? bound : double(r.consistency));
      p.materials[m].implicit_viscosity = implicit;
      p.implicit_viscosity = p.implicit_viscosity || implicit;
      p.materials[m].non_newtonian = true;
      p.rheology = true;
    }
    // The viscous stress (docs/choices.md): the full deviatoric stress lives in the implicit update;
    // `auto` gives it to the non-Newtonian materials (where mu varies by orders of magnitude across
    // a yield surface, div(mu grad v^T) is not small), unless the scene asks for explicit integration.
    const ViscousStress stress = scene.numerics.viscous_stress;
    const bool non_newtonian = ms.model != "newtonian";
    const bool explicit_asked = scene.numerics.viscous_integration == ViscousIntegration::explicit_;
    const bool full = laminar && ms.viscosity + ms.consistency + ms.yield_stress > 0 &&
                      (stress == ViscousStress::full ||
                       (stress == ViscousStress::automatic && non_newtonian && !explicit_asked));
    if (full && scene.numerics.viscous_integration == ViscousIntegration::explicit_)
      throw std::invalid_argument(material_error(ms) +
                                  "the full viscous stress ('stress: full') is integrated implicitly; use "
                                  "'integration: auto' or 'implicit', or 'stress: laplacian' with explicit integration");
    if (full) {
      p.materials[m].full_stress = true;
      p.materials[m].implicit_viscosity = true;
      p.implicit_viscosity = true;
      p.full_stress = true;
    }
  }
  if (!scene.transitions.empty()) {
    // The criterion reads every fluid particle's effective shear stress, and daughters have half
    // their mother's h: the rheology pass runs for Newtonian materials too, and every pass takes
    // the per-particle h from the start.
    p.rheology = true;
    p.uniform_h = false;
    p.splitting = true;
  }
  p.wall_material = 0;
  p.interface_correction = scene.numerics.interface_correction && p.material_count > 1;
  p.uniform_sound_speed = true;
  for (int m = 1; m < p.material_count; ++m)
    p.uniform_sound_speed = p.uniform_sound_speed && p.materials[m].sound_speed == p.materials[0].sound_speed;
  if (scene.domain) {
    for (int k = 0; k < scene.dimensions; ++k) {
      if (!scene.periodic[std::size_t(k)]) continue;
      p.periodic = true;
      p.period[k] = sph::Real(scene.domain->max[std::size_t(k)] - scene.domain->min[std::size_t(k)]);
      p.periodic_origin[k] = sph::Real(scene.domain->min[std::size_t(k)]);
      p.periodic_end[k] = sph::Real(scene.domain->max[std::size_t(k)]);
    }
  }
  for (int k = 0; k < 3; ++k) p.hydrostatic_gravity[k] = p.period[k] > 0 ? sph::Real(0) : p.gravity[k];
  p.boundary = scene.numerics.boundary == BoundaryKind::mdbc ? sph::Boundary::mdbc : sph::Boundary::dbc;
  // The full stress is built from renormalised gradients over 2h: walls at their own velocity put a
  // kink into the profile at the wall, the gradients average it away and the wall shear comes out
  // at about half (a yield-stress layer slid on DBC walls); by default its walls mirror the fluid.
  p.wall_no_slip = scene.numerics.no_slip.value_or(p.full_stress);
  // Wall function (docs/choices.md, "Wall friction"): y below a tenth of the spacing is held there.
  p.wall_function = scene.numerics.wall_function;
  p.wall_viscosity_normal = scene.numerics.viscosity == ViscosityKind::artificial &&
                            scene.numerics.artificial_wall_normal.value_or(scene.numerics.boundary == BoundaryKind::mdbc) &&
                            (!scene.walls.empty() || !scene.structures.empty());
  p.wall_roughness_length = sph::Real(scene.numerics.wall_roughness / 30.0);
  p.wall_function_min_distance = sph::Real(0.1 * scene.particle_spacing);
  if (p.wall_function && p.implicit_viscosity) {
    const auto& w = scene.numerics.wall_function_where;
    throw std::invalid_argument(w.file + ":" + std::to_string(w.line) + ":" + std::to_string(w.column) +
                                ": error: 'wall_function' does not combine with implicitly integrated viscosity "
                                "(a non-Newtonian material, or 'integration: implicit'), whose update holds the "
                                "wall's viscous terms; use 'integration: explicit' or leave 'wall_function' out");
  }
  p.wall_constraint = scene.numerics.impermeable && (!scene.walls.empty() || !scene.structures.empty());
  p.wall_constraint_band = sph::Real(0.5 * scene.particle_spacing);
  p.wall_constraint_reach = sph::Real(scene.particle_spacing);
  for (const auto& w : scene.walls) p.free_slip_walls = p.free_slip_walls || w.free_slip;
  p.body_count = int(scene.structures.size());
  for (const auto& probe : scene.probes) p.wall_loads = p.wall_loads || probe.type == ProbeSpec::Type::wall_load;
  p.zone_count = int(scene.open_boundaries.size());
  for (std::size_t k = 0; k < scene.open_boundaries.size(); ++k) {
    const auto& ob = scene.open_boundaries[k];
    sph::BufferZone& z = p.zones[k];
    const int a = ob.velocity.axis;
    z.type = ob.inlet ? sph::ZoneType::inlet : sph::ZoneType::outlet;
    z.profile = ob.velocity.parabolic ? sph::Profile::parabolic : sph::Profile::uniform;
    z.axis = a;
    z.sign = sph::Real(ob.velocity.sign);
    // The face towards the fluid: downstream for an inlet, upstream for an outlet.
    const bool downstream_is_max = ob.velocity.sign > 0;
    z.plane = sph::Real(ob.inlet == downstream_is_max ? ob.box.max[a] : ob.box.min[a]);
    z.thickness = sph::Real(ob.box.max[a] - ob.box.min[a]);
    z.velocity = sph::Real(ob.velocity.mean);
    for (int k2 = 0; k2 < 3; ++k2) {
      z.lo[k2] = sph::Real(ob.box.min[k2]);
      z.hi[k2] = sph::Real(ob.box.max[k2]);
    }
    z.material = std::uint8_t(std::max(0, material_index(scene, ob.material)));
  }
  return p;
}

bool has_free_structures(const Scene& scene) {
  for (const auto& st : scene.structures)
    if (st.motion == StructureSpec::Motion::free || st.motion == StructureSpec::Motion::bullet) return true;
  return false;
}

bool has_bullet_structures(const Scene& scene) {
  for (const auto& st : scene.structures)
    if (st.motion == StructureSpec::Motion::bullet) return true;
  return false;
}

// The Bullet world of the scene's bullet structures (fsi/bullet_world.hpp), with the mass properties
// the run uses; their meshes are read again here (the sampling's copy is gone).
static std::unique_ptr<BulletWorld> bullet_world(const Scene& scene, const std::vector<FreeBodySummary>& free_bodies,
                                                 const SurfaceLayers& surface) {
  std::vector<std::optional<MassProperties>> mass(scene.structures.size());
  for (const auto& fb : free_bodies) mass[fb.structure] = fb.mass_properties;
  std::vector<geometry::TriangleMesh> meshes(scene.structures.size());
  for (std::size_t k = 0; k < scene.structures.size(); ++k) {
    const StructureSpec& st = scene.structures[k];
    if (st.motion == StructureSpec::Motion::bullet && st.shape == StructureSpec::Shape::mesh)
      meshes[k] = geometry::load_mesh(st.resolved_file);
  }
  return make_bullet_world(scene, mass, meshes, surface);
}

MassProperties structure_mass_properties(const Scene& scene, const StructureSpec& st) {
  return mass_properties_of(scene, st, nullptr);
}

Simulation::Simulation(Scene scene, const RunOptions& options) : scene_(std::move(scene)) {
  params_ = physics_params(scene_);
  const bool free_bodies = has_free_structures(scene_);
  const bool prescribed = has_prescribed_structures(scene_);
  ids_ = sph::register_fields(store_, params_, !scene_.structures.empty(), free_bodies || prescribed);
  build_particles();

  std::unique_ptr<sph::Backend> backend;
  if (options.backend == "cpu") {
    backend = sph::make_cpu_backend(options.threads);
  } else if (options.backend == "cuda") {
    backend = sph::make_cuda_backend();
  } else if (options.backend == "device-omp") {
    backend = sph::make_omp_device_backend(options.threads);
  } else if (options.backend == "auto") {
    std::string why;
    backend = sph::cuda_device_count(&why) > 0 ? sph::make_cuda_backend() : sph::make_cpu_backend(options.threads);
    // A backend without splitting, implicit viscosity or moving bodies hands the scene to the CPU.
    // Moving bodies on CUDA passed CudaBodies.* (tests/unit/test_cuda_bodies.cpp) on an H200 on
    // 2026-12-04 (docs/performance.md, "GPU"), so 'auto' runs them there.
    if (!scene_.transitions.empty() && !backend->supports_splitting()) backend = sph::make_cpu_backend(options.threads);
    // The implicit viscous solve runs on the device backend since 2026-12-05, checked there only
    // through its device-omp build (BackendParity.PipelineImpact*): until it has run on a GPU,
    // 'auto' keeps such scenes (the default scene among them) on the CPU; --backend cuda runs them.
    if (params_.implicit_viscosity && (!backend->supports_implicit_viscosity() || backend->name() == "cuda"))
      backend = sph::make_cpu_backend(options.threads);
    if ((free_bodies || prescribed) && !backend->supports_moving_bodies())
      backend = sph::make_cpu_backend(options.threads);
  } else {
    throw std::invalid_argument("unknown backend '" + options.backend + "' (expected auto, cpu, cuda or device-omp)");
  }
  if (!scene_.transitions.empty() && !backend->supports_splitting())
    throw std::invalid_argument("the scene has transitions (particle splitting), which the " + backend->name() +
                                " backend does not run yet; use --backend cpu (or auto)");
  if (params_.implicit_viscosity && !backend->supports_implicit_viscosity())
    throw std::invalid_argument("the scene integrates a material's viscosity implicitly, which the " + backend->name() +
                                " backend does not run yet; use --backend cpu (or auto), or 'integration: explicit' "
                                "with a stated 'max_viscosity'");
  if (free_bodies && !backend->supports_moving_bodies())
    throw std::invalid_argument("the scene has free structures (motion: free or bullet), which the " + backend->name() +
                                " backend does not run yet; use --backend cpu (or auto)");
  if (prescribed && !backend->supports_moving_bodies())
    throw std::invalid_argument("the scene has prescribed structures (motion: prescribed), which the " +
                                backend->name() + " backend does not run yet; use --backend cpu (or auto)");
  backend_name_ = backend->name();
  threads_ = backend->threads();
  sph::TimeStepParams tp;
  tp.cfl = scene_.numerics.cfl;
  tp.viscous_factor = scene_.numerics.viscous_dt_factor;
  tp.min_time_step = scene_.numerics.min_time_step;
  tp.density_ratio_limit = scene_.numerics.density_ratio_limit;
  solver_ = std::make_unique<sph::Solver>(store_, ids_, params_, summary_.domain, tp, std::move(backend));
  if (!scene_.transitions.empty()) solver_->set_splitting(split_params(scene_), scene_.capacity.error_when_full);
  if (free_bodies) {
    std::vector<std::optional<RigidBody>> rigid(scene_.structures.size());
    for (const auto& fb : summary_.free_bodies) {
      const StructureSpec& st = scene_.structures[fb.structure];
      DofMask mask;
      for (std::size_t a = 0; a < 3; ++a) {
        mask.translation[a] = !st.lock_translation[a];
        mask.rotation[a] = !st.lock_rotation[a];
      }
      if (st.motion == StructureSpec::Motion::free) add_hinge_locks(scene_, fb.structure, mask);
      try {
        rigid[fb.structure].emplace(fb.mass_properties, mask);
      } catch (const std::exception& e) {
        std::ostringstream os;
        os << st.where.file << ":" << st.where.line << ":" << st.where.column << ": error: structure '" << st.name
           << "': " << e.what();
        throw std::invalid_argument(os.str());
      }
    }
    const Eigen::Vector3d g(scene_.gravity[0], scene_.gravity[1], scene_.dimensions == 3 ? scene_.gravity[2] : 0.0);
    // Constraints and contacts (scene_interactions.hpp), from the bodies at t = 0.
    std::vector<BodyConstraint> constraints = body_constraints(scene_, rigid);
    std::unique_ptr<BodyContacts> contacts = body_contacts(scene_, surface_layers_, rigid);
    bodies_ = std::make_unique<BodyCoupling>(std::move(rigid), g);
    bodies_->set_fast_forces(std::move(constraints), std::move(contacts));
    if (has_bullet_structures(scene_)) bodies_->set_bullet(bullet_world(scene_, summary_.free_bodies, surface_layers_));
    solver_->set_coupling(bodies_.get());
    // The particles were written at their sampled positions; the placement rounds x_c + R r0 once,
    // as every later step does, so the first step starts from the same kind of positions.
    bodies_->place(solver_->backend(), true);
  }
  if (prescribed) {
    const sph::Solver* solver = solver_.get();
    prescribed_ = make_prescribed_coupling(scene_, store_, ids_, summary_.domain, [solver] { return solver->time(); });
    if (bodies_) {
      chain_ = std::make_unique<CouplingChain>();
      chain_->add(bodies_.get());
      chain_->add(prescribed_.get());
      solver_->set_coupling(chain_.get());
      // The prescribed structures are contact obstacles of the moving bodies, along their paths.
      const PrescribedCoupling* paths = prescribed_.get();
      bodies_->set_obstacle_motion(
          [paths](std::size_t k, double t) {
            const BodyKinematics b = paths->kinematics(k, t);
            ObstacleMotion m;
            m.reference = Eigen::Vector3d(b.position[0], b.position[1], b.position[2]);
            m.rotation = Eigen::Quaterniond(b.orientation[0], b.orientation[1], b.orientation[2], b.orientation[3])
                             .toRotationMatrix();
            m.velocity = Eigen::Vector3d(b.velocity[0], b.velocity[1], b.velocity[2]);
            m.angular_velocity = Eigen::Vector3d(b.angular_velocity[0], b.angular_velocity[1], b.angular_velocity[2]);
            return m;
          },
          [solver] { return solver->time(); });
    } else {
      solver_->set_coupling(prescribed_.get());
    }
    // Rounded once from x_ref + d(0) + R(0) r0, as every later placement.
    prescribed_->place_at(solver_->backend(), 0.0);
  }
}

sph::SplitParams split_params(const Scene& scene) {
  sph::SplitParams sp;
  if (int(scene.transitions.size()) > sph::kMaxSplitRules)
    throw std::invalid_argument("at most " + std::to_string(sph::kMaxSplitRules) + " transitions are supported");
  const double h0 = scene.smoothing_ratio * scene.particle_spacing;
  const auto index = [&](const std::string& name) {
    const int m = material_index(scene, name);
    if (m < 0) throw std::invalid_argument("transition names an unknown material '" + name + "'");
    return std::uint8_t(m);
  };
  sp.relax_iterations = scene.numerics.split_relaxation;
  for (const auto& t : scene.transitions) {
    sph::SplitRule& r = sp.rules[sp.rule_count++];
    r.from = index(t.from);
    r.to = index(t.to);
    r.threshold = sph::Real(t.shear_stress_threshold);
    r.interface_only = t.interface_only;
    // A particle of level L (h = h0 / 2^L) may split while L < levels: h > h0 / 2^levels, with
    // the bound halfway between the last level allowed and the first refused.
    r.min_smoothing_length = sph::Real(1.5 * h0 / std::pow(2.0, t.levels));
  }
  return sp;
}

std::size_t particle_capacity(const Scene& scene, std::size_t initial) {
  if (scene.transitions.empty()) return initial;
  if (scene.capacity.max_particles > 0) {
    // Fewer than the start holds would refuse every split (it was once raised silently).
    if (scene.capacity.max_particles < initial) {
      std::ostringstream os;
      os << at_text(scene.capacity.where, "error") << "capacity: max_particles = "
         << scene.capacity.max_particles << " is below the " << initial
         << " particles the scene starts with (fluid, walls and structures), so no particle could ever split; "
            "give at least " << initial << " plus room for the daughters, or 'factor' (e.g. 2) instead";
      throw std::invalid_argument(os.str());
    }
    return scene.capacity.max_particles;
  }
  return std::size_t(std::ceil(scene.capacity.factor * double(initial)));
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
    geometry::Point ghost{0, 0, 0};  // mDBC ghost offset (boundary particles)
    std::uint8_t body = sph::kNoBody;
    double volume = 0;               // particle volume [m^d]
    Point velocity{0, 0, 0};
    std::uint8_t zone = sph::kNoZone;
    bool free_slip = false;          // a particle of a free-slip wall
    Point offset{0, 0, 0};           // moving structures: position relative to the centre of mass
  };
  std::vector<Item> items;
  summary_.particles_per_material.assign(s.materials.size(), 0);

  auto material_of = [&](const std::string& name, const SourceLocation& where) {
    if (const int m = material_index(s, name); m >= 0) return std::uint8_t(m);
    std::ostringstream os;
    os << where.file << ":" << where.line << ":" << where.column << ": error: unknown material '" << name << "'";
    throw std::invalid_argument(os.str());
  };

  double global_top = -std::numeric_limits<double>::infinity();
  for (const auto& f : s.fluids) global_top = std::max(global_top, box_heights(s, f.box).top);

  // Structures are sampled first: fluid lattice points inside them are left out.
  std::vector<geometry::SampledBody> bodies;
  std::vector<geometry::Solid> solids;
  for (const auto& st : s.structures) {
    const int layers = st.layers > 0 ? st.layers : std::max(1, int(std::ceil(2.0 * s.smoothing_ratio - 1e-9)));
    try {
      // A mesh file is read once, for the particles and the solid.
      geometry::TriangleMesh mesh;
      if (st.shape == StructureSpec::Shape::mesh) mesh = geometry::load_mesh(st.resolved_file);
      const geometry::TriangleMesh* m = st.shape == StructureSpec::Shape::mesh ? &mesh : nullptr;
      bodies.push_back(sample_structure(st, dx, d, layers, m));
      solids.push_back(structure_solid(st, d, m));
      if (st.motion == StructureSpec::Motion::free || st.motion == StructureSpec::Motion::bullet)
        summary_.free_bodies.push_back({bodies.size() - 1, st.name, mass_properties_of(s, st, m)});
    } catch (const std::exception& e) {
      std::ostringstream os;
      os << st.where.file << ":" << st.where.line << ":" << st.where.column << ": error: structure '" << st.name
         << "': " << e.what();
      throw std::invalid_argument(os.str());
    }
    if (bodies.back().points.empty()) {
      std::ostringstream os;
      os << st.where.file << ":" << st.where.line << ":" << st.where.column << ": error: structure '" << st.name
         << "' is smaller than the particle spacing " << dx << " m and yields no particles";
      throw std::invalid_argument(os.str());
    }
    // The body's volume: a mesh reports the whole solid's; a primitive the sampled layers', so it
    // is sampled once more, filled.
    double volume = bodies.back().volume;
    if (st.shape != StructureSpec::Shape::mesh) volume = sample_structure(st, dx, d, 0).volume;
    summary_.structures.push_back({st.name, bodies.back().points.size(), bodies.back().surface_area, volume});
    // The surface layer, for DEM contacts (scene_interactions.hpp).
    surface_layers_.emplace_back();
    for (std::size_t i = 0; i < bodies.back().points.size(); ++i)
      if (bodies.back().layer[i] == 0) {
        const auto& p = bodies.back().points[i];
        surface_layers_.back().emplace_back(p[0], p[1], d == 3 ? p[2] : 0.0);
      }
  }
  const StructureCarver carver(std::move(solids), dx);

  // Fluid blocks of several densities (layers) start from the weight of all fluid above each
  // particle; a single density keeps the depth below its block's top (same values, same bits).
  std::vector<std::uint8_t> block_material;
  for (const auto& f : s.fluids) block_material.push_back(material_of(f.material, f.where));
  bool layered = false;
  for (std::uint8_t bm : block_material)
    layered = layered || params_.materials[bm].eos.rest_density != params_.materials[block_material[0]].eos.rest_density;
  // Walls under layers: the column above the nearest point of the fluid blocks' footprint.
  Box footprint{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const auto& f : s.fluids)
    for (int k = 0; k < 3; ++k) {
      footprint.min[k] = std::min(footprint.min[k], f.box.min[k]);
      footprint.max[k] = std::max(footprint.max[k], f.box.max[k]);
    }
  auto layered_density = [&](const sph::TaitEos& eos, const Vec3d& x, bool clamp_to_footprint) {
    Vec3d xc = x;
    if (clamp_to_footprint) {
      const Vec3d gv = hydrostatic_gravity(s);
      for (int k = 0; k < d; ++k)
        if (gv[k] == 0) xc[k] = std::clamp(x[k], footprint.min[k], footprint.max[k]);
    }
    return eos.density_at_gauge(layered_pressure(s, params_, xc, block_material));
  };

  // The cells the box walls fill, as built (geometry::lattice_box: whole cells from the min corner,
  // up to dx/2 off the stated box). A fluid lattice point whose cell lies mostly in them (its centre
  // less than dx/4 inside a closed face of a tank, or within dx/4 of an obstacle's cells) is left
  // out: a block stated up to a wall that the lattice ends short of would otherwise sit in the
  // wall's layers (issue #27 item 8).
  std::vector<geometry::Aabb> wall_cells;  // per wall: container inner box or solid box, as built
  for (const auto& w : s.walls) wall_cells.push_back(geometry::lattice_box(to_aabb(w.box), dx, d));
  auto in_wall_cells = [&](const Point& x) {
    const double q = 0.25 * dx;
    for (std::size_t w = 0; w < s.walls.size(); ++w) {
      const WallSpec& wall = s.walls[w];
      const geometry::Aabb& c = wall_cells[w];
      if (wall.kind == WallSpec::Kind::solid_box) {
        bool inside = true;
        for (int k = 0; k < d; ++k) inside = inside && x[k] > c.min[k] - q && x[k] < c.max[k] + q;
        if (inside) return true;
      } else if (wall.kind == WallSpec::Kind::container) {
        bool near = true;  // within the tank's cells grown by half a cell
        for (int k = 0; k < d; ++k) near = near && x[k] >= c.min[k] - 0.5 * dx && x[k] <= c.max[k] + 0.5 * dx;
        if (!near) continue;
        for (int k = 0; k < d; ++k)
          if ((!wall.open[2 * k] && x[k] - c.min[k] < q) || (!wall.open[2 * k + 1] && c.max[k] - x[k] < q)) return true;
      }
    }
    return false;
  };

  std::vector<std::pair<SourceLocation, std::size_t>> wall_drops;  // per block with points left out
  std::vector<std::size_t> block_first;  // items of fluid block b: [block_first[b], block_first[b + 1])
  for (const auto& f : s.fluids) {
    block_first.push_back(items.size());
    std::size_t left_in_walls = 0;
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
    const std::size_t first = items.size();
    std::vector<Point> carved;
    const int this_block = int(&f - s.fluids.data());
    // A polygon takes the points of the lattice anchored at the origin that fall inside it, so
    // that polygons next to each other (a slide in the water around it) share one lattice. In 3D
    // that is the lattice of its x-z plane, repeated across y as a box with the span's extent
    // would be (geometry::extrude_across_y), so it meets tank walls and boxes on the same y rows.
    const int v = section_axis(d);
    std::vector<Point> lattice;
    geometry::Aabb block_cells = to_aabb(f.box);  // the box whose whole cells the block's lattice fills
    if (f.polygon.empty()) {
      // A box inside a tank takes the tank's lattice (whole cells from the tank's min corner),
      // clipped to the tank's cells at its closed faces: its particles then stand exactly dx from
      // the wall particles, also where the lattice ends the tank up to dx/2 short of the stated box
      // (a block stated up to x = 3.22 in a tank built to 3.21 once reached into the wall's
      // layers; issue #27 item 8). Each face moves by at most dx/2; `turbid check` lists both.
      for (std::size_t w = 0; w < s.walls.size(); ++w) {
        if (s.walls[w].kind != WallSpec::Kind::container) continue;
        const geometry::Aabb& c = wall_cells[w];
        bool centred = true;
        for (int k = 0; k < d; ++k) {
          const double mid = 0.5 * (f.box.min[k] + f.box.max[k]);
          centred = centred && mid > c.min[k] && mid < c.max[k];
        }
        if (!centred) continue;
        for (int k = 0; k < d; ++k) {
          const double a = c.min[k];
          long i0 = std::lround((f.box.min[k] - a) / dx), i1 = std::lround((f.box.max[k] - a) / dx);
          const long n = std::lround((c.max[k] - a) / dx);
          if (!s.walls[w].open[2 * k]) i0 = std::max(i0, 0L);
          if (!s.walls[w].open[2 * k + 1]) i1 = std::min(i1, n);
          if (i1 <= i0) i1 = i0 + 1;  // at least one cell, as fill_box
          block_cells.min[k] = a + double(i0) * dx;
          block_cells.max[k] = a + double(i1) * dx;
        }
        break;
      }
      lattice = geometry::fill_box(block_cells, dx, d);
    } else {
      // (i + 1/2) dx, computed from the integer indices so that a box anchored at the origin
      // produces the very same coordinates.
      const long i0 = long(std::floor(f.box.min[0] / dx + 1e-9)), i1 = long(std::ceil(f.box.max[0] / dx - 1e-9));
      const long j0 = long(std::floor(f.box.min[v] / dx + 1e-9)), j1 = long(std::ceil(f.box.max[v] / dx - 1e-9));
      for (long j = j0; j < j1; ++j)
        for (long i = i0; i < i1; ++i) lattice.push_back({(double(i) + 0.5) * dx, (double(j) + 0.5) * dx, 0.0});
      if (d == 3) lattice = geometry::extrude_across_y(lattice, f.span[0], f.span[1], dx);
    }
    for (const auto& x : lattice) {
      // Outside its polygon, or an earlier block's point. (A box's own lattice is not tested
      // against its own box: its last row may lie an ulp beyond max.)
      if ((!f.polygon.empty() && !inside_polygon(f.polygon, x[0], x[v])) ||
          block_of(s, x, std::size_t(this_block)) >= 0)
        continue;
      if (carver.blocks(x)) {
        ++summary_.fluid_removed_by_structures;
        carved.push_back(x);
        continue;
      }
      if (in_wall_cells(x)) {
        ++left_in_walls;
        continue;
      }
      const double depth = std::max(0.0, top - height_of(s, x));
      const double rho = layered ? layered_density(eos, x, false) : eos.hydrostatic_density(g, depth);
      items.push_back({x, rho, m, sph::Kind::fluid, {0, 0, 0}, sph::kNoBody, cell_volume,
                       profile_velocity(f.initial_velocity, f.box, x, d)});
      ++summary_.particles_per_material[m];
    }
    // The fluid's share of the carved cells goes to the nearest kept particles (see below).
    if (!carved.empty()) {
      std::vector<double*> volumes;
      for (std::size_t i = first; i < items.size(); ++i) volumes.push_back(&items[i].volume);
      std::vector<Point> kept;
      for (std::size_t i = first; i < items.size(); ++i) kept.push_back(items[i].x);
      std::vector<Point> moments(kept.size(), Point{0, 0, 0});
      summary_.fluid_volume_restored +=
          restore_carved_volume(carver, block_cells, dx, d, carved, kept, volumes, moments);
      // A particle that took over part of the gap moves to the centroid of all it stands for, and
      // starts at the hydrostatic density there.
      for (std::size_t q = 0; q < kept.size(); ++q) {
        Item& it = items[first + q];
        if (it.volume <= cell_volume) continue;
        for (int k = 0; k < d; ++k) it.x[k] = (kept[q][k] * cell_volume + moments[q][k]) / it.volume;
        it.density = layered ? layered_density(eos, it.x, false)
                             : eos.hydrostatic_density(g, std::max(0.0, top - height_of(s, it.x)));
      }
    }
    if (left_in_walls > 0) wall_drops.push_back({f.where, left_in_walls});
  }
  summary_.fluid_particles = items.size();
  block_first.push_back(items.size());
  for (std::size_t b = 0; b < s.fluids.size(); ++b) {
    const FluidBlock& f = s.fluids[b];
    WorldSummary::Extent e;
    e.what = "fluid block";
    e.where = f.where;
    e.stated = f.box;
    if (f.polygon.empty()) {
      e.stated_volume = 1;
      for (int k = 0; k < d; ++k) e.stated_volume *= f.box.max[k] - f.box.min[k];
    } else {
      double area = 0;  // shoelace, in the section plane
      for (std::size_t i = 0; i < f.polygon.size(); ++i) {
        const auto& a = f.polygon[i];
        const auto& c = f.polygon[(i + 1) % f.polygon.size()];
        area += a[0] * c[1] - c[0] * a[1];
      }
      e.stated_volume = 0.5 * std::abs(area) * (d == 3 ? f.span[1] - f.span[0] : 1.0);
    }
    e.built = {{1e300, 1e300, 0}, {-1e300, -1e300, 0}};
    if (d == 3) e.built.min[2] = 1e300, e.built.max[2] = -1e300;
    for (std::size_t i = block_first[b]; i < block_first[b + 1]; ++i) {
      e.built_volume += items[i].volume;
      for (int k = 0; k < d; ++k) {
        e.built.min[k] = std::min(e.built.min[k], items[i].x[k] - 0.5 * dx);
        e.built.max[k] = std::max(e.built.max[k], items[i].x[k] + 0.5 * dx);
      }
    }
    summary_.extents.push_back(e);
  }
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    const WallSpec& wall = s.walls[w];
    if (wall.kind == WallSpec::Kind::polyline) continue;
    WorldSummary::Extent e;
    e.what = wall.kind == WallSpec::Kind::container ? "container" : "solid box";
    e.where = wall.where;
    e.stated = wall.box;
    e.built = {wall_cells[w].min, wall_cells[w].max};
    e.stated_volume = e.built_volume = 1;
    for (int k = 0; k < d; ++k) {
      e.stated_volume *= wall.box.max[k] - wall.box.min[k];
      e.built_volume *= e.built.max[k] - e.built.min[k];
    }
    summary_.extents.push_back(e);
  }

  const auto& wall_eos = params_.materials[params_.wall_material].eos;
  // The faces of a solid box that rest on a container's inner face (a box on its tank's floor).
  auto hidden_faces = [&](const geometry::Aabb& b) {
    std::array<bool, 6> hidden{};
    for (std::size_t w = 0; w < s.walls.size(); ++w) {
      if (s.walls[w].kind != WallSpec::Kind::container) continue;
      const geometry::Aabb& c = wall_cells[w];
      for (int k = 0; k < d; ++k) {
        if (std::abs(b.min[k] - c.min[k]) < 0.5 * dx) hidden[std::size_t(2 * k)] = true;
        if (std::abs(b.max[k] - c.max[k]) < 0.5 * dx) hidden[std::size_t(2 * k + 1)] = true;
      }
    }
    return hidden;
  };
  std::vector<std::size_t> wall_first;  // items of wall w: [wall_first[w], wall_first[w + 1])
  for (const auto& w : s.walls) {
    wall_first.push_back(items.size());
    const int layers = wall_layers(s, w);
    std::vector<geometry::Point> pts;
    switch (w.kind) {
      case WallSpec::Kind::container: pts = geometry::container_walls(to_aabb(w.box), dx, d, layers, w.open); break;
      case WallSpec::Kind::solid_box: pts = geometry::box_shell(to_aabb(w.box), dx, d, w.layers); break;
      case WallSpec::Kind::polyline:
        pts = geometry::polyline_walls(w.points, w.closed, dx, layers, w.side);
        // 3D: the section's layers repeated on the y rows of a tank with the same y extent.
        if (d == 3) pts = geometry::extrude_across_y(pts, w.span[0], w.span[1], dx);
        break;
    }
    for (const auto& x : pts) {
      // Walls start at the hydrostatic density of the water above them, so the first steps carry
      // no pressure jump between fluid and wall.
      const double depth = std::isfinite(global_top) ? std::max(0.0, global_top - height_of(s, x)) : 0.0;
      Point ghost{0, 0, 0};
      // The surface is the box as built (whole cells from its min corner, where the particles
      // stand dx/2 behind it), not as stated: a solid box stated 0.161 m long at dx = 0.03 is built
      // 0.15 m long, and its stated face once put the ghost nodes 0.011 m too far out.
      const geometry::Aabb& built = wall_cells[std::size_t(&w - s.walls.data())];
      switch (w.kind) {
        case WallSpec::Kind::container: ghost = ghost_container({built.min, built.max}, x, d); break;
        case WallSpec::Kind::solid_box: ghost = ghost_solid_box({built.min, built.max}, x, d, hidden_faces(built)); break;
        case WallSpec::Kind::polyline: ghost = ghost_polyline(w, x, d); break;
      }
      const double rho = layered ? layered_density(wall_eos, x, true) : wall_eos.hydrostatic_density(g, depth);
      items.push_back({x, rho, 0, sph::Kind::wall, ghost, sph::kNoBody, cell_volume, {0, 0, 0}, sph::kNoZone, w.free_slip});
    }
  }
  wall_first.push_back(items.size());
  summary_.wall_particles = items.size() - summary_.fluid_particles;
  std::vector<std::size_t> structure_first;  // items of structure b: [structure_first[b], structure_first[b + 1])
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    structure_first.push_back(items.size());
    const auto& body = bodies[b];
    Point centre{0, 0, 0};
    for (const auto& fb : summary_.free_bodies)
      if (fb.structure == b)
        for (int k = 0; k < 3; ++k) centre[std::size_t(k)] = fb.mass_properties.centre_of_mass[k];
    // A prescribed structure moves and turns about its reference point.
    if (s.structures[b].motion == StructureSpec::Motion::prescribed) centre = s.structures[b].reference_point;
    for (std::size_t i = 0; i < body.points.size(); ++i) {
      const Point& x = body.points[i];
      const double depth = std::isfinite(global_top) ? std::max(0.0, global_top - height_of(s, x)) : 0.0;
      const Point ghost{2 * body.depth[i] * body.normals[i][0], 2 * body.depth[i] * body.normals[i][1],
                        d == 3 ? 2 * body.depth[i] * body.normals[i][2] : 0.0};
      items.push_back({x, wall_eos.hydrostatic_density(g, depth), 0, sph::Kind::structure, ghost, std::uint8_t(b),
                       body.volumes[i]});
      for (std::size_t k = 0; k < 3; ++k) items.back().offset[k] = x[k] - centre[k];
    }
  }
  structure_first.push_back(items.size());
  summary_.structure_particles = items.size() - summary_.fluid_particles - summary_.wall_particles;
  const double support = 2.0 * double(params_.smoothing_length);
  for (std::size_t k = 0; k < s.open_boundaries.size(); ++k) {
    const auto& ob = s.open_boundaries[k];
    const sph::BufferZone& z = params_.zones[k];
    if (double(z.thickness) < support * (1 - 1e-9)) {
      std::ostringstream os;
      os << ob.where.file << ":" << ob.where.line << ":" << ob.where.column << ": error: open boundary '" << ob.name
         << "' is " << z.thickness << " m thick along the flow, less than the kernel support 2h = " << support
         << " m at this spacing";
      throw std::invalid_argument(os.str());
    }
    const auto& eos = params_.materials[z.material].eos;
    for (const auto& x : geometry::fill_box(to_aabb(ob.box), dx, d)) {
      const double depth = std::isfinite(global_top) ? std::max(0.0, global_top - height_of(s, x)) : 0.0;
      Point v{0, 0, 0};
      if (ob.inlet && d == 2) {
        const auto u = sph::zone_velocity<2>(z, sph::Vec<2>{{sph::Real(x[0]), sph::Real(x[1])}});
        v = {double(u[0]), double(u[1]), 0.0};
      } else if (ob.inlet) {
        const auto u = sph::zone_velocity<3>(z, sph::Vec<3>{{sph::Real(x[0]), sph::Real(x[1]), sph::Real(x[2])}});
        v = {double(u[0]), double(u[1]), double(u[2])};
      }
      items.push_back({x, eos.hydrostatic_density(g, depth), z.material, sph::Kind::buffer, {0, 0, 0}, sph::kNoBody,
                       cell_volume, v, std::uint8_t(k)});
    }
  }
  summary_.buffer_particles =
      items.size() - summary_.fluid_particles - summary_.wall_particles - summary_.structure_particles;
  if (summary_.fluid_particles == 0) throw std::invalid_argument("the scene has no fluid particles");

  // Domain: as given, or the particles' bounding box grown by 10% per side.
  if (s.domain) {
    for (int k = 0; k < 3; ++k) {
      summary_.domain.min[k] = s.domain->min[k];
      summary_.domain.max[k] = s.domain->max[k];
      summary_.domain.periodic[k] = s.periodic[std::size_t(k)];
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

  {
    std::vector<Point> xs(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) xs[i] = items[i].x;
    summary_.warnings = check_layout(s, summary_.domain, xs, block_first, wall_first, structure_first, carver);
    for (const auto& [where, n] : wall_drops) {
      summary_.fluid_removed_by_walls += n;
      std::ostringstream os;
      os << at_text(where, "warning") << n
         << " lattice points of this fluid block lie in the cells of a wall as built (walls are whole cells from "
            "their min corner, up to dx/2 off the stated box) and are left out; state the block up to the wall's "
            "built extent (turbid check lists it) to silence this";
      summary_.warnings.push_back(os.str());
    }
  }

  store_.reserve(particle_capacity(s, items.size()));
  store_.resize(items.size());
  auto* x = static_cast<sph::Real*>(store_.raw(ids_.position));
  auto* rho = store_.data<sph::Real>(ids_.density);
  auto* mass = store_.data<sph::Real>(ids_.mass);
  auto* h = store_.data<sph::Real>(ids_.smoothing_length);
  auto* mat = store_.data<std::uint8_t>(ids_.material);
  auto* kind = store_.data<std::uint8_t>(ids_.kind);
  auto* id = store_.data<std::uint32_t>(ids_.id);
  auto* ghost = ids_.boundary_normal >= 0 ? static_cast<sph::Real*>(store_.raw(ids_.boundary_normal)) : nullptr;
  auto* body = ids_.body >= 0 ? store_.data<std::uint8_t>(ids_.body) : nullptr;
  auto* zone = ids_.zone >= 0 ? store_.data<std::uint8_t>(ids_.zone) : nullptr;
  auto* slip = ids_.free_slip >= 0 ? store_.data<std::uint8_t>(ids_.free_slip) : nullptr;
  auto* vel = static_cast<sph::Real*>(store_.raw(ids_.velocity));
  auto* offset = ids_.body_offset >= 0 ? static_cast<sph::Real*>(store_.raw(ids_.body_offset)) : nullptr;
  auto* normal0 = ids_.body_normal >= 0 ? static_cast<sph::Real*>(store_.raw(ids_.body_normal)) : nullptr;
  for (std::size_t i = 0; i < items.size(); ++i) {
    // The body frame is the world's axes at t = 0 (rigid_body.hpp): r0 = p0 - x0, n0 = n.
    if (offset)
      for (int k = 0; k < d; ++k) offset[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].offset[k]);
    if (normal0)
      for (int k = 0; k < d; ++k) normal0[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].ghost[k]);
    for (int k = 0; k < d; ++k) x[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].x[k]);
    if (ghost)
      for (int k = 0; k < d; ++k) ghost[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].ghost[k]);
    if (body) body[i] = items[i].body;
    if (zone) zone[i] = items[i].zone;
    if (slip) slip[i] = items[i].free_slip ? 1 : 0;
    for (int k = 0; k < d; ++k) vel[i * std::size_t(d) + std::size_t(k)] = sph::Real(items[i].velocity[k]);
    rho[i] = sph::Real(items[i].density);
    mass[i] = sph::Real(items[i].density * items[i].volume);  // V = m / rho: dx^d on the lattice
    h[i] = params_.smoothing_length;
    mat[i] = items[i].material;
    kind[i] = std::uint8_t(items[i].kind);
    id[i] = std::uint32_t(i);
  }
  // Walls and structures follow the fluid in `items` (fluid, walls, structures, buffers).
  boundary_first_id_ = std::uint32_t(summary_.fluid_particles);
  boundary_ghost0_.clear();
  for (std::size_t i = boundary_first_id_; i < items.size(); ++i) {
    if (items[i].kind != sph::Kind::wall && items[i].kind != sph::Kind::structure) break;
    boundary_ghost0_.push_back({float(items[i].ghost[0]), float(items[i].ghost[1]), float(items[i].ghost[2])});
  }
  summary_.smoothing_length = params_.smoothing_length;
  for (int m = 0; m < params_.material_count; ++m) summary_.sound_speed.push_back(params_.materials[m].sound_speed);
  summary_.cpu_memory = sph::cpu_memory_per_particle(store_, params_, scene_.particle_spacing, !scene_.transitions.empty());
  summary_.device_memory = sph::device_memory_per_particle(store_, params_, !scene_.transitions.empty());
}

double Simulation::particle_steps_per_second() const {
  return wall_seconds_ > 0 ? double(particle_steps_) / wall_seconds_ : 0.0;
}

double Simulation::fluid_particle_steps_per_second() const {
  return wall_seconds_ > 0 ? double(fluid_particle_steps_) / wall_seconds_ : 0.0;
}

void Simulation::start() { solver_->start(); }

void Simulation::resume(double time, std::uint64_t steps, std::uint64_t removed, std::uint64_t output_index,
                        std::uint64_t checkpoint_index, std::uint64_t particle_steps, double wall_seconds) {
  solver_->resume(time, steps, removed);
  forces_index_ = 0;
  if (scene_.output.forces_every > 0) forces_index_ = next_index_after(time, scene_.output.forces_every, 0);
  probes_index_ = 0;
  if (scene_.output.probes_every > 0) probes_index_ = next_index_after(time, scene_.output.probes_every, 0);
  output_index_ = output_index;
  checkpoint_index_ = checkpoint_index;
  particle_steps_ = particle_steps;
  wall_seconds_ = wall_seconds;  // the whole run's, so its rate counts the steps and time before the resume alike
}

// A constraint or contact too stiff for the body substeps, told in the scene's terms: which item,
// which key, its value, and what value would do (the substep scales as sqrt(m / k) for a spring's
// stiffness, as m / c for its damping, and for a Hertz contact as E^(-2/5) at a given approach
// speed, E^(-1/3) where the speed of falling through the static overlap sets it: E / ratio^3 does).
static std::string substep_message(const Scene& scene, const SubstepLimitError& e) {
  std::ostringstream os;
  os << std::setprecision(3);
  const double ratio = e.wanted / BodyCoupling::kMaxSubsteps;  // > 1
  if (e.source == SubstepLimitError::Source::constraint && e.index >= 0 &&
      std::size_t(e.index) < scene.constraints.size()) {
    const ConstraintSpec& c = scene.constraints[std::size_t(e.index)];
    os << at_text(c.where, "error");
    os << "constraint '" << c.name << "' needs body substeps of " << e.substep << " s, " << e.wanted
       << " of them in the fluid step of " << e.dt << " s (at most " << BodyCoupling::kMaxSubsteps << "): ";
    if (c.type == ConstraintSpec::Type::hinge)
      os << "its pivot stiffness follows from the bodies' masses and the spacing; give the bodies more mass or "
            "moment of inertia, or use motion: bullet";
    else {
      os << "lower";
      if (c.stiffness > 0)
        os << " its 'stiffness' (" << c.stiffness << " N/m) below about " << c.stiffness / (ratio * ratio) << " N/m";
      if (c.stiffness > 0 && c.damping > 0) os << " or";
      if (c.damping > 0)
        os << " its 'damping' (" << c.damping << " N s/m) below about " << c.damping / ratio << " N s/m";
      if (c.stiffness > 0 && c.damping > 0) os << ", whichever sets the substep";
    }
  } else if (e.source == SubstepLimitError::Source::contact && e.index >= 0 &&
             std::size_t(e.index) < scene.structures.size()) {
    const StructureSpec& st = scene.structures[std::size_t(e.index)];
    os << at_text(st.where, "error");
    os << "the contacts of structure '" << st.name << "' need body substeps of " << e.substep << " s, " << e.wanted
       << " of them in the fluid step of " << e.dt << " s (at most " << BodyCoupling::kMaxSubsteps << "): lower ";
    if (st.contact.given && st.contact.youngs_modulus > 0)
      os << "its 'contact: youngs_modulus' (" << st.contact.youngs_modulus << " Pa) below about "
         << st.contact.youngs_modulus / std::pow(ratio, 3.0) << " Pa";
    else
      os << "the youngs_modulus of the contacts it meets (its own 'contact' and that of the walls or structures "
            "it touches)";
  } else {
    return e.what();
  }
  return os.str();
}

void Simulation::step() { step(std::numeric_limits<double>::infinity()); }

void Simulation::step(double max_dt) {
  const double dt = std::min(solver_->next_time_step(), max_dt);
  particle_steps_ += store_.size();
  // Fluid: all but walls, structures and open-boundary buffers (walls are 25-80% of many scenes).
  const std::size_t fixed = boundary_ghost0_.size() + summary_.buffer_particles;
  fluid_particle_steps_ += store_.size() > fixed ? store_.size() - fixed : 0;
  try {
    solver_->step(dt);
  } catch (const SubstepLimitError& e) {
    throw std::runtime_error(substep_message(scene_, e));
  }
}

std::vector<sph::BodyLoad> Simulation::structure_loads() {
  std::vector<std::array<double, 3>> reference;
  for (const auto& st : scene_.structures) reference.push_back(st.reference_point);
  if (bodies_)
    for (std::size_t k = 0; k < reference.size(); ++k)
      if (bodies_->is_free(k))
        for (int a = 0; a < 3; ++a) reference[k][std::size_t(a)] = bodies_->body(k).position()[a];
  if (prescribed_)
    for (std::size_t k = 0; k < reference.size(); ++k)
      if (prescribed_->is_prescribed(k)) {
        const Eigen::Vector3d x = prescribed_->reference_point(k, time());
        for (int a = 0; a < 3; ++a) reference[k][std::size_t(a)] = x[a];
      }
  return solver_->backend().body_loads(reference);
}

std::vector<BodyKinematics> Simulation::body_kinematics() const {
  std::vector<BodyKinematics> out(scene_.structures.size());
  if (prescribed_)
    for (std::size_t k = 0; k < out.size(); ++k)
      if (prescribed_->is_prescribed(k)) out[k] = prescribed_->kinematics(k, time());
  if (!bodies_) return out;
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (!bodies_->is_free(k)) continue;
    const RigidBody& b = bodies_->body(k);
    const Eigen::Vector3d w = b.angular_velocity();
    const Eigen::Quaterniond& q = b.orientation();
    out[k].orientation = {q.w(), q.x(), q.y(), q.z()};
    for (int a = 0; a < 3; ++a) {
      out[k].position[std::size_t(a)] = b.position()[a];
      out[k].velocity[std::size_t(a)] = b.velocity()[a];
      out[k].angular_velocity[std::size_t(a)] = w[a];
      out[k].contact_force[std::size_t(a)] = bodies_->contact_load(k).force[a];
    }
  }
  return out;
}

FluidBehindWalls Simulation::measure_fluid_behind_walls() {
  sync_to_host();
  PenetrationInput in;
  in.dimensions = scene_.dimensions;
  in.size = store_.size();
  in.position = static_cast<const float*>(store_.raw(ids_.position));
  in.kind = store_.data<std::uint8_t>(ids_.kind);
  in.id = store_.data<std::uint32_t>(ids_.id);
  in.body = ids_.body >= 0 ? store_.data<std::uint8_t>(ids_.body) : nullptr;
  in.ghost0 = &boundary_ghost0_;
  in.first_id = boundary_first_id_;
  in.radius = 2.0 * params_.smoothing_length;  // the kernel support
  in.tolerance = 0.25 * scene_.particle_spacing;  // see fsi/wall_penetration.hpp
  in.band = 0.5 * scene_.particle_spacing;
  in.inside = scene_.particle_spacing;  // as params_.wall_constraint_reach
  for (const auto& k : body_kinematics()) {
    const Eigen::Quaterniond q(k.orientation[0], k.orientation[1], k.orientation[2], k.orientation[3]);
    const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    std::array<double, 9> r{};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) r[std::size_t(3 * a + b)] = R(a, b);
    in.rotation.push_back(r);
  }
  behind_walls_ = count_fluid_behind_walls(in);
  return behind_walls_;
}

std::vector<double> Simulation::probe_values() {
  sync_to_host();
  return evaluate_probes(scene_, store_, ids_, params_);
}

void Simulation::run(Observer& observer) {
  using clock = std::chrono::steady_clock;
  interrupted_ = false;
  const double every = scene_.output.every;
  const double ck_every = scene_.output.checkpoint_every;
  // Output k is due at time k * every; the first step at or past that time writes it.
  auto output_due = [&] { return every > 0 ? double(output_index_) * every : 0.0; };
  // probes.csv (a time column even without probes): every step, every probes_every, else at every
  // output.
  const double p_every = scene_.output.probes_every;
  const bool p_step = scene_.output.probes_each_step;
  auto probes_due = [&](bool output_now) {
    if (p_step) return true;
    if (p_every > 0) return time() >= double(probes_index_) * p_every;
    return output_now;
  };
  auto write_probes = [&] {
    observer.on_probes(*this);
    if (p_every > 0) probes_index_ = next_index_after(time(), p_every, probes_index_);
  };
  const bool output_at_start = output_index_ == 0 || time() >= output_due();
  if (output_at_start) {
    check_fluid_behind_walls();
    observer.on_output(*this);
    ++output_index_;
  }
  // A resumed run's row at its start time was written before the checkpoint.
  if (p_step ? time() == 0.0 : probes_due(output_at_start)) write_probes();
  // forces.csv: every step, every forces_every, else at every output (every step without an
  // output interval).
  const bool structures = !scene_.structures.empty();
  const double f_every = scene_.output.forces_every;
  const bool f_step = scene_.output.forces_each_step;
  auto forces_due = [&](bool output_now) {
    if (!structures) return false;
    if (f_step) return true;
    if (f_every > 0) return time() >= double(forces_index_) * f_every;
    return output_now || every == 0;
  };
  auto write_forces = [&] {
    observer.on_forces(*this);
    if (f_every > 0) forces_index_ = next_index_after(time(), f_every, forces_index_);
  };
  if (structures && time() == 0.0 && forces_index_ == 0) write_forces();
  const auto t0 = clock::now();
  const double wall_before = wall_seconds_;
  auto last_progress = t0;
  // The last step lands on the end time (a run asked for 0.001 s once simulated a whole larger step,
  // issue #28 item 1); a remainder below the smallest allowed step counts as there.
  const double end = scene_.end_time, close = scene_.numerics.min_time_step;
  while (end - time() > close) {
    step(end - time());
    const auto now = clock::now();
    wall_seconds_ = wall_before + std::chrono::duration<double>(now - t0).count();
    const bool last = end - time() <= close;
    const bool output_now = (every > 0 && time() >= output_due()) || last;
    if (forces_due(output_now)) write_forces();
    if (output_now) {
      check_fluid_behind_walls();
      observer.on_output(*this);
      if (every > 0) output_index_ = next_index_after(time(), every, output_index_);
    }
    if (probes_due(output_now)) write_probes();
    if (ck_every > 0 && time() >= double(checkpoint_index_ + 1) * ck_every) {
      checkpoint_index_ = next_index_after(time(), ck_every, checkpoint_index_ + 1) - 1;
      sync_to_host();
      observer.on_checkpoint(*this);
    }
    if (std::chrono::duration<double>(now - last_progress).count() >= 0.5 || last) {
      observer.on_progress(*this);
      last_progress = now;
    }
    if (!last && observer.stop_requested()) {
      interrupted_ = true;
      sync_to_host();
      observer.on_checkpoint(*this);
      break;
    }
  }
  sync_to_host();
  observer.on_finish(*this);
}

// Measured at every output; past the scene's `numerics: max_fluid_behind_walls` the run stops
// (issue #27 item 9), naming the key, the count and the deepest particle.
void Simulation::check_fluid_behind_walls() {
  const FluidBehindWalls& b = measure_fluid_behind_walls();
  const auto& limit = scene_.numerics.max_fluid_behind_walls;
  if (!limit || b.count <= *limit) return;
  std::ostringstream os;
  os << at_text(scene_.numerics.max_fluid_behind_walls_where, "error") << "at t = " << time() << " s, "
     << b.count << " fluid particles are behind a wall or structure surface (" << b.below_walls << " walls, "
     << b.inside_structures << " structures; the deepest " << b.deepest / scene_.particle_spacing
     << " particle spacings behind), more than 'max_fluid_behind_walls' = " << *limit
     << " allows: the walls let fluid through (a finer spacing, more wall layers or a smaller time step "
        "may help), or raise the limit";
  throw std::runtime_error(os.str());
}

// The smallest k >= from with k * every > time: the index of the next output, force row or
// checkpoint of a periodic schedule. Constant time whatever time / every is (a loop of ++k once
// hung a run with every = 1e-300); a schedule past 2^63 entries is never due again.
std::uint64_t next_index_after(double time, double every, std::uint64_t from) {
  if (double(from) * every > time) return from;
  const double q = std::floor(time / every);
  if (!(q < 9.2e18)) return std::numeric_limits<std::uint64_t>::max();
  std::uint64_t k = std::max(from, std::uint64_t(q));
  while (double(k) * every <= time) ++k;  // one or two steps past the rounding of time / every
  return k;
}

}  // namespace turbid::fsi
