// Particles crossing the planes of open-boundary buffer zones (see BufferZone), on the host:
//  - an inlet buffer particle that has moved past its zone's plane into the fluid becomes fluid,
//    and a new buffer particle takes its place one zone thickness upstream (the count grows);
//  - a fluid particle that has moved past an outlet zone's plane becomes a buffer particle of it;
//  - an outlet buffer particle that has left its zone downstream is removed.
// Particles are visited in index order and new ones appended in that order, so the outcome is
// deterministic. Backends call this after the drift, before the sort.
#pragma once
#include <cstddef>

#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

struct OpenBoundaryCounts {
  std::size_t inflow = 0;   // buffer particles that became fluid (and as many new buffer particles)
  std::size_t to_outlet = 0;  // fluid particles that entered an outlet zone
  std::size_t outflow = 0;  // buffer particles removed past an outlet
};

OpenBoundaryCounts update_open_boundaries(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params);

}  // namespace turbid::sph
