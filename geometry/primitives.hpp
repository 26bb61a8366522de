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
// Depth. A particle's depth is its exact distance to the primitive's surface: sphere/circle
// R - |p| = (k + 0.5) h, box the distance to the nearest face, cylinder the nearer of side and cap.
// Where faces tie (box corners and edges on a cubic lattice, the rim of a cylinder where side and
// cap are equally near) the normal is the direction to the shared edge/corner point (the sum of the
// tied faces' normals, each scaled by its distance) and depth is the distance to that point, so that
// x + depth * normal is on the surface in every case (the ghost node is the point reflection through
// the edge/corner).
// Bodies smaller than about one spacing are still sampled (one shell) but cannot keep the
// particles dx/2 apart.
#pragma once
#include <vector>

#include "geometry/placement.hpp"
#include "geometry/shapes.hpp"

namespace turbid::geometry {

// A structure sampled into boundary particles (primitives here, meshes in mesh.hpp). For every
// particle, x + depth * normal is a point of the body's surface (exactly for the primitives, to
// rounding; for meshes the nearest point of the mesh), so the modified dynamic boundary condition can
// mirror it to the ghost node x + 2 depth normal.
struct SampledBody {
  std::vector<Point> points;    // particle positions
  std::vector<Point> normals;   // outward unit normal of the nearest surface for each point
  std::vector<double> volumes;  // volume (area in 2D) each particle stands for [m^3] / [m^2]
  std::vector<int> layer;       // 0 = surface layer, 1, 2, ... inward
  std::vector<double> depth;    // distance below the surface along the normal [m]: to the nearest
                                // surface point, or to the edge/corner where two or three faces
                                // tie (then the normal points at that edge/corner), see above
  std::vector<double> surface_share;  // surface area each particle stands for [m^2] (length in 2D);
                                      // 0 except in layer 0, sums to surface_area
  double surface_area = 0;      // sum over layer-0 particles of their surface share [m^2] (perimeter [m] in 2D)
  double volume = 0;            // primitives: sum of volumes [m^3] (area in 2D), i.e. of the sampled
                                // layers; meshes: the volume of the whole solid (see mesh.hpp)
};

// Rigid placement of a primitive built about its own centre (the origin): see placement.hpp
// (scale, then rotation about x, y, z in degrees, then translation; normals are rotated). In 2D only
// the rotation about z is allowed and translation[2] must be 0 (std::invalid_argument otherwise).

// Box of extents `size` centred at the origin ([-size/2, size/2]; size[2] ignored in 2D): a
// cell-centred lattice with spacing size_k / round(size_k / dx) per axis. A particle's layer is its
// cell count to the nearest face; its normal is that face's normal (pointing at the shared edge/corner
// where faces tie, e.g. at corners of a cubic lattice; depth is then the distance to that point).
// layers <= 0 (or more layers than fit) fills the whole solid. dims is 2 or 3.
SampledBody sample_box(Point size, double dx, int layers, int dims, const Placement& placement = {});

// Sphere of `radius` about the origin: concentric shells, a spherical Fibonacci lattice of
// N_k = round(4 pi r_k^2 / h^2) points on each. dims 2: a circle, rings of N_k = round(2 pi r_k / h).
SampledBody sample_sphere(double radius, double dx, int layers, int dims, const Placement& placement = {});

// Cylinder of `radius` and `length`, axis along z, centred at the origin (z in [-L/2, L/2]):
// slices of height h_z = L / round(L / dx), each holding concentric rings at radii
// r_i = R - (i + 0.5) h_r. A particle's layer is min(ring index, slice count to the nearer cap),
// its normal that of the nearer of side and cap (pointing at the rim where they tie).
// dims 2: a circle of `radius` (length ignored), as sample_sphere.
SampledBody sample_cylinder(double radius, double length, double dx, int layers, int dims,
                            const Placement& placement = {});

}  // namespace turbid::geometry
