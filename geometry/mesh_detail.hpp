// Internals shared by the mesh sampler (mesh.cpp) and the signed distance of mesh solids
// (solid.cpp): small vector helpers, a bounding-volume hierarchy for nearest-item queries, closest
// points on segments and triangles, the crossings of lines parallel to x with triangles (3D) and
// of lines parallel to x with segments (2D) that decide inside / outside, and the section of a
// mesh by the plane z = 0. Not part of the geometry API: no checks of arguments here.
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "geometry/shapes.hpp"

namespace turbid::geometry::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

inline Point sub(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Point add(const Point& a, const Point& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Point mul(const Point& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Point& a) { return std::sqrt(dot(a, a)); }
inline Point unit_or_zero(const Point& a) {
  const double n = norm(a);
  return n > 0 ? mul(a, 1.0 / n) : Point{0, 0, 0};
}

// Key of the undirected edge {a, b}.
inline std::uint64_t edge_key(int a, int b) {
  const auto lo = std::uint64_t(std::uint32_t(std::min(a, b))), hi = std::uint64_t(std::uint32_t(std::max(a, b)));
  return (lo << 32) | hi;
}

// Bounding box of a point set (min = +inf, max = -inf for none).
Aabb bounds(const std::vector<Point>& pts);

// Squared distance from p to the box [lo, hi] (0 inside).
inline double box_distance2(const Point& lo, const Point& hi, const Point& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({lo[k] - p[k], 0.0, p[k] - hi[k]});
    d2 += d * d;
  }
  return d2;
}

// ---- bounding-volume hierarchy for nearest-item queries --------------------------------------

// Median-split BVH over item boxes (leaves of up to 4 items). Owns its boxes; const queries are
// safe from several threads.
class Bvh {
 public:
  // boxes[i] = {min, max} of item i.
  explicit Bvh(std::vector<std::array<Point, 2>> boxes) : boxes_(std::move(boxes)) {
    order_.resize(boxes_.size());
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = int(i);
    nodes_.reserve(2 * boxes_.size() / kLeaf + 2);
    if (!boxes_.empty()) build(0, int(boxes_.size()));
  }

  // The item minimising dist2(item) (a squared distance) among those with dist2 < best_d2; -1 if
  // none. best_d2 is lowered to the distance found.
  template <class F>
  int nearest(const Point& p, double& best_d2, F&& dist2) const {
    int best = -1;
    if (nodes_.empty()) return best;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (box_d2(n, p) >= best_d2) continue;
      if (n.count > 0) {
        for (int q = n.start; q < n.start + n.count; ++q) {
          const double d2 = dist2(order_[q]);
          if (d2 < best_d2) {
            best_d2 = d2;
            best = order_[q];
          }
        }
        continue;
      }
      const int l = int(&n - nodes_.data()) + 1, r = n.right;
      const double dl = box_d2(nodes_[l], p), dr = box_d2(nodes_[r], p);
      // Nearer child popped first.
      const int first = dl <= dr ? l : r, second = dl <= dr ? r : l;
      const double d_first = std::min(dl, dr), d_second = std::max(dl, dr);
      if (d_second < best_d2 && top < 127) stack[top++] = second;
      if (d_first < best_d2 && top < 127) stack[top++] = first;
    }
    return best;
  }

 private:
  static constexpr int kLeaf = 4;
  struct Node {
    Point lo, hi;
    int start = 0, count = 0;  // leaf: items order_[start, start + count)
    int right = -1;            // internal: left child is the next node
  };

  static double box_d2(const Node& n, const Point& p) { return box_distance2(n.lo, n.hi, p); }

  int build(int start, int end) {
    const int id = int(nodes_.size());
    nodes_.push_back({});
    Point lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf}, clo = lo, chi = hi;
    for (int q = start; q < end; ++q) {
      const auto& b = boxes_[order_[q]];
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], b[0][k]);
        hi[k] = std::max(hi[k], b[1][k]);
        const double c = 0.5 * (b[0][k] + b[1][k]);
        clo[k] = std::min(clo[k], c);
        chi[k] = std::max(chi[k], c);
      }
    }
    nodes_[id].lo = lo;
    nodes_[id].hi = hi;
    if (end - start <= kLeaf) {
      nodes_[id].start = start;
      nodes_[id].count = end - start;
      return id;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    const int mid = (start + end) / 2;
    std::nth_element(order_.begin() + start, order_.begin() + mid, order_.begin() + end, [&](int a, int b) {
      return boxes_[a][0][axis] + boxes_[a][1][axis] < boxes_[b][0][axis] + boxes_[b][1][axis];
    });
    build(start, mid);
    const int r = build(mid, end);
    nodes_[id].right = r;
    return id;
  }

  std::vector<std::array<Point, 2>> boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

// ---- closest points ---------------------------------------------------------------------------

// Feature of a triangle (a, b, c) holding the closest point.
enum Feature { kFace, kVertexA, kVertexB, kVertexC, kEdgeAB, kEdgeBC, kEdgeCA };

// Closest point of segment [a, b] to p; t its parameter in [0, 1].
Point closest_on_segment(const Point& p, const Point& a, const Point& b, double& t);

// Closest point of triangle (a, b, c) to p, by the Voronoi regions of its vertices, edges and face;
// f receives the feature holding it.
Point closest_on_triangle(const Point& p, const Point& a, const Point& b, const Point& c, Feature& f);

// ---- crossings of lines parallel to x ---------------------------------------------------------

struct Crossing {
  double x;
  int sign;  // +1 entering the solid along +x, -1 leaving
};

// Sign (+1 left, -1 right) of (y0, z0) relative to the directed edge ia -> ib in the (y, z) plane,
// evaluated from the lower vertex index so that both triangles sharing the edge get opposite signs
// of the same number; exact zeros are resolved by perturbing the point by (eps, eps^2). `value`
// receives the edge function itself (for barycentric weights). 0 only for an edge parallel to x.
int edge_side(const std::vector<Point>& P, int ia, int ib, double y0, double z0, double& value);

// Whether the line {y = y0, z = z0} crosses triangle t (of vertices P), and where (out).
bool triangle_crossing(const std::vector<Point>& P, const std::array<int, 3>& t, double y0, double z0, Crossing& out);

// Crossings of the line {y = y0, z = z0} with the triangles tris[0 .. count) of T, sorted by x.
void line_crossings(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T, const int* tris,
                    std::size_t count, double y0, double z0, std::vector<Crossing>& out);

// 2D: whether the line {y = y0} crosses the directed segment a -> b of a counter-clockwise boundary
// (ends with y >= y0 count as above the line), and where (out; leaving along +x when going up).
inline bool segment_crossing(const Point& a, const Point& b, double y0, Crossing& out) {
  const bool ua = a[1] >= y0, ub = b[1] >= y0;
  if (ua == ub) return false;
  out = {a[0] + (y0 - a[1]) * (b[0] - a[0]) / (b[1] - a[1]), ub ? -1 : 1};
  return true;
}

// ---- the section by z = 0 -----------------------------------------------------------------------

// Closed polygons (outer boundaries counter-clockwise, holes clockwise: outside on the right of
// every segment) of the section of the solid bounded by the triangles T over vertices P by the
// plane z = 0 (vertices on the plane count as above it). MeshError if the plane misses the solid or
// the section is not a set of closed curves.
std::vector<std::vector<Point>> cut_by_plane(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T);

}  // namespace turbid::geometry::detail
