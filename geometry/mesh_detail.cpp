// Internals shared by the mesh sampler and the mesh solids; see mesh_detail.hpp.
#include "geometry/mesh_detail.hpp"

#include <unordered_map>

#include "geometry/mesh.hpp"

namespace turbid::geometry::detail {

Aabb bounds(const std::vector<Point>& pts) {
  Aabb b{{kInf, kInf, kInf}, {-kInf, -kInf, -kInf}};
  for (const auto& p : pts)
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], p[k]);
      b.max[k] = std::max(b.max[k], p[k]);
    }
  return b;
}

// ---- closest points ---------------------------------------------------------------------------

Point closest_on_segment(const Point& p, const Point& a, const Point& b, double& t) {
  const Point ab = sub(b, a);
  const double l2 = dot(ab, ab);
  t = l2 > 0 ? std::clamp(dot(sub(p, a), ab) / l2, 0.0, 1.0) : 0.0;
  return add(a, mul(ab, t));
}

// Closest point of triangle (a, b, c) to p, by the Voronoi regions of its vertices, edges and face.
Point closest_on_triangle(const Point& p, const Point& a, const Point& b, const Point& c, Feature& f) {
  const Point ab = sub(b, a), ac = sub(c, a), ap = sub(p, a);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    f = kVertexA;
    return a;
  }
  const Point bp = sub(p, b);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    f = kVertexB;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    f = kEdgeAB;
    return add(a, mul(ab, d1 / (d1 - d3)));
  }
  const Point cp = sub(p, c);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    f = kVertexC;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    f = kEdgeCA;
    return add(a, mul(ac, d2 / (d2 - d6)));
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    f = kEdgeBC;
    return add(b, mul(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
  }
  const double denom = va + vb + vc;
  if (denom > 0) {
    f = kFace;
    return add(a, add(mul(ab, vb / denom), mul(ac, vc / denom)));
  }
  // Degenerate (zero-area) triangle: the nearest of its edges.
  double t;
  Point best = closest_on_segment(p, a, b, t);
  f = kEdgeAB;
  const Point q1 = closest_on_segment(p, b, c, t), q2 = closest_on_segment(p, c, a, t);
  if (dot(sub(q1, p), sub(q1, p)) < dot(sub(best, p), sub(best, p))) {
    best = q1;
    f = kEdgeBC;
  }
  if (dot(sub(q2, p), sub(q2, p)) < dot(sub(best, p), sub(best, p))) {
    best = q2;
    f = kEdgeCA;
  }
  return best;
}

// ---- crossings of lines parallel to x ---------------------------------------------------------

int edge_side(const std::vector<Point>& P, int ia, int ib, double y0, double z0, double& value) {
  const bool flip = ia > ib;
  const Point& a = P[flip ? ib : ia];
  const Point& b = P[flip ? ia : ib];
  const double uy = b[1] - a[1], uz = b[2] - a[2];
  double e = uy * (z0 - a[2]) - uz * (y0 - a[1]);
  int s = e > 0 ? 1 : (e < 0 ? -1 : (uz != 0 ? (uz > 0 ? -1 : 1) : (uy > 0 ? 1 : (uy < 0 ? -1 : 0))));
  if (flip) {
    e = -e;
    s = -s;
  }
  value = e;
  return s;
}

bool triangle_crossing(const std::vector<Point>& P, const std::array<int, 3>& t, double y0, double z0, Crossing& out) {
  double wc, wa, wb;  // edge functions opposite c, a, b
  const int s0 = edge_side(P, t[0], t[1], y0, z0, wc);
  if (s0 == 0) return false;
  const int s1 = edge_side(P, t[1], t[2], y0, z0, wa);
  if (s1 != s0) return false;
  const int s2 = edge_side(P, t[2], t[0], y0, z0, wb);
  if (s2 != s0) return false;
  const double sum = wa + wb + wc;
  double x;
  if (sum != 0) {
    x = (wa * P[t[0]][0] + wb * P[t[1]][0] + wc * P[t[2]][0]) / sum;
  } else {
    x = (P[t[0]][0] + P[t[1]][0] + P[t[2]][0]) / 3.0;  // not reached for a non-degenerate projection
  }
  // All edges to the left: counter-clockwise in (y, z), normal with +x component: leaving.
  out = {x, s0 > 0 ? -1 : 1};
  return true;
}

void line_crossings(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T, const int* tris,
                    std::size_t count, double y0, double z0, std::vector<Crossing>& out) {
  out.clear();
  Crossing c;
  for (std::size_t q = 0; q < count; ++q)
    if (triangle_crossing(P, T[tris[q]], y0, z0, c)) out.push_back(c);
  std::sort(out.begin(), out.end(), [](const Crossing& a, const Crossing& b) { return a.x < b.x; });
}

// ---- the section by z = 0 -----------------------------------------------------------------------

// Closed polygons (outer boundaries counter-clockwise) of the section of the mesh by z = 0.
std::vector<std::vector<Point>> cut_by_plane(const std::vector<Point>& P, const std::vector<std::array<int, 3>>& T) {
  auto above = [&](int v) { return P[v][2] >= 0; };
  std::unordered_map<std::uint64_t, int> point_of_edge;
  std::vector<Point> pts;
  auto crossing = [&](int a, int b) {
    const std::uint64_t key = edge_key(a, b);
    const auto it = point_of_edge.find(key);
    if (it != point_of_edge.end()) return it->second;
    const Point& p = P[std::min(a, b)];
    const Point& q = P[std::max(a, b)];
    const double t = p[2] / (p[2] - q[2]);
    const int id = int(pts.size());
    pts.push_back({p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]), 0.0});
    point_of_edge.emplace(key, id);
    return id;
  };
  std::vector<int> next;  // next[point] = following point along the section
  std::size_t segments = 0;
  for (const auto& t : T) {
    const bool s[3] = {above(t[0]), above(t[1]), above(t[2])};
    if (s[0] == s[1] && s[1] == s[2]) continue;
    // The vertex alone on its side, and its neighbours in the triangle's order.
    const int lone = s[0] != s[1] && s[0] != s[2] ? 0 : (s[1] != s[0] && s[1] != s[2] ? 1 : 2);
    const int L = t[lone], N = t[(lone + 1) % 3], Pv = t[(lone + 2) % 3];
    const int c_next = crossing(L, N), c_prev = crossing(Pv, L);
    // Direction ez x n (outside on the right): from the edge leaving an upper lone vertex to the
    // edge entering it; reversed for a lower one.
    const int from = s[lone] ? c_next : c_prev, to = s[lone] ? c_prev : c_next;
    if (next.size() < pts.size()) next.resize(pts.size(), -1);
    if (next[from] >= 0) throw MeshError("The section of the mesh by the plane z = 0 is not a set of closed curves.");
    next[from] = to;
    ++segments;
  }
  if (segments == 0) throw MeshError("The plane z = 0 does not cut the mesh: its section there is empty.");
  next.resize(pts.size(), -1);
  std::vector<std::vector<Point>> loops;
  std::vector<char> used(pts.size(), 0);
  for (std::size_t s0 = 0; s0 < pts.size(); ++s0) {
    if (used[s0] || next[s0] < 0) continue;
    std::vector<Point> loop;
    int p = int(s0);
    while (!used[p]) {
      used[p] = 1;
      // Coincident consecutive points (the plane through a vertex) are kept once.
      if (loop.empty() || pts[p] != loop.back()) loop.push_back(pts[p]);
      p = next[p];
      if (p < 0) throw MeshError("The section of the mesh by the plane z = 0 is not a set of closed curves.");
    }
    if (p != int(s0)) throw MeshError("The section of the mesh by the plane z = 0 is not a set of closed curves.");
    while (loop.size() > 1 && loop.back() == loop.front()) loop.pop_back();
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  if (loops.empty()) throw MeshError("The plane z = 0 does not cut the mesh: its section there has no area.");
  return loops;
}

}  // namespace turbid::geometry::detail
