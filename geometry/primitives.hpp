// Layered particle sampling of solid primitives (box, sphere/circle, cylinder) for structures:
// positions, outward normals of the nearest surface, the volume each particle stands for, and
// the layer (0 = at the surface, increasing inward). No physics.
//
// Layout. Every primitive is cut into shells of thickness h parallel to its surface; particles of
// shell k sit at depth (k + 0.5) h below the surface, spaced ~h along it. h is dx adjusted so that
// a whole number of shells (cells) fits: h = extent / n, n = max(1, round(extent / dx)), hence
// h lies within [dx/1.5, 1.5 dx] for n >= 1 (and is dx exactly when extent is a multiple of dx).
// Each shell is split into N cells of equal measure, N from the shell's mid-surface area / h^2
// (length / h in 2D); each particle's volume is its cell's exact measure, so the volumes sum to the
// analytic volume of the sampled layer region (up to rounding):
//   box:      v = s_x s_y s_z (s_k = size_k / n_k; s_x s_y in 2D)
//   sphere:   v = [4/3 pi (r_o^3 - r_i^3)] / N_k = (4 pi r_k^2 + pi h^2 / 3) h / N_k,
//             r_o = R - k h, r_i = r_o - h, r_k = r_o - h/2 (mean shell area share x thickness)
//   circle:   v = pi (r_o^2 - r_i^2) / N_k = 2 pi r_k h / N_k
//   cylinder: v = pi (r_o^2 - r_i^2) h_z / N_i (annulus of ring i times the slice height h_z)
// The surface share of a surface-layer particle is likewise its exact patch of the surface
// (box: the faces of its cell on the box surface; sphere: 4 pi R^2 / N_0; circle: 2 pi R / N_0;
// cylinder: 2 pi R h_z / N_0 on the side plus the annulus pi (r_o^2 - r_i^2) / N_i on a cap), so
// surface_area is the analytic area of the primitive. What remains a sampling error is where the
// particles sit (moments such as sum v |p - c|^2 converge as O(h^2); see the unit tests).
// Bodies smaller than about one spacing are still sampled (one shell) but cannot keep the
// particles dx/2 apart.
#pragma once
#include <vector>

#include "geometry/shapes.hpp"

namespace turbid::geometry {

struct SampledBody {
  std::vector<Point> points;    // particle positions
  std::vector<Point> normals;   // outward unit normal of the nearest surface for each point
  std::vector<double> volumes;  // volume (area in 2D) each particle stands for [m^3] / [m^2]
  std::vector<int> layer;       // 0 = surface layer, 1, 2, ... inward
  double surface_area = 0;      // sum over layer-0 particles of their surface share [m^2] (perimeter [m] in 2D)
  double volume = 0;            // sum of volumes [m^3] (area in 2D)
};

// Rigid placement of a primitive built about its own centre (the origin). scale multiplies the
// primitive's dimensions before sampling (the spacing stays dx); then the points are rotated about
// x, then y, then z (degrees; p' = Rz Ry Rx p) and translated. Normals are rotated. In 2D only the
// rotation about z is allowed and translation[2] must be 0 (std::invalid_argument otherwise).
struct Placement {
  Point translation{0, 0, 0};
  Point rotation_deg{0, 0, 0};
  double scale = 1.0;
};

// Box of extents `size` centred at the origin ([-size/2, size/2]; size[2] ignored in 2D): a
// cell-centred lattice with spacing size_k / round(size_k / dx) per axis. A particle's layer is its
// cell count to the nearest face; its normal is that face's normal (normalised sum of the normals
// where faces tie, e.g. at corners of a cubic lattice).
// layers <= 0 (or more layers than fit) fills the whole solid. dims is 2 or 3.
SampledBody sample_box(Point size, double dx, int layers, int dims, const Placement& placement = {});

// Sphere of `radius` about the origin: concentric shells, a spherical Fibonacci lattice of
// N_k = round(4 pi r_k^2 / h^2) points on each. dims 2: a circle, rings of N_k = round(2 pi r_k / h).
SampledBody sample_sphere(double radius, double dx, int layers, int dims, const Placement& placement = {});

// Cylinder of `radius` and `length`, axis along z, centred at the origin (z in [-L/2, L/2]):
// slices of height h_z = L / round(L / dx), each holding concentric rings at radii
// r_i = R - (i + 0.5) h_r. A particle's layer is min(ring index, slice count to the nearer cap),
// its normal that of the nearer of side and cap (normalised sum where they tie).
// dims 2: a circle of `radius` (length ignored), as sample_sphere.
SampledBody sample_cylinder(double radius, double length, double dx, int layers, int dims,
                            const Placement& placement = {});

}  // namespace turbid::geometry
