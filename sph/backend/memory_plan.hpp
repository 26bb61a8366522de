// What each backend holds per particle of capacity, by purpose, for `turbid check` (which prints
// both plans for a scene before it runs) and for the backends themselves (the CPU's neighbour
// list width is decided here). Plain C++, no backend headers.
//  - CPU backend (backend/cpu/cpu_backend.cpp): the store's fields, the sort (keys, order, the
//    store's permutation scratch as wide as its widest field, the coordinate arrays of the
//    vectorised distance checks), the neighbour list (the largest share in 3D), and what only some
//    scenes use.
//  - Device backend (backend/device/device_backend.inl): the fields, the sort (keys, order, the
//    gather's scratch as wide as the widest field, Thrust's sort buffers from the caching
//    allocator), and what only some scenes use; the backend reports what it actually holds
//    (Backend::device_bytes), and a test compares the two.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

// Entries per particle of the CPU's neighbour list: 1.5 x the lattice particles in the support
// sphere (circle in 2D) of radius 2 h_max, rounded up to 8; `spacing`: the initial lattice's [m].
inline std::uint32_t neighbour_list_stride(const PhysicsParams& p, double spacing) {
  const double r = 2.0 * p.max_smoothing_length / spacing;
  const double inside = p.dimensions == 2 ? 3.14159265 * r * r : 4.18879 * r * r * r;
  return (std::uint32_t(1.5 * inside) + 15u) & ~7u;
}

// The widest field of the store (the sort's scratch is that wide) [bytes].
inline std::size_t widest_field_bytes(const ParticleStore& s) {
  std::size_t widest = 1;
  for (int f = 0; f < s.field_count(); ++f) widest = std::max(widest, s.field_bytes(FieldId(f)));
  return widest;
}

// With transitions, on either backend: new slots, rule, first slot, relaxation zone and shift.
inline std::size_t splitting_bytes(const PhysicsParams& p) {
  return sizeof(std::uint32_t) + sizeof(std::int8_t) + sizeof(std::uint64_t) + 1 + std::size_t(p.dimensions) * sizeof(Real);
}

// With implicit viscosity, on either backend: the conjugate-gradient vectors (and the full
// stress's tensors and carrier viscosity), sph/implicit_viscosity_solve.hpp's ViscousWork.
inline std::size_t implicit_viscosity_bytes(const PhysicsParams& p) {
  if (!p.implicit_viscosity) return 0;
  const std::size_t d = std::size_t(p.dimensions);
  std::size_t b = 8 * d * sizeof(Real);
  if (p.full_stress) b += 3 * d * d * sizeof(Real) + sizeof(Real);
  return b;
}

struct CpuMemory {
  std::size_t fields = 0;          // the registered fields (ParticleStore::bytes_per_particle)
  std::size_t sort = 0;            // keys, order, permutation scratch, coordinate arrays
  std::size_t neighbour_list = 0;  // stride entries and a count, 4 bytes each
  std::size_t splitting = 0;       // with transitions
  std::size_t implicit = 0;        // with implicit viscosity: the conjugate-gradient vectors (and the full stress's tensors)
  std::size_t total() const { return fields + sort + neighbour_list + splitting + implicit; }
};

inline CpuMemory cpu_memory_per_particle(const ParticleStore& s, const PhysicsParams& p, double spacing, bool transitions) {
  CpuMemory m;
  const std::size_t d = std::size_t(p.dimensions);
  m.fields = s.bytes_per_particle();
  m.sort = 2 * sizeof(std::uint32_t) + widest_field_bytes(s) + d * sizeof(Real);
  m.neighbour_list = (std::size_t(neighbour_list_stride(p, spacing)) + 1) * sizeof(std::uint32_t);
  if (transitions) m.splitting = splitting_bytes(p);
  m.implicit = implicit_viscosity_bytes(p);
  return m;
}

struct DeviceMemory {
  std::size_t fields = 0;           // the registered fields (ParticleStore::bytes_per_particle)
  std::size_t sort = 0;             // keys and order (8), the gather scratch, Thrust's sort buffers (about 10)
  std::size_t splitting = 0;        // with transitions
  std::size_t open_boundaries = 0;  // with buffer zones: each particle's crossing
  std::size_t structures = 0;       // with structures: the list the loads are summed over
  std::size_t implicit = 0;         // with implicit viscosity: as on the CPU
  std::size_t total() const { return fields + sort + splitting + open_boundaries + structures + implicit; }
};

inline DeviceMemory device_memory_per_particle(const ParticleStore& s, const PhysicsParams& p, bool transitions) {
  DeviceMemory m;
  m.fields = s.bytes_per_particle();
  // Thrust's stable sort by key of 32-bit keys and values keeps a second copy of each (8 bytes),
  // which the caching allocator rounds up by a quarter.
  m.sort = 2 * sizeof(std::uint32_t) + widest_field_bytes(s) + 10;
  if (transitions) m.splitting = splitting_bytes(p);
  if (p.zone_count > 0) m.open_boundaries = 1;
  if (p.body_count > 0) m.structures = sizeof(std::uint32_t);
  m.implicit = implicit_viscosity_bytes(p);
  return m;
}

}  // namespace turbid::sph
