// Mesh files -> TriangleMesh (assimp), validation, and lattice sampling into boundary particles; see
// mesh.hpp for the method.
#include "geometry/mesh.hpp"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <unordered_map>
#include <utility>

#include "geometry/mesh_detail.hpp"

namespace turbid::geometry {

namespace {

using namespace detail;

constexpr int kSub = 8;  // integration lines per cell and axis (8 x 8 in 3D, 8 in 2D)

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
std::string fmt(const Point& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buf;
}

std::string capitalised(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = char(s[0] - 'a' + 'A');
  return s;
}

// ---- vertex merging -------------------------------------------------------------------------

// Merges vertices closer than `tol` (hash grid of cell tol, 27 neighbouring cells searched);
// returns the new index of every input vertex.
std::vector<int> merge_vertices(const std::vector<Point>& raw, double tol, std::vector<Point>& merged) {
  std::vector<int> remap(raw.size());
  merged.clear();
  if (raw.empty()) return remap;
  if (!(tol > 0)) {  // all vertices coincide (zero bounding box)
    merged.push_back(raw[0]);
    std::fill(remap.begin(), remap.end(), 0);
    return remap;
  }
  const Aabb box = bounds(raw);
  struct Key {
    std::int64_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      std::uint64_t h = std::uint64_t(k.x) * 0x9E3779B97F4A7C15ull;
      h ^= std::uint64_t(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
      h ^= std::uint64_t(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
      return std::size_t(h);
    }
  };
  std::unordered_map<Key, std::vector<int>, KeyHash> grid;
  grid.reserve(raw.size());
  const double tol2 = tol * tol;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const Point& p = raw[i];
    const Key c{std::int64_t(std::floor((p[0] - box.min[0]) / tol)), std::int64_t(std::floor((p[1] - box.min[1]) / tol)),
                std::int64_t(std::floor((p[2] - box.min[2]) / tol))};
    int found = -1;
    for (int dz = -1; dz <= 1 && found < 0; ++dz)
      for (int dy = -1; dy <= 1 && found < 0; ++dy)
        for (int dx = -1; dx <= 1 && found < 0; ++dx) {
          const auto it = grid.find({c.x + dx, c.y + dy, c.z + dz});
          if (it == grid.end()) continue;
          for (int m : it->second) {
            const Point d = sub(merged[m], p);
            if (dot(d, d) <= tol2) {
              found = m;
              break;
            }
          }
        }
    if (found < 0) {
      found = int(merged.size());
      merged.push_back(p);
      grid[c].push_back(found);
    }
    remap[i] = found;
  }
  return remap;
}

// ---- lattice --------------------------------------------------------------------------------

struct Lattice {
  Point origin{0, 0, 0};
  double dx = 1;
  int n[3] = {1, 1, 1};
  int dims = 3;

  std::size_t size() const { return std::size_t(n[0]) * n[1] * n[2]; }
  std::size_t index(int i, int j, int k) const { return (std::size_t(k) * n[1] + j) * n[0] + i; }
  Point centre(int i, int j, int k) const {
    return {origin[0] + (i + 0.5) * dx, origin[1] + (j + 0.5) * dx, dims == 3 ? origin[2] + (k + 0.5) * dx : 0.0};
  }
  int cell(double x, int axis) const {
    const double c = std::floor((x - origin[axis]) / dx);
    return int(std::clamp(c, 0.0, double(n[axis] - 1)));
  }
};

Lattice make_lattice(const Aabb& box, double dx, int dims) {
  Lattice L;
  L.dx = dx;
  L.dims = dims;
  double cells = 1;
  for (int k = 0; k < dims; ++k) {
    L.origin[k] = box.min[k];
    const double c = std::max(1.0, std::ceil((box.max[k] - box.min[k]) / dx));
    cells *= c;
    if (cells > 4e8)
      throw std::invalid_argument("sample_mesh: the lattice over the mesh's bounding box would have more than 4e8 cells at dx = " +
                                  fmt(dx) + " m; use a coarser spacing");
    L.n[k] = int(c);
  }
  if (dims == 2) L.origin[2] = 0;
  return L;
}

// Adds the inside length of [a, b] within each cell of one lattice line (times `weight`) to acc
// (acc[i] for cell i of the line, stride apart).
void add_interval(const Lattice& L, double a, double b, double weight, double* acc, std::size_t stride) {
  if (!(b > a)) return;
  const int i0 = L.cell(a, 0), i1 = L.cell(b, 0);
  for (int i = i0; i <= i1; ++i) {
    const double lo = L.origin[0] + i * L.dx, hi = L.origin[0] + (i + 1) * L.dx;
    const double len = (a <= lo && b >= hi) ? L.dx : std::min(b, hi) - std::max(a, lo);
    if (len > 0) acc[i * stride] += len * weight;
  }
}


// Integrates the inside intervals of a sorted crossing list into acc.
void integrate_line(const Lattice& L, const std::vector<Crossing>& cr, double weight, double* acc) {
  int w = 0;
  double start = 0;
  for (const auto& c : cr) {
    const int w2 = w + c.sign;
    if (w == 0 && w2 != 0) start = c.x;
    if (w != 0 && w2 == 0) add_interval(L, start, c.x, weight, acc, 1);
    w = w2;
  }
}

// Marks the lattice centres of one line (fixed j, k) whose winding number is non-zero.
void classify_line(const Lattice& L, const std::vector<Crossing>& cr, char* inside) {
  std::size_t q = 0;
  int w = 0;
  for (int i = 0; i < L.n[0]; ++i) {
    const double x = L.origin[0] + (i + 0.5) * L.dx;
    while (q < cr.size() && cr[q].x < x) w += cr[q++].sign;
    inside[i] = w != 0;
  }
}

// Compressed lists: items of bucket b are items[start[b] .. start[b + 1]).
struct Buckets {
  std::vector<std::size_t> start;
  std::vector<int> items;
};

// ---- assembling the body --------------------------------------------------------------------

struct SurfaceHit {
  double depth;
  Point normal;
};

// Finds the kept particle nearest to p (satisfying `accept`), searching the lattice in growing
// shells of cells; -1 if there is none.
int nearest_kept(const Lattice& L, const std::vector<int>& kept, const std::vector<Point>& pts, const Point& p,
                 const std::function<bool(int)>& accept) {
  const int c[3] = {L.cell(p[0], 0), L.cell(p[1], 1), L.dims == 3 ? L.cell(p[2], 2) : 0};
  const int max_ring = std::max({L.n[0], L.n[1], L.n[2]});
  int best = -1;
  double best_d2 = kInf;
  for (int r = 0; r <= max_ring; ++r) {
    // A centre in shell r is at least (r - 0.5) dx away along one axis.
    if (best >= 0 && (r - 0.5) * L.dx > std::sqrt(best_d2)) break;
    const int rz = L.dims == 3 ? r : 0;
    for (int k = std::max(0, c[2] - rz); k <= std::min(L.n[2] - 1, c[2] + rz); ++k)
      for (int j = std::max(0, c[1] - r); j <= std::min(L.n[1] - 1, c[1] + r); ++j)
        for (int i = std::max(0, c[0] - r); i <= std::min(L.n[0] - 1, c[0] + r); ++i) {
          if (std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])}) != r) continue;
          const int id = kept[L.index(i, j, k)];
          if (id < 0 || !accept(id)) continue;
          const Point d = sub(pts[id], p);
          const double d2 = dot(d, d);
          if (d2 < best_d2) {
            best_d2 = d2;
            best = id;
          }
        }
  }
  return best;
}

// Builds the body from the per-cell inside flags of the centres and inside volumes.
// depth_of(centre, limit) gives the nearest surface point's depth and normal, or depth = inf when
// none is nearer than limit. for_each_surface_piece(fn) calls fn(centroid, measure) for pieces of
// the surface smaller than dx/2.
template <class DepthOf, class Pieces>
SampledBody assemble(const Lattice& L, const std::vector<char>& inside, const std::vector<double>& cell_volume,
                     int layers, DepthOf&& depth_of, Pieces&& for_each_surface_piece) {
  SampledBody b;
  std::vector<int> kept(L.size(), -1);
  const double limit = layers > 0 ? layers * L.dx : kInf;
  for (int k = 0; k < L.n[2]; ++k)
    for (int j = 0; j < L.n[1]; ++j)
      for (int i = 0; i < L.n[0]; ++i) {
        const std::size_t c = L.index(i, j, k);
        if (!inside[c]) continue;
        const Point x = L.centre(i, j, k);
        const SurfaceHit h = depth_of(x, limit);
        if (!(h.depth < limit)) continue;
        kept[c] = int(b.points.size());
        b.points.push_back(x);
        b.normals.push_back(h.normal);
        b.depth.push_back(h.depth);
        int layer = int(h.depth / L.dx);
        if (layers > 0) layer = std::min(layer, layers - 1);
        b.layer.push_back(layer);
        b.volumes.push_back(cell_volume[c]);
        b.surface_share.push_back(0.0);
      }
  if (b.points.empty())
    throw MeshError("The mesh is thinner than the particle spacing: no lattice point at dx = " + fmt(L.dx) +
                    " m lies inside it; use a finer spacing or a larger scale.");

  // Cells partly inside whose centre is outside: their inside volume goes to the nearest particle.
  const auto any = [](int) { return true; };
  double total = 0;
  for (int k = 0; k < L.n[2]; ++k)
    for (int j = 0; j < L.n[1]; ++j)
      for (int i = 0; i < L.n[0]; ++i) {
        const std::size_t c = L.index(i, j, k);
        const double v = cell_volume[c];
        if (!(v > 0)) continue;
        total += v;
        if (inside[c]) continue;  // kept (own volume) or deeper than the kept layers
        const int id = nearest_kept(L, kept, b.points, L.centre(i, j, k), any);
        b.volumes[id] += v;
      }
  b.volume = total;

  // Surface pieces to the nearest surface-layer particle (any particle if there is no layer 0).
  bool have_layer0 = false;
  for (int l : b.layer) have_layer0 = have_layer0 || l == 0;
  const std::function<bool(int)> surface_layer = [&](int id) { return !have_layer0 || b.layer[id] == 0; };
  for_each_surface_piece([&](const Point& centroid, double measure) {
    const int id = nearest_kept(L, kept, b.points, centroid, surface_layer);
    b.surface_share[id] += measure;
  });
  for (double s : b.surface_share) b.surface_area += s;
  return b;
}

// ---- 3D ---------------------------------------------------------------------------------------

SampledBody sample_solid(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T, double dx,
                         int layers) {
  const Lattice L = make_lattice(bounds(P), dx, 3);
  const int ny = L.n[1], nz = L.n[2];

  // Triangles bucketed by the (y, z) cells their projection's bounding box overlaps.
  Buckets cols;
  cols.start.assign(std::size_t(ny) * nz + 1, 0);
  auto yz_range = [&](const std::array<int, 3>& t, int r[4]) {
    double lo[2] = {kInf, kInf}, hi[2] = {-kInf, -kInf};
    for (int v : t)
      for (int a = 0; a < 2; ++a) {
        lo[a] = std::min(lo[a], P[v][a + 1]);
        hi[a] = std::max(hi[a], P[v][a + 1]);
      }
    r[0] = L.cell(lo[0], 1);
    r[1] = L.cell(hi[0], 1);
    r[2] = L.cell(lo[1], 2);
    r[3] = L.cell(hi[1], 2);
  };
  for (const auto& t : T) {
    int r[4];
    yz_range(t, r);
    for (int k = r[2]; k <= r[3]; ++k)
      for (int j = r[0]; j <= r[1]; ++j) ++cols.start[std::size_t(k) * ny + j + 1];
  }
  for (std::size_t c = 1; c < cols.start.size(); ++c) cols.start[c] += cols.start[c - 1];
  cols.items.resize(cols.start.back());
  {
    std::vector<std::size_t> fill(cols.start.begin(), cols.start.end() - 1);
    for (std::size_t q = 0; q < T.size(); ++q) {
      int r[4];
      yz_range(T[q], r);
      for (int k = r[2]; k <= r[3]; ++k)
        for (int j = r[0]; j <= r[1]; ++j) cols.items[fill[std::size_t(k) * ny + j]++] = int(q);
    }
  }

  std::vector<char> inside(L.size(), 0);
  std::vector<double> volume(L.size(), 0.0);
  std::vector<Crossing> cr;
  const double h = dx / kSub, weight = h * h;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j) {
      const std::size_t b = std::size_t(k) * ny + j;
      const int* tris = cols.items.data() + cols.start[b];
      const std::size_t count = cols.start[b + 1] - cols.start[b];
      if (count == 0) continue;
      const double yc = L.origin[1] + (j + 0.5) * dx, zc = L.origin[2] + (k + 0.5) * dx;
      line_crossings(P, T, tris, count, yc, zc, cr);
      classify_line(L, cr, inside.data() + L.index(0, j, k));
      for (int bz = 0; bz < kSub; ++bz)
        for (int by = 0; by < kSub; ++by) {
          const double y = L.origin[1] + (j + (by + 0.5) / kSub) * dx, z = L.origin[2] + (k + (bz + 0.5) / kSub) * dx;
          line_crossings(P, T, tris, count, y, z, cr);
          integrate_line(L, cr, weight, volume.data() + L.index(0, j, k));
        }
    }

  // Nearest-triangle queries and pseudo-normals (for particles on the surface).
  std::vector<std::array<Point, 2>> boxes(T.size());
  std::vector<Point> face_normal(T.size());
  std::vector<Point> vertex_normal(P.size(), Point{0, 0, 0});
  std::unordered_map<std::uint64_t, Point> edge_normal;
  edge_normal.reserve(T.size() * 2);
  for (std::size_t q = 0; q < T.size(); ++q) {
    const auto& t = T[q];
    Point lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
    for (int v : t)
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], P[v][a]);
        hi[a] = std::max(hi[a], P[v][a]);
      }
    boxes[q] = {lo, hi};
    const Point n = unit_or_zero(cross(sub(P[t[1]], P[t[0]]), sub(P[t[2]], P[t[0]])));
    face_normal[q] = n;
    for (int c = 0; c < 3; ++c) {
      const Point e1 = sub(P[t[(c + 1) % 3]], P[t[c]]), e2 = sub(P[t[(c + 2) % 3]], P[t[c]]);
      const double angle = std::atan2(norm(cross(e1, e2)), dot(e1, e2));
      vertex_normal[t[c]] = add(vertex_normal[t[c]], mul(n, angle));
      Point& en = edge_normal[edge_key(t[c], t[(c + 1) % 3])];
      en = add(en, n);
    }
  }
  const Bvh bvh(std::move(boxes));

  // Queries come in lattice order: the previous answer's triangle bounds the next search.
  int hint = -1;
  auto depth_of = [&](const Point& x, double limit) -> SurfaceHit {
    double best_d2 = limit < kInf ? limit * limit : kInf;
    Point best_c{0, 0, 0};
    Feature best_f = kFace;
    auto dist2 = [&](int q) {
      Feature f;
      const auto& t = T[q];
      const Point c = closest_on_triangle(x, P[t[0]], P[t[1]], P[t[2]], f);
      const Point d = sub(c, x);
      const double d2 = dot(d, d);
      if (d2 < best_d2) {
        best_c = c;
        best_f = f;
      }
      return d2;
    };
    int tri = -1;
    if (hint >= 0) {
      const double d2 = dist2(hint);
      if (d2 < best_d2) {
        best_d2 = d2;
        tri = hint;
      }
    }
    const int found = bvh.nearest(x, best_d2, dist2);
    if (found >= 0) tri = found;
    if (tri < 0) return {kInf, {0, 0, 0}};
    hint = tri;
    const double depth = std::sqrt(best_d2);
    if (depth > 1e-9 * dx) return {depth, mul(sub(best_c, x), 1.0 / depth)};
    const auto& t = T[tri];
    Point n;
    switch (best_f) {
      case kFace: n = face_normal[tri]; break;
      case kVertexA: n = vertex_normal[t[0]]; break;
      case kVertexB: n = vertex_normal[t[1]]; break;
      case kVertexC: n = vertex_normal[t[2]]; break;
      case kEdgeAB: n = edge_normal[edge_key(t[0], t[1])]; break;
      case kEdgeBC: n = edge_normal[edge_key(t[1], t[2])]; break;
      default: n = edge_normal[edge_key(t[2], t[0])]; break;
    }
    return {depth, unit_or_zero(n)};
  };

  auto pieces = [&](auto&& give) {
    for (const auto& t : T) {
      const Point a = P[t[0]], u = sub(P[t[1]], a), v = sub(P[t[2]], a);
      const double longest = std::max({norm(u), norm(v), norm(sub(v, u))});
      const double area = 0.5 * norm(cross(u, v));
      if (!(area > 0)) continue;
      const int m = std::max(1, int(std::ceil(longest / (0.5 * dx) * (1 + 1e-12))));
      const double piece = area / (double(m) * m);
      for (int i = 0; i < m; ++i)
        for (int j = 0; j + i < m; ++j) {
          give(add(a, add(mul(u, (i + 1.0 / 3.0) / m), mul(v, (j + 1.0 / 3.0) / m))), piece);
          if (i + j + 1 < m) give(add(a, add(mul(u, (i + 2.0 / 3.0) / m), mul(v, (j + 2.0 / 3.0) / m))), piece);
        }
    }
  };
  return assemble(L, inside, volume, layers, depth_of, pieces);
}

// ---- 2D ---------------------------------------------------------------------------------------

SampledBody sample_section(const std::vector<std::vector<Point>>& loops, double dx, int layers) {
  struct Segment {
    Point a, b, normal;
    int loop, index;
  };
  std::vector<Segment> segs;
  std::vector<Point> all;
  std::vector<std::vector<Point>> vertex_normal(loops.size());
  for (std::size_t l = 0; l < loops.size(); ++l) {
    const auto& lp = loops[l];
    const std::size_t n = lp.size();
    vertex_normal[l].assign(n, Point{0, 0, 0});
    for (std::size_t i = 0; i < n; ++i) {
      const Point a = lp[i], b = lp[(i + 1) % n];
      const Point nn = unit_or_zero({b[1] - a[1], a[0] - b[0], 0.0});  // right of a -> b: outward
      segs.push_back({a, b, nn, int(l), int(i)});
      vertex_normal[l][i] = add(vertex_normal[l][i], nn);
      vertex_normal[l][(i + 1) % n] = add(vertex_normal[l][(i + 1) % n], nn);
      all.push_back(a);
    }
  }
  const Lattice L = make_lattice(bounds(all), dx, 2);
  const int ny = L.n[1];

  // Segments bucketed by the lattice rows their y range overlaps.
  Buckets rows;
  rows.start.assign(std::size_t(ny) + 1, 0);
  for (const auto& s : segs)
    for (int j = L.cell(std::min(s.a[1], s.b[1]), 1); j <= L.cell(std::max(s.a[1], s.b[1]), 1); ++j) ++rows.start[j + 1];
  for (std::size_t c = 1; c < rows.start.size(); ++c) rows.start[c] += rows.start[c - 1];
  rows.items.resize(rows.start.back());
  {
    std::vector<std::size_t> fill(rows.start.begin(), rows.start.end() - 1);
    for (std::size_t q = 0; q < segs.size(); ++q) {
      const auto& s = segs[q];
      for (int j = L.cell(std::min(s.a[1], s.b[1]), 1); j <= L.cell(std::max(s.a[1], s.b[1]), 1); ++j)
        rows.items[fill[j]++] = int(q);
    }
  }
  std::vector<Crossing> cr;
  auto row_crossings = [&](int j, double y0) {
    cr.clear();
    for (std::size_t q = rows.start[j]; q < rows.start[j + 1]; ++q) {
      const auto& s = segs[rows.items[q]];
      Crossing c;
      if (segment_crossing(s.a, s.b, y0, c)) cr.push_back(c);
    }
    std::sort(cr.begin(), cr.end(), [](const Crossing& a, const Crossing& b) { return a.x < b.x; });
  };
  std::vector<char> inside(L.size(), 0);
  std::vector<double> area(L.size(), 0.0);
  for (int j = 0; j < ny; ++j) {
    row_crossings(j, L.origin[1] + (j + 0.5) * dx);
    classify_line(L, cr, inside.data() + L.index(0, j, 0));
    for (int by = 0; by < kSub; ++by) {
      row_crossings(j, L.origin[1] + (j + (by + 0.5) / kSub) * dx);
      integrate_line(L, cr, dx / kSub, area.data() + L.index(0, j, 0));
    }
  }

  std::vector<std::array<Point, 2>> boxes(segs.size());
  for (std::size_t q = 0; q < segs.size(); ++q) {
    const auto& s = segs[q];
    boxes[q] = {Point{std::min(s.a[0], s.b[0]), std::min(s.a[1], s.b[1]), 0.0},
                Point{std::max(s.a[0], s.b[0]), std::max(s.a[1], s.b[1]), 0.0}};
  }
  const Bvh bvh(std::move(boxes));
  int hint = -1;  // the previous query's segment bounds the next search (lattice order)
  auto depth_of = [&](const Point& x, double limit) -> SurfaceHit {
    double best_d2 = limit < kInf ? limit * limit : kInf;
    Point best_c{0, 0, 0};
    double best_t = 0.5;
    auto dist2 = [&](int i) {
      double t;
      const Point c = closest_on_segment(x, segs[i].a, segs[i].b, t);
      const Point d = sub(c, x);
      const double d2 = dot(d, d);
      if (d2 < best_d2) {
        best_c = c;
        best_t = t;
      }
      return d2;
    };
    int q = -1;
    if (hint >= 0) {
      const double d2 = dist2(hint);
      if (d2 < best_d2) {
        best_d2 = d2;
        q = hint;
      }
    }
    const int found = bvh.nearest(x, best_d2, dist2);
    if (found >= 0) q = found;
    if (q < 0) return {kInf, {0, 0, 0}};
    hint = q;
    const double depth = std::sqrt(best_d2);
    if (depth > 1e-9 * dx) return {depth, mul(sub(best_c, x), 1.0 / depth)};
    const auto& s = segs[q];
    const auto& vn = vertex_normal[s.loop];
    const Point n = best_t <= 0 ? vn[s.index] : (best_t >= 1 ? vn[(s.index + 1) % vn.size()] : s.normal);
    return {depth, unit_or_zero(n)};
  };
  auto pieces = [&](auto&& give) {
    for (const auto& s : segs) {
      const Point u = sub(s.b, s.a);
      const double len = norm(u);
      if (!(len > 0)) continue;
      const int m = std::max(1, int(std::ceil(len / (0.5 * dx) * (1 + 1e-12))));
      for (int i = 0; i < m; ++i) give(add(s.a, mul(u, (i + 0.5) / m)), len / m);
    }
  };
  return assemble(L, inside, area, layers, depth_of, pieces);
}

}  // namespace

// ---- TriangleMesh ---------------------------------------------------------------------------

double TriangleMesh::area() const {
  double a = 0;
  for (const auto& t : triangles)
    a += 0.5 * norm(cross(sub(vertices[t[1]], vertices[t[0]]), sub(vertices[t[2]], vertices[t[0]])));
  return a;
}

double TriangleMesh::volume() const {
  if (vertices.empty()) return 0;
  // About the bounding-box centre, to keep the sum free of cancellation far from the origin.
  const Aabb box = bounds(vertices);
  const Point o = mul(add(box.min, box.max), 0.5);
  double v = 0;
  for (const auto& t : triangles)
    v += dot(sub(vertices[t[0]], o), cross(sub(vertices[t[1]], o), sub(vertices[t[2]], o)));
  return v / 6.0;
}

// ---- validation -----------------------------------------------------------------------------

void validate_mesh(const TriangleMesh& mesh, const std::string& subject) {
  const std::string who = capitalised(subject);
  if (mesh.triangles.empty()) throw MeshError(who + " is empty: it contains no triangles.");
  const int nv = int(mesh.vertices.size());
  for (std::size_t q = 0; q < mesh.triangles.size(); ++q) {
    const auto& t = mesh.triangles[q];
    for (int v : t)
      if (v < 0 || v >= nv)
        throw MeshError(who + " is invalid: triangle " + std::to_string(q) + " refers to vertex " + std::to_string(v) +
                        ", but there are " + std::to_string(nv) + " vertices.");
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      throw MeshError(who + " is invalid: triangle " + std::to_string(q) + " repeats a vertex.");
  }
  // Uses of each edge: along (lo -> hi) and against.
  struct Uses {
    int along = 0, against = 0;
  };
  std::unordered_map<std::uint64_t, Uses> uses;
  uses.reserve(mesh.triangles.size() * 2);
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const int a = t[c], b = t[(c + 1) % 3];
      Uses& u = uses[edge_key(a, b)];
      (a < b ? u.along : u.against)++;
    }
  std::size_t open = 0, multiple = 0, misoriented = 0;
  for (const auto& [key, u] : uses) {
    const int n = u.along + u.against;
    open += n == 1;
    multiple += n > 2;
    misoriented += n == 2 && u.along != 1;
  }
  // The first offending edge in triangle order, for the message.
  auto example = [&](auto&& bad, int* count) {
    for (const auto& t : mesh.triangles)
      for (int c = 0; c < 3; ++c) {
        const int a = t[c], b = t[(c + 1) % 3];
        const Uses& u = uses.at(edge_key(a, b));
        if (bad(u)) {
          if (count) *count = u.along + u.against;
          return "the edge from " + fmt(mesh.vertices[a]) + " to " + fmt(mesh.vertices[b]);
        }
      }
    return std::string("?");
  };
  if (open > 0)
    throw MeshError(who + " is open: " + std::to_string(open) + " boundary edge" + (open == 1 ? "" : "s") + ", e.g. " +
                    example([](const Uses& u) { return u.along + u.against == 1; }, nullptr) +
                    " (an edge of only one triangle); a structure must be a closed (watertight) surface.");
  if (multiple > 0) {
    int n = 0;
    const std::string e = example([](const Uses& u) { return u.along + u.against > 2; }, &n);
    throw MeshError(who + " is non-manifold: " + std::to_string(multiple) + " edge" + (multiple == 1 ? " is" : "s are") +
                    " shared by more than two triangles, e.g. " + e + " (shared by " + std::to_string(n) +
                    "); every edge of a closed surface must join exactly two.");
  }
  if (misoriented > 0)
    throw MeshError(who + " has an inconsistent orientation: " + std::to_string(misoriented) + " edge" +
                    (misoriented == 1 ? " is" : "s are") + " traversed twice in the same direction, e.g. " +
                    example([](const Uses& u) { return u.along + u.against == 2 && u.along != 1; }, nullptr) +
                    "; all faces must be ordered the same way (counter-clockwise seen from outside).");
  const double v = mesh.volume();
  const Aabb box = bounds(mesh.vertices);
  const double diag = norm(sub(box.max, box.min));
  if (v < -1e-12 * diag * diag * diag)
    throw MeshError(who + " is inside-out: its signed volume is " + fmt(v) +
                    ", so its normals point inward; flip the faces (reverse the vertex order of every triangle).");
  if (!(v > 1e-12 * diag * diag * diag))
    throw MeshError(who + " encloses no volume (signed volume " + fmt(v) + "): it is flat.");
}

// ---- loading --------------------------------------------------------------------------------

TriangleMesh load_mesh(const std::string& path) {
  const std::string subject = "mesh file '" + path + "'";
  const std::string who = capitalised(subject);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw MeshError(who + " was not found.");
  if (!std::filesystem::is_regular_file(path, ec)) throw MeshError(who + " is not a regular file.");
  if (std::filesystem::file_size(path, ec) == 0 && !ec) throw MeshError(who + " is empty (0 bytes).");

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    std::string reason = importer.GetErrorString();
    while (!reason.empty() && (reason.back() == '\n' || reason.back() == '.' || reason.back() == ' ')) reason.pop_back();
    if (reason.empty()) reason = "unknown error";
    throw MeshError(who + " could not be read: " + reason + ".");
  }

  // All meshes of all nodes, moved by the accumulated node transforms.
  std::vector<Point> raw;
  std::vector<std::array<int, 3>> raw_tris;
  std::function<void(const aiNode*, const aiMatrix4x4&)> visit = [&](const aiNode* node, const aiMatrix4x4& parent) {
    const aiMatrix4x4 m = parent * node->mTransformation;
    const bool mirror = m.Determinant() < 0;
    for (unsigned q = 0; q < node->mNumMeshes; ++q) {
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[q]];
      const int base = int(raw.size());
      for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const double x = p.x, y = p.y, z = p.z;
        raw.push_back({m.a1 * x + m.a2 * y + m.a3 * z + m.a4, m.b1 * x + m.b2 * y + m.b3 * z + m.b4,
                       m.c1 * x + m.c2 * y + m.c3 * z + m.c4});
      }
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines have no area
        std::array<int, 3> t{base + int(face.mIndices[0]), base + int(face.mIndices[1]), base + int(face.mIndices[2])};
        if (mirror) std::swap(t[1], t[2]);
        raw_tris.push_back(t);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], m);
  };
  visit(scene->mRootNode, aiMatrix4x4());
  if (raw_tris.empty()) throw MeshError(who + " is empty: it contains no triangles.");

  TriangleMesh mesh;
  const Aabb box = bounds(raw);
  const std::vector<int> remap = merge_vertices(raw, 1e-9 * norm(sub(box.max, box.min)), mesh.vertices);
  for (const auto& t : raw_tris) {
    const std::array<int, 3> m{remap[t[0]], remap[t[1]], remap[t[2]]};
    if (m[0] == m[1] || m[1] == m[2] || m[2] == m[0]) continue;  // collapsed: no area
    mesh.triangles.push_back(m);
  }
  if (mesh.triangles.empty()) throw MeshError(who + " is empty: all its triangles have zero size.");
  validate_mesh(mesh, subject);
  return mesh;
}

// ---- sampling -------------------------------------------------------------------------------

SampledBody sample_mesh(const TriangleMesh& mesh, double dx, int layers, int dims, const Placement& placement) {
  if (!(dx > 0) || !std::isfinite(dx)) throw std::invalid_argument("sample_mesh: spacing dx must be positive");
  if (dims != 2 && dims != 3) throw std::invalid_argument("sample_mesh: dims must be 2 or 3");
  if (!(placement.scale > 0) || !std::isfinite(placement.scale))
    throw std::invalid_argument("sample_mesh: placement scale must be positive");
  validate_mesh(mesh, "the mesh");
  const PlacementMap map(placement);
  std::vector<Point> P(mesh.vertices.size());
  for (std::size_t v = 0; v < P.size(); ++v) P[v] = map.apply(mesh.vertices[v]);
  if (dims == 3) return sample_solid(P, mesh.triangles, dx, layers);
  return sample_section(cut_by_plane(P, mesh.triangles), dx, layers);
}

}  // namespace turbid::geometry
