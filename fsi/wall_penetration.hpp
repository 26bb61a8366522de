// Fluid behind walls (issue #27 item 9): how many fluid particles sit beyond the surface of a wall
// or structure, and how deep the deepest one is. Each boundary particle b knows its ghost offset
// g_b (twice its depth below the surface, along the normal into the fluid; fsi::Simulation sets it
// when the world is built), so the surface near b passes through x_b + g_b / 2 with normal
// g_b / |g_b|. A fluid particle i is behind a surface when its signed distance to the surface of its
// nearest boundary particle b (within `radius`) is negative,
//   s_i = (x_i - x_b - g_b / 2) . g_b / |g_b| < 0,
// with a tolerance: s < -tolerance. On the lattice the first fluid row stands dx/2 in front of the
// surface (s = +dx/2); fsi::Simulation takes tolerance = dx/4, because a fluid particle resting in
// the hollow between four wall particles of a 3D layer, 0.75 dx from each (close, but it happens
// under an impact), stands sqrt(0.75^2 - 0.5) dx = 0.25 dx above their plane, dx/4 beyond the
// surface, without having gone through anything; deeper than that it is among the wall's layers. Moving
// structures carry their ghost offsets with their rotation (g = R g0). The boundary particles within
// `band` (dx/2) of the nearest distance decide, by the rule of sph::WallConstraintPass, which puts
// such fluid back on the surface: behind some of their surfaces (e the one it is least behind) and
// not in front of a surface that meets e's at a convex edge (e behind that surface's plane). Beside a
// box's side face, behind the plane of its top row, a particle is outside; inside a box standing on
// the floor, above the floor's surface, it is inside (a concave junction). A particle farther than
// `inside` (dx) from every boundary particle is inside no wall (beside a box's corner it may see
// only the plane of the top row, and be below it).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace turbid::fsi {

struct FluidBehindWalls {
  std::size_t count = 0;     // fluid particles behind a wall or structure surface
  double deepest = 0;        // the largest distance behind a surface of those counted [m] (0 when count = 0)
  std::size_t below_walls = 0;       // of count: behind a wall's surface
  std::size_t inside_structures = 0; // of count: behind a structure's surface
};

// The particles as the store holds them (host): positions (d per particle), kinds (sph::Kind), ids,
// body index per particle (nullptr without structures). ghost0[id - first_id] is the ghost offset
// at t = 0 of boundary particle `id` (3 per particle, the world frame at t = 0); rotation[k] the
// current rotation of structure k (row-major 3 x 3; identity for fixed ones).
struct PenetrationInput {
  int dimensions = 2;
  std::size_t size = 0;
  const float* position = nullptr;
  const std::uint8_t* kind = nullptr;
  const std::uint32_t* id = nullptr;
  const std::uint8_t* body = nullptr;
  const std::vector<std::array<float, 3>>* ghost0 = nullptr;
  std::uint32_t first_id = 0;
  std::vector<std::array<double, 9>> rotation;
  double radius = 0;     // search radius for the nearest boundary particle [m] (the kernel support)
  double tolerance = 0;  // counted when more than this behind the surface [m]
  double band = 0;       // boundary particles within the nearest distance + band all decide [m]
  double inside = 0;     // a fluid particle farther than this from its nearest is inside no wall [m] (0: no bound)
};

FluidBehindWalls count_fluid_behind_walls(const PenetrationInput& in);

}  // namespace turbid::fsi
