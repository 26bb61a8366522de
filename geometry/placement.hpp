// Rigid placement of a shape built in its own frame: scale, rotation (about x, then y, then z) and
// translation. Shared by the primitive samplers (primitives.hpp) and the mesh sampler (mesh.hpp) so
// that both use one convention. No physics.
#pragma once
#include "geometry/shapes.hpp"

namespace turbid::geometry {

// scale multiplies the shape's dimensions (a mesh: its coordinates) before sampling, the spacing
// stays dx; then the shape is rotated about x, then y, then z (degrees; p' = Rz Ry Rx p) and
// translated. Normals are rotated.
struct Placement {
  Point translation{0, 0, 0};
  Point rotation_deg{0, 0, 0};
  double scale = 1.0;
};

// The map of a Placement. R = Rz Ry Rx is built once.
class PlacementMap {
 public:
  explicit PlacementMap(const Placement& placement);

  // R v (directions, normals: rotation only).
  Point rotate(const Point& v) const;
  // R p + t: a point already scaled (the primitives scale their dimensions themselves).
  Point move(const Point& p) const;
  // R (scale p) + t: a point in the shape's own, unscaled frame (mesh vertices).
  Point apply(const Point& p) const;
  // R^T v: the inverse of rotate.
  Point rotate_back(const Point& v) const;
  // R^T (p - t): the inverse of move (a placed point back in the shape's scaled frame).
  Point move_back(const Point& p) const;

 private:
  double m_[3][3];  // row-major R
  Point t_;
  double scale_;
};

}  // namespace turbid::geometry
