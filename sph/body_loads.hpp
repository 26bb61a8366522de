// Per-structure sums of the forces the fluid puts on structure particles (StructureForcePass):
// total force and torque about each structure's reference point. Host code, in double precision;
// a backend calls it on host copies of position, structure_force and body.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "sph/physics_params.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

struct BodyLoad {
  std::array<double, 3> force{0, 0, 0};   // [N] (N/m in 2D)
  std::array<double, 3> torque{0, 0, 0};  // about the reference point [N m] (N m/m in 2D: z only)
};

// reference[k]: the point torques of body k are taken about.
template <int D>
std::vector<BodyLoad> sum_body_loads(const Vec<D>* position, const Vec<D>* force, const std::uint8_t* body,
                                     std::size_t count, const std::vector<std::array<double, 3>>& reference) {
  std::vector<BodyLoad> out(reference.size());
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t k = body[i];
    if (k >= out.size()) continue;  // kNoBody
    double f[3] = {0, 0, 0}, r[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a) {
      f[a] = force[i][a];
      r[a] = double(position[i][a]) - reference[k][a];
    }
    BodyLoad& L = out[k];
    for (int a = 0; a < 3; ++a) L.force[a] += f[a];
    L.torque[0] += r[1] * f[2] - r[2] * f[1];
    L.torque[1] += r[2] * f[0] - r[0] * f[2];
    L.torque[2] += r[0] * f[1] - r[1] * f[0];
  }
  return out;
}

}  // namespace turbid::sph
