// Plain, device-copyable parameters of the fluid model for one run (materials, kernel, options).
#pragma once
#include <cstdint>

#include "sph/config.hpp"
#include "sph/eos.hpp"
#include "sph/kernels.hpp"

namespace turbid::sph {

inline constexpr int kMaxMaterials = 8;

enum class Diffusion : std::uint8_t { none, molteni, antuono, fourtakas };
enum class Viscosity : std::uint8_t { artificial, laminar };

// Particle kinds; the kind field is a u8.
enum class Kind : std::uint8_t { fluid = 0, wall = 1, structure = 2, buffer = 3 };

struct MaterialParams {
  TaitEos eos;
  Real sound_speed;        // c0 [m/s]
  Real dynamic_viscosity;  // mu [Pa s]
};

struct PhysicsParams {
  int dimensions = 2;
  KernelKind kernel = KernelKind::wendland_c2;
  Diffusion diffusion = Diffusion::fourtakas;
  Viscosity viscosity = Viscosity::artificial;
  Real diffusion_delta = Real(0.1);
  Real artificial_viscosity = Real(0.01);
  Real smoothing_length = 0;   // h of the initial lattice [m]
  bool uniform_h = true;       // every particle has h == smoothing_length (fast path)
  Real max_smoothing_length = 0;  // largest h present [m]; the neighbour search covers 2 h_max
  Real gravity[3] = {0, 0, 0}; // [m/s^2]
  int material_count = 0;
  int wall_material = 0;       // EOS used for wall particles' pressure
  MaterialParams materials[kMaxMaterials];
};

}  // namespace turbid::sph
