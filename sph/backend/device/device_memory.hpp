// What the device backend (device_backend.inl) holds in device memory per particle of capacity,
// by purpose: the store's fields, the sort (keys, order, the gather's scratch as wide as the widest
// field, and Thrust's sort buffers from the caching allocator), and what only some scenes use.
// Plain C++ (no Thrust), so that `turbid check` reports it for a scene without a device; the
// backend reports what it actually holds (Backend::device_bytes), and a test compares the two.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

struct DeviceMemory {
  std::size_t fields = 0;           // the registered fields (ParticleStore::bytes_per_particle)
  std::size_t sort = 0;             // keys and order (8), the gather scratch, Thrust's sort buffers (about 10)
  std::size_t splitting = 0;        // with transitions: slots, rule, first slot, relaxation zone and shift
  std::size_t open_boundaries = 0;  // with buffer zones: each particle's crossing
  std::size_t structures = 0;       // with structures: the list the loads are summed over
  std::size_t total() const { return fields + sort + splitting + open_boundaries + structures; }
};

inline DeviceMemory device_memory_per_particle(const ParticleStore& s, const PhysicsParams& p, bool transitions) {
  DeviceMemory m;
  m.fields = s.bytes_per_particle();
  std::size_t widest = 1;
  for (int f = 0; f < s.field_count(); ++f) widest = std::max(widest, s.field_bytes(FieldId(f)));
  // Thrust's stable sort by key of 32-bit keys and values keeps a second copy of each (8 bytes),
  // which the caching allocator rounds up by a quarter.
  m.sort = 2 * sizeof(std::uint32_t) + widest + 10;
  if (transitions) m.splitting = sizeof(std::uint32_t) + sizeof(std::int8_t) + sizeof(std::uint64_t) + 1 + std::size_t(p.dimensions) * sizeof(Real);
  if (p.zone_count > 0) m.open_boundaries = 1;
  if (p.body_count > 0) m.structures = sizeof(std::uint32_t);
  return m;
}

}  // namespace turbid::sph
