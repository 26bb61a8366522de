// Particles crossing the planes of open-boundary buffer zones (see BufferZone), on the host:
//  - an inlet buffer particle that has moved past its zone's plane into the fluid becomes fluid,
//    and a new buffer particle takes its place one zone thickness upstream (the count grows);
//  - a fluid particle that has moved past an outlet zone's plane becomes a buffer particle of it;
//  - an outlet buffer particle that has left its zone downstream is removed.
// Particles are visited in index order and new ones appended in that order, so the outcome is
// deterministic. Backends call this after the drift, before the sort. The decision for one
// particle (zone_crossing) is shared: the CPU applies it in update_open_boundaries, the device
// backend in a pass followed by a scan and a compaction on the device.
#pragma once
#include <cstddef>
#include <cstdint>

#include "sph/config.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

struct OpenBoundaryCounts {
  std::size_t inflow = 0;   // buffer particles that became fluid (and as many new buffer particles)
  std::size_t to_outlet = 0;  // fluid particles that entered an outlet zone
  std::size_t outflow = 0;  // buffer particles removed past an outlet
};

enum class ZoneCrossing : std::uint8_t {
  none,
  inflow,     // an inlet buffer particle past its plane: becomes fluid of the zone's material, and a
              // copy one zone thickness upstream becomes the new buffer particle
  outflow,    // an outlet buffer particle past the zone's far face: removed
  to_outlet,  // a fluid particle past an outlet's plane inside its cross-section: a buffer particle of it
};

// What happens to a particle at coordinates x (d of them) of this kind and zone; for to_outlet,
// *outlet is the zone it enters (the first in the scene's order).
TURBID_HD inline ZoneCrossing zone_crossing(const Real* x, int d, std::uint8_t kind, std::uint8_t zone,
                                            const PhysicsParams& p, std::uint8_t* outlet) {
  // Beyond the plane along the flow: (x_axis - plane) * sign > 0.
  auto past = [&](const BufferZone& z, Real plane) { return (x[z.axis] - plane) * z.sign > Real(0); };
  if (kind == std::uint8_t(Kind::buffer)) {
    const BufferZone& z = p.zones[zone];
    if (z.type == ZoneType::inlet && past(z, z.plane)) return ZoneCrossing::inflow;
    if (z.type == ZoneType::outlet && past(z, z.plane + z.sign * z.thickness)) return ZoneCrossing::outflow;
  } else if (kind == std::uint8_t(Kind::fluid)) {
    for (int k = 0; k < p.zone_count; ++k) {
      const BufferZone& z = p.zones[k];
      if (z.type != ZoneType::outlet || !past(z, z.plane)) continue;
      bool inside = true;  // the zone's cross-section
      for (int a = 0; a < d; ++a)
        if (a != z.axis && (x[a] < z.lo[a] || x[a] > z.hi[a])) inside = false;
      if (!inside) continue;
      *outlet = std::uint8_t(k);
      return ZoneCrossing::to_outlet;
    }
  }
  return ZoneCrossing::none;
}

OpenBoundaryCounts update_open_boundaries(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params);

}  // namespace turbid::sph
