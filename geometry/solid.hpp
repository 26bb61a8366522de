// Exact signed distance to the solids structures are made of: the primitives of primitives.hpp (box,
// sphere, cylinder) and closed triangle meshes (mesh.hpp), placed with the same convention
// (placement.hpp: scale, rotation about x, then y, then z in degrees, translation). No physics.
//
// signed_distance(p) is the Euclidean distance from p to the surface of the placed solid [m],
// negative inside, positive outside (0 on the surface):
//  box       of extents `size` centred at the origin (2D: the rectangle size[0] x size[1], size[2]
//            ignored): |max(q, 0)| + min(max_k q_k, 0), q_k = |x_k| - size_k / 2 in the box's frame,
//            so beyond an edge or corner it is the distance to that edge or corner;
//  sphere    of `radius` about the origin: |x| - R (2D: a circle);
//  cylinder  of `radius` R and `length` L, axis along z before rotation (z in [-L/2, L/2]):
//            with s = sqrt(x^2 + y^2) - R and a = |z| - L/2, hypot(max(s, 0), max(a, 0)) +
//            min(max(s, a), 0), i.e. beyond the rim the distance to the rim circle (2D: a circle of
//            `radius`, length ignored);
//  mesh      3D: the distance to the nearest triangle of the placed mesh (exact to rounding; a
//            bounding-volume hierarchy over the triangles, built once per Solid), its sign from the
//            winding number of the mesh's inside test (mesh.hpp: signed crossings of the line through
//            p parallel to x, up to p; exact up to rounding of the crossing abscissae, so the sign is
//            right also next to the surface); 2D: the section of the placed mesh by the plane z = 0
//            (closed polygons, as sample_mesh cuts it), the distance to the nearest segment and the
//            sign from the polygons' winding number along the line through p parallel to x.
// In 2D the query's z is ignored (the solid is the planar figure); for the primitives only a
// rotation about z and translation[2] = 0 are allowed in 2D (std::invalid_argument otherwise, as for
// the samplers); for a mesh any placement is, it chooses the section.
//
// Early exit. signed_distance(p, cutoff) returns the same value where |d| < cutoff; where
// |d| >= cutoff it may stop early and return a value v with the sign of d and cutoff <= |v| <= |d|
// (for a mesh: the distance to its bounding box when p is farther than cutoff from it, else
// +-cutoff). Primitives always answer exactly. So "d < t" for any t < cutoff is decided exactly.
//
// Cost (mesh, Release, one thread): building is O(triangles log triangles) (a 20k-triangle sphere:
// ~20 ms); a query inside the mesh's bounding box is a winding-number test over the triangles of one
// (y, z) grid cell plus a nearest-triangle search, about 1 us (1e6 queries over the bounding box of
// that sphere with a cut-off of R / 12.5: 1 s); outside the bounding box farther than the cut-off, a
// box test. Queries are const and may run from several threads.
#pragma once
#include <memory>
#include <utility>

#include "geometry/mesh.hpp"
#include "geometry/placement.hpp"
#include "geometry/shapes.hpp"

namespace turbid::geometry {

class Solid {
 public:
  // Bad dimensions (not positive and finite), dims not 2 or 3, scale not positive or a 2D placement
  // other than a rotation about z are std::invalid_argument.
  static Solid box(Point size, int dims, const Placement& placement = {});
  static Solid sphere(double radius, int dims, const Placement& placement = {});
  static Solid cylinder(double radius, double length, int dims, const Placement& placement = {});
  // The mesh is validated (validate_mesh: MeshError for an open, non-manifold, misoriented,
  // inside-out or flat mesh); in 2D a plane z = 0 that misses the placed mesh is a MeshError.
  static Solid mesh(const TriangleMesh& mesh, int dims, const Placement& placement = {});

  // Signed distance [m], negative inside (see above).
  double signed_distance(const Point& p) const;
  // The same where |d| < cutoff; otherwise possibly an early answer with the right sign and
  // cutoff <= |value| <= |d| (see above).
  double signed_distance(const Point& p, double cutoff) const;

  // Axis-aligned box holding the placed solid (2D: z from 0 to 0).
  const Aabb& bounds() const;
  int dims() const;

  class Shape;  // implementation (solid.cpp)

 private:
  explicit Solid(std::shared_ptr<const Shape> shape) : shape_(std::move(shape)) {}
  std::shared_ptr<const Shape> shape_;  // immutable, shared by copies
};

}  // namespace turbid::geometry
