// Point sets sampled from simple shapes: lattices filling boxes, wall layers around boxes and along
// 2D polylines, and the extrusion of such 2D point sets across y into 3D. Points carry no physics; the caller decides what they become.
#pragma once
#include <array>
#include <vector>

namespace turbid::geometry {

using Point = std::array<double, 3>;

struct Aabb {
  Point min{0, 0, 0};
  Point max{0, 0, 0};
};

// The box a lattice of whole cells covers: [min, min + n dx] per axis, n = max(1, round(extent / dx))
// (fill_box's points fill it, container_walls' walls stand outside it). It differs from the stated
// box by up to dx/2 per axis.
Aabb lattice_box(const Aabb& box, double dx, int dims);

// Cell-centred lattice points (spacing dx) inside [min, max] in the first `dims` axes.
std::vector<Point> fill_box(const Aabb& box, double dx, int dims);

// Lattice points of fill_box within `layers` spacings of the box surface (a hollow shell);
// layers <= 0 fills the whole box.
std::vector<Point> box_shell(const Aabb& box, double dx, int dims, int layers);

// `layers` layers of lattice points outside the faces of `box` (a tank), continuing the
// cell-centred lattice of fill_box so that wall and fluid particles are exactly dx apart.
// open[2k] / open[2k+1] leave out the -/+ face of axis k; corners and edges are filled
// when both adjacent faces are closed.
std::vector<Point> container_walls(const Aabb& box, double dx, int dims, int layers,
                                   const std::array<bool, 6>& open);

// 2D: points along a polyline at spacing ~dx, `layers` rows offset by dx to one side
// (side = -1: right of the direction of travel, +1: left), the first row dx/2 from the line.
std::vector<Point> polyline_walls(const std::vector<Point>& vertices, bool closed, double dx, int layers,
                                  int side);

// 3D from a cross-section: every point (a, b, 0) of a set in the vertical x-z plane becomes the
// points (a, y_k, b), y_k = y_min + (k + 1/2) dx for k < max(1, round((y_max - y_min) / dx)): the
// rule of fill_box and container_walls, so that an extruded set and a box or tank with the same y
// extent share one lattice across y.
std::vector<Point> extrude_across_y(const std::vector<Point>& section, double y_min, double y_max, double dx);

}  // namespace turbid::geometry
