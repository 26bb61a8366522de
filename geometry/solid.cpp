// Exact signed distances of placed primitives and meshes; see solid.hpp.
#include "geometry/solid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "geometry/mesh_detail.hpp"

namespace turbid::geometry {

using namespace detail;

class Solid::Shape {
 public:
  virtual ~Shape() = default;
  // Signed distance with the early-exit contract of Solid::signed_distance(p, cutoff).
  virtual double distance(const Point& p, double cutoff) const = 0;
  Aabb box;
  int dims = 3;
};

namespace {

void check_common(const char* who, int dims, const Placement& pl, bool planar_placement) {
  const std::string w(who);
  if (dims != 2 && dims != 3) throw std::invalid_argument(w + ": dims must be 2 or 3");
  if (!(pl.scale > 0) || !std::isfinite(pl.scale)) throw std::invalid_argument(w + ": placement scale must be positive");
  if (planar_placement && dims == 2 && (pl.rotation_deg[0] != 0 || pl.rotation_deg[1] != 0 || pl.translation[2] != 0))
    throw std::invalid_argument(w + ": in 2D only a rotation about z and an in-plane translation are allowed");
}

void check_positive(const char* who, const char* what, double v) {
  if (!(v > 0) || !std::isfinite(v)) throw std::invalid_argument(std::string(who) + ": " + what + " must be positive");
}

// ---- primitives -------------------------------------------------------------------------------

class Primitive final : public Solid::Shape {
 public:
  enum Kind { kBox, kBall, kCylinder };

  // half: half extents in the primitive's scaled frame (box: size / 2; ball: R; cylinder: R, R, L/2).
  Primitive(Kind kind, const Point& half, int d, const Placement& pl) : kind_(kind), half_(half), map_(pl) {
    dims = d;
    box = {{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
    for (int c = 0; c < 8; ++c) {
      const Point corner{(c & 1) ? half[0] : -half[0], (c & 2) ? half[1] : -half[1], (c & 4) ? half[2] : -half[2]};
      const Point q = map_.move(corner);
      for (int k = 0; k < 3; ++k) {
        box.min[k] = std::min(box.min[k], q[k]);
        box.max[k] = std::max(box.max[k], q[k]);
      }
    }
    if (dims == 2) box.min[2] = box.max[2] = 0;
  }

  double distance(const Point& p, double) const override {
    const Point q = map_.move_back(dims == 2 ? Point{p[0], p[1], 0.0} : p);
    switch (kind_) {
      case kBox: {
        double out2 = 0, in = -kInf;
        for (int k = 0; k < dims; ++k) {
          const double e = std::abs(q[k]) - half_[k];
          in = std::max(in, e);
          if (e > 0) out2 += e * e;
        }
        return in > 0 ? std::sqrt(out2) : in;
      }
      case kBall: return (dims == 2 ? std::hypot(q[0], q[1]) : std::hypot(q[0], q[1], q[2])) - half_[0];
      case kCylinder: {
        const double s = std::hypot(q[0], q[1]) - half_[0];
        if (dims == 2) return s;
        const double a = std::abs(q[2]) - half_[2];
        if (s <= 0 && a <= 0) return std::max(s, a);
        return std::hypot(std::max(s, 0.0), std::max(a, 0.0));
      }
    }
    return kInf;
  }

 private:
  Kind kind_;
  Point half_;
  PlacementMap map_;
};

// ---- meshes -----------------------------------------------------------------------------------

// A uniform grid of buckets over a 1D or 2D range; items of cell c are items[start[c] .. start[c+1]).
struct Grid {
  double origin[2] = {0, 0}, size[2] = {1, 1};
  int n[2] = {1, 1};
  std::vector<std::size_t> start;
  std::vector<int> items;

  // lo/hi: the range covered; cells: about how many cells to use.
  void shape(const double lo[2], const double hi[2], int axes, double cells) {
    double measure = 1;
    for (int a = 0; a < axes; ++a) measure *= std::max(hi[a] - lo[a], 1e-300);
    const double s = std::pow(measure / std::max(cells, 1.0), 1.0 / axes);
    for (int a = 0; a < 2; ++a) {
      origin[a] = lo[a];
      n[a] = a < axes ? int(std::clamp(std::ceil((hi[a] - lo[a]) / s), 1.0, 4096.0)) : 1;
      size[a] = a < axes && hi[a] > lo[a] ? (hi[a] - lo[a]) / n[a] : 1.0;
    }
  }
  int cell(double x, int a) const {
    const double c = std::floor((x - origin[a]) / size[a]);
    return int(std::clamp(c, 0.0, double(n[a] - 1)));
  }
  // Fills the buckets from the [lo, hi] range of every item (range(i, lo, hi)).
  template <class Range>
  void fill(std::size_t count, Range&& range) {
    start.assign(std::size_t(n[0]) * n[1] + 1, 0);
    auto each_cell = [&](std::size_t i, auto&& fn) {
      double lo[2], hi[2];
      range(i, lo, hi);
      const int i0 = cell(lo[0], 0), i1 = cell(hi[0], 0), j0 = cell(lo[1], 1), j1 = cell(hi[1], 1);
      for (int j = j0; j <= j1; ++j)
        for (int k = i0; k <= i1; ++k) fn(std::size_t(j) * n[0] + k);
    };
    for (std::size_t i = 0; i < count; ++i) each_cell(i, [&](std::size_t c) { ++start[c + 1]; });
    for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    items.resize(start.back());
    std::vector<std::size_t> at(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < count; ++i) each_cell(i, [&](std::size_t c) { items[at[c]++] = int(i); });
  }
};

// Common part of the mesh shapes: the early exits outside the bounding box and the combination of
// the inside test with the nearest-item search.
template <class Derived>
class MeshShape : public Solid::Shape {
 public:
  double distance(const Point& p0, double cutoff) const override {
    const Point p = dims == 2 ? Point{p0[0], p0[1], 0.0} : p0;
    const double box_d = std::sqrt(box_distance2(box.min, box.max, p));
    if (box_d > 0 && box_d >= cutoff) return box_d;  // outside, and no nearer than cutoff
    const bool in = box_d == 0 && static_cast<const Derived&>(*this).inside(p);
    double best_d2 = cutoff < kInf ? cutoff * cutoff : kInf;
    const int found = bvh_.nearest(p, best_d2, [&](int i) { return static_cast<const Derived&>(*this).distance2(p, i); });
    const double d = found >= 0 ? std::sqrt(best_d2) : std::max(cutoff, box_d);
    return in ? -d : d;
  }

 protected:
  explicit MeshShape(std::vector<std::array<Point, 2>> boxes) : bvh_(std::move(boxes)) {}
  Bvh bvh_;
};

std::vector<std::array<Point, 2>> triangle_boxes(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T) {
  std::vector<std::array<Point, 2>> boxes(T.size());
  for (std::size_t q = 0; q < T.size(); ++q) {
    Point lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
    for (int v : T[q])
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], P[v][a]);
        hi[a] = std::max(hi[a], P[v][a]);
      }
    boxes[q] = {lo, hi};
  }
  return boxes;
}

class Mesh3D final : public MeshShape<Mesh3D> {
 public:
  Mesh3D(std::vector<Point> P, std::vector<std::array<int, 3>> T)
      : MeshShape(triangle_boxes(P, T)), P_(std::move(P)), T_(std::move(T)) {
    dims = 3;
    box = bounds(P_);
    // (y, z) buckets of the triangles' projections, about two cells per triangle.
    const double lo[2] = {box.min[1], box.min[2]}, hi[2] = {box.max[1], box.max[2]};
    grid_.shape(lo, hi, 2, 2.0 * double(T_.size()));
    grid_.fill(T_.size(), [&](std::size_t q, double l[2], double h[2]) {
      l[0] = l[1] = kInf;
      h[0] = h[1] = -kInf;
      for (int v : T_[q])
        for (int a = 0; a < 2; ++a) {
          l[a] = std::min(l[a], P_[v][a + 1]);
          h[a] = std::max(h[a], P_[v][a + 1]);
        }
    });
  }

  // Winding number of the line through p parallel to x, up to p (mesh.hpp's inside test).
  bool inside(const Point& p) const {
    const std::size_t c = std::size_t(grid_.cell(p[2], 1)) * grid_.n[0] + grid_.cell(p[1], 0);
    int w = 0;
    Crossing cr;
    for (std::size_t q = grid_.start[c]; q < grid_.start[c + 1]; ++q)
      if (triangle_crossing(P_, T_[grid_.items[q]], p[1], p[2], cr) && cr.x < p[0]) w += cr.sign;
    return w != 0;
  }

  double distance2(const Point& p, int q) const {
    Feature f;
    const auto& t = T_[q];
    const Point d = sub(closest_on_triangle(p, P_[t[0]], P_[t[1]], P_[t[2]], f), p);
    return dot(d, d);
  }

 private:
  std::vector<Point> P_;
  std::vector<std::array<int, 3>> T_;
  Grid grid_;
};

struct Segment {
  Point a, b;  // outside on the right of a -> b
};

std::vector<Segment> segments_of(const std::vector<std::vector<Point>>& loops) {
  std::vector<Segment> segs;
  for (const auto& lp : loops)
    for (std::size_t i = 0; i < lp.size(); ++i) segs.push_back({lp[i], lp[(i + 1) % lp.size()]});
  return segs;
}

std::vector<std::array<Point, 2>> segment_boxes(const std::vector<Segment>& segs) {
  std::vector<std::array<Point, 2>> boxes(segs.size());
  for (std::size_t q = 0; q < segs.size(); ++q) {
    const auto& s = segs[q];
    boxes[q] = {Point{std::min(s.a[0], s.b[0]), std::min(s.a[1], s.b[1]), 0.0},
                Point{std::max(s.a[0], s.b[0]), std::max(s.a[1], s.b[1]), 0.0}};
  }
  return boxes;
}

class Mesh2D final : public MeshShape<Mesh2D> {
 public:
  explicit Mesh2D(std::vector<Segment> segs) : MeshShape(segment_boxes(segs)), segs_(std::move(segs)) {
    dims = 2;
    box = {{kInf, kInf, 0.0}, {-kInf, -kInf, 0.0}};
    for (const auto& s : segs_)
      for (int a = 0; a < 2; ++a) {
        box.min[a] = std::min(box.min[a], s.a[a]);
        box.max[a] = std::max(box.max[a], s.a[a]);
      }
    // Rows in y, about one per segment.
    const double lo[2] = {box.min[1], 0.0}, hi[2] = {box.max[1], 0.0};
    grid_.shape(lo, hi, 1, double(segs_.size()));
    grid_.fill(segs_.size(), [&](std::size_t q, double l[2], double h[2]) {
      l[0] = std::min(segs_[q].a[1], segs_[q].b[1]);
      h[0] = std::max(segs_[q].a[1], segs_[q].b[1]);
      l[1] = h[1] = 0;
    });
  }

  // Winding number of the line through p parallel to x, up to p (sample_mesh's 2D inside test).
  bool inside(const Point& p) const {
    const int r = grid_.cell(p[1], 0);
    int w = 0;
    Crossing cr;
    for (std::size_t q = grid_.start[r]; q < grid_.start[r + 1]; ++q) {
      const auto& s = segs_[grid_.items[q]];
      if (segment_crossing(s.a, s.b, p[1], cr) && cr.x < p[0]) w += cr.sign;
    }
    return w != 0;
  }

  double distance2(const Point& p, int q) const {
    double t;
    const Point d = sub(closest_on_segment(p, segs_[q].a, segs_[q].b, t), p);
    return dot(d, d);
  }

 private:
  std::vector<Segment> segs_;
  Grid grid_;
};

}  // namespace

// ---- Solid ----------------------------------------------------------------------------------------

Solid Solid::box(Point size, int dims, const Placement& pl) {
  check_common("Solid::box", dims, pl, true);
  for (int k = 0; k < dims; ++k) check_positive("Solid::box", "size", size[k]);
  if (dims == 2) size[2] = 0;
  return Solid(std::make_shared<Primitive>(Primitive::kBox, mul(size, 0.5 * pl.scale), dims, pl));
}

Solid Solid::sphere(double radius, int dims, const Placement& pl) {
  check_common("Solid::sphere", dims, pl, true);
  check_positive("Solid::sphere", "radius", radius);
  const double R = radius * pl.scale;
  return Solid(std::make_shared<Primitive>(Primitive::kBall, Point{R, R, dims == 3 ? R : 0.0}, dims, pl));
}

Solid Solid::cylinder(double radius, double length, int dims, const Placement& pl) {
  check_common("Solid::cylinder", dims, pl, true);
  check_positive("Solid::cylinder", "radius", radius);
  const double R = radius * pl.scale;
  if (dims == 2) return Solid(std::make_shared<Primitive>(Primitive::kCylinder, Point{R, R, 0.0}, dims, pl));
  check_positive("Solid::cylinder", "length", length);
  return Solid(std::make_shared<Primitive>(Primitive::kCylinder, Point{R, R, 0.5 * length * pl.scale}, dims, pl));
}

Solid Solid::mesh(const TriangleMesh& mesh, int dims, const Placement& pl) {
  check_common("Solid::mesh", dims, pl, false);
  validate_mesh(mesh, "the mesh");
  const PlacementMap map(pl);
  std::vector<Point> P(mesh.vertices.size());
  for (std::size_t v = 0; v < P.size(); ++v) P[v] = map.apply(mesh.vertices[v]);
  if (dims == 3) return Solid(std::make_shared<Mesh3D>(std::move(P), mesh.triangles));
  return Solid(std::make_shared<Mesh2D>(segments_of(cut_by_plane(P, mesh.triangles))));
}

double Solid::signed_distance(const Point& p) const { return shape_->distance(p, kInf); }

double Solid::signed_distance(const Point& p, double cutoff) const {
  return shape_->distance(p, std::max(cutoff, 0.0));
}

const Aabb& Solid::bounds() const { return shape_->box; }

int Solid::dims() const { return shape_->dims; }

}  // namespace turbid::geometry
