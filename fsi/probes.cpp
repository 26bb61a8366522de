// Probe evaluation; see probes.hpp. Runs on the host after the backend synchronised the store.
#include "fsi/probes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sph/dispatch.hpp"
#include "sph/vec.hpp"

namespace turbid::fsi {
namespace {

template <int D>
double evaluate(const Scene& scene, const ProbeSpec& probe, const sph::ParticleStore& s, const sph::FieldIds& ids,
                const sph::PhysicsParams& params) {
  using sph::Real;
  using V = sph::Vec<D>;
  const std::size_t n = s.size();
  const V* x = s.data<V>(ids.position);
  const V* v = s.data<V>(ids.velocity);
  const Real* rho = s.data<Real>(ids.density);
  const Real* p = s.data<Real>(ids.pressure);
  const Real* m = s.data<Real>(ids.mass);
  const std::uint8_t* mat = s.data<std::uint8_t>(ids.material);
  const std::uint8_t* kind = s.data<std::uint8_t>(ids.kind);
  auto fluid = [&](std::size_t i) { return kind[i] == std::uint8_t(sph::Kind::fluid); };

  switch (probe.type) {
    case ProbeSpec::Type::front_position: {
      const int want = probe.material.empty() ? -1 : material_index(scene, probe.material);
      double best = -std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < n; ++i)
        if (fluid(i) && (want < 0 || mat[i] == want)) best = std::max(best, double(x[i][probe.axis]));
      return std::isfinite(best) ? best : std::nan("");
    }
    case ProbeSpec::Type::pressure: {
      // Shepard interpolation of fluid pressure: sum p_j W V_j / sum W V_j.
      double num = 0, den = 0;
      const double h = params.smoothing_length;
      V at;
      for (int k = 0; k < D; ++k) at[k] = Real(probe.point[k]);
      sph::dispatch_kernel<D>(params, [&](auto kernel_tag, auto) {
        using K = typename decltype(kernel_tag)::type;
        for (std::size_t i = 0; i < n; ++i) {
          if (!fluid(i)) continue;
          const double r = std::sqrt(double(sph::norm2(x[i] - at)));
          if (r >= 2 * h) continue;
          const double w = K::w(Real(r), Real(h)) * double(m[i]) / double(rho[i]);
          num += w * p[i];
          den += w;
        }
      });
      // No reading where too little fluid is near the point (a dry sensor, one stray particle).
      return den > 0 && den >= probe.min_kernel_sum ? num / den : std::nan("");
    }
    case ProbeSpec::Type::max_speed: {
      double v2 = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (fluid(i)) v2 = std::max(v2, double(sph::norm2(v[i])));
      return std::sqrt(v2);
    }
    case ProbeSpec::Type::kinetic_energy: {
      double e = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (fluid(i)) e += 0.5 * double(m[i]) * double(sph::norm2(v[i]));
      return e;
    }
    case ProbeSpec::Type::fluid_particles: {
      std::size_t c = 0;
      for (std::size_t i = 0; i < n; ++i) c += fluid(i) ? 1 : 0;
      return double(c);
    }
    case ProbeSpec::Type::surface_elevation: {
      // Particles count for the station when their horizontal distance to it is below dx. A
      // narrower band could miss every column (in 3D a disc must reach dx/sqrt(2) to hold a point of
      // a square lattice however the station falls, and disordered particles wander by a fraction
      // of dx); the kernel support 2h would average the surface over 4 dx and blunt a steep wave.
      // Over dx the reading is off by at most the surface slope times dx.
      // The value is the highest such particle's centre plus dx/2: a particle stands for a cell of
      // height dx, so a block filled to height H (top row at H - dx/2) reads H at rest.
      const int want = probe.material.empty() ? -1 : material_index(scene, probe.material);
      const int up = probe.axis;
      const double dx = scene.particle_spacing;
      double best = -std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < n; ++i) {
        if (!fluid(i) || (want >= 0 && mat[i] != want)) continue;
        double r2 = 0;
        for (int k = 0; k < D; ++k)
          if (k != up) r2 += (double(x[i][k]) - probe.point[k]) * (double(x[i][k]) - probe.point[k]);
        if (r2 < dx * dx) best = std::max(best, double(x[i][up]));
      }
      return std::isfinite(best) ? best + 0.5 * dx : std::nan("");  // no fluid at the station: NaN
    }
    case ProbeSpec::Type::material_mass: {
      // Splitting moves mass from one material to another: with transitions the sum over the
      // materials involved is what stays constant.
      const int want = material_index(scene, probe.material);
      double total = 0;
      for (std::size_t i = 0; i < n; ++i)
        if (fluid(i) && mat[i] == want) total += double(m[i]);
      return total;
    }
  }
  return std::nan("");
}

}  // namespace

const char* probe_unit(ProbeSpec::Type t) {
  switch (t) {
    case ProbeSpec::Type::front_position: return "m";
    case ProbeSpec::Type::pressure: return "Pa";
    case ProbeSpec::Type::max_speed: return "m/s";
    case ProbeSpec::Type::kinetic_energy: return "J";
    case ProbeSpec::Type::fluid_particles: return "1";
    case ProbeSpec::Type::surface_elevation: return "m";
    case ProbeSpec::Type::material_mass: return "kg";
  }
  return "";
}

std::vector<double> evaluate_probes(const Scene& scene, const sph::ParticleStore& store, const sph::FieldIds& ids,
                                    const sph::PhysicsParams& params) {
  std::vector<double> out;
  out.reserve(scene.probes.size());
  for (const auto& probe : scene.probes)
    out.push_back(scene.dimensions == 2 ? evaluate<2>(scene, probe, store, ids, params)
                                        : evaluate<3>(scene, probe, store, ids, params));
  return out;
}

}  // namespace turbid::fsi
