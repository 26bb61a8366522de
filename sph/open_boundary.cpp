// Open-boundary conversions; see open_boundary.hpp.
#include "sph/open_boundary.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

#include "sph/config.hpp"

namespace turbid::sph {

OpenBoundaryCounts update_open_boundaries(ParticleStore& s, const FieldIds& ids, const PhysicsParams& p) {
  OpenBoundaryCounts counts;
  if (p.zone_count == 0) return counts;
  const int d = p.dimensions;
  const std::size_t n = s.size();
  Real* x = static_cast<Real*>(s.raw(ids.position));
  std::uint8_t* kind = s.data<std::uint8_t>(ids.kind);
  std::uint8_t* zone = s.data<std::uint8_t>(ids.zone);
  std::uint8_t* material = s.data<std::uint8_t>(ids.material);
  std::vector<std::size_t> spawn;
  std::vector<std::uint8_t> keep(n, 1);
  bool any_removed = false;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t outlet = kNoZone;
    switch (zone_crossing(x + i * std::size_t(d), d, kind[i], zone[i], p, &outlet)) {
      case ZoneCrossing::inflow:
        kind[i] = std::uint8_t(Kind::fluid);
        material[i] = p.zones[zone[i]].material;
        spawn.push_back(i);
        ++counts.inflow;
        break;
      case ZoneCrossing::outflow:
        keep[i] = 0;
        any_removed = true;
        ++counts.outflow;
        break;
      case ZoneCrossing::to_outlet:
        kind[i] = std::uint8_t(Kind::buffer);
        zone[i] = outlet;
        ++counts.to_outlet;
        break;
      case ZoneCrossing::none:
        break;
    }
  }
  if (!spawn.empty()) {
    std::uint32_t next_id = 0;
    const std::uint32_t* id0 = s.data<std::uint32_t>(ids.id);
    for (std::size_t i = 0; i < n; ++i) next_id = std::max(next_id, id0[i] + 1);
    s.resize(n + spawn.size());
    keep.resize(n + spawn.size(), 1);
    for (std::size_t k = 0; k < spawn.size(); ++k) {
      const std::size_t from = spawn[k], to = n + k;
      for (int f = 0; f < s.field_count(); ++f) {
        const std::size_t bytes = s.field_bytes(f);
        auto* base = static_cast<std::byte*>(s.raw(f));
        std::memcpy(base + to * bytes, base + from * bytes, bytes);
      }
      // raw pointers may have moved with the resize
      Real* xs = static_cast<Real*>(s.raw(ids.position));
      std::uint8_t* zones = s.data<std::uint8_t>(ids.zone);
      const std::uint8_t z = zones[from];
      zones[from] = kNoZone;  // the particle that became fluid
      const BufferZone& zone_def = p.zones[z];
      xs[to * std::size_t(d) + std::size_t(zone_def.axis)] -= zone_def.sign * zone_def.thickness;
      s.data<std::uint8_t>(ids.kind)[to] = std::uint8_t(Kind::buffer);
      s.data<std::uint32_t>(ids.id)[to] = next_id++;
    }
  }
  if (any_removed) s.compact(keep.data());
  return counts;
}

}  // namespace turbid::sph
