// Probe evaluation; see probes.hpp. Runs on the host after the backend synchronised the store.
#include "fsi/probes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "sph/dispatch.hpp"
#include "sph/vec.hpp"

namespace turbid::fsi {
namespace {

// A sensor face's frame: the unit normal n and, in the face, the unit vectors a (and b in 3D);
// in 2D a = (-n_y, n_x).
struct FaceFrame {
  std::array<double, 3> n{0, 0, 0}, a{0, 0, 0}, b{0, 0, 0};
};

template <int D>
FaceFrame face_frame(std::array<double, 3> normal) {
  double len = 0;
  for (int k = 0; k < D; ++k) len += normal[std::size_t(k)] * normal[std::size_t(k)];
  len = std::sqrt(len);
  for (int k = 0; k < D; ++k) normal[std::size_t(k)] /= len;
  FaceFrame f;
  f.n = normal;
  if constexpr (D == 2) {
    f.a = {-normal[1], normal[0], 0};
  } else {
    std::array<double, 3> a = std::abs(normal[0]) < 0.9 ? std::array<double, 3>{1, 0, 0} : std::array<double, 3>{0, 1, 0};
    const double an = a[0] * normal[0] + a[1] * normal[1] + a[2] * normal[2];
    for (int k = 0; k < 3; ++k) a[std::size_t(k)] -= an * normal[std::size_t(k)];
    const double al = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (auto& v : a) v /= al;
    f.a = a;
    f.b = {normal[1] * a[2] - normal[2] * a[1], normal[2] * a[0] - normal[0] * a[2], normal[0] * a[1] - normal[1] * a[0]};
  }
  return f;
}

// Sample points of a sensor face centred on `c` and normal to `normal`: a segment of length `d` in
// 2D, a disc of diameter `d` in 3D, sampled at about dx / 4 (9 to 33 points across), each point
// the centre of an equal share of the face's area.
template <int D>
std::vector<std::array<double, 3>> sensor_face_points(const std::array<double, 3>& c, const std::array<double, 3>& normal,
                                                      double d, double dx) {
  const FaceFrame f = face_frame<D>(normal);
  const int across = std::min(33, std::max(9, int(std::ceil(4 * d / dx))));
  std::vector<std::array<double, 3>> out;
  if constexpr (D == 2) {
    for (int i = 0; i < across; ++i) {
      const double s = d * ((i + 0.5) / across - 0.5);
      out.push_back({c[0] + s * f.a[0], c[1] + s * f.a[1], 0});
    }
  } else {
    const auto& a = f.a;
    const auto& b = f.b;
    // A square grid of `across` x `across` cells over the disc's bounding square; the cell centres
    // inside the disc, each an equal share of its area.
    for (int i = 0; i < across; ++i)
      for (int j = 0; j < across; ++j) {
        const double u = d * ((i + 0.5) / across - 0.5), v = d * ((j + 0.5) / across - 0.5);
        if (u * u + v * v > 0.25 * d * d) continue;
        out.push_back({c[0] + u * a[0] + v * b[0], c[1] + u * a[1] + v * b[1], c[2] + u * a[2] + v * b[2]});
      }
  }
  return out;
}

// A load cell behind a wall (probe type wall_load): the pressure the fluid's force on the wall and
// structure particles behind a face on the wall surface gives, p = -sum_b w_b F_b . n / A. F_b is
// the force of the last force pass on b (StructureForcePass: the exact reaction of the fluid's pair
// accelerations, plus the impermeable-wall pass's impulse of the last drift over its step); n the
// face's unit normal into the fluid; A its area (d per metre in 2D, pi d^2 / 4 in 3D). b counts
// when it lies behind the face by at most 2 h_max + dx (every layer the fluid's kernel reaches),
// with the share w_b of its lattice cell (dx wide, dx x dx in 3D, centred on b's projection on the
// face) that lies on the face: a uniform pressure then reads exactly at any spacing and face size.
// The face sits on the wall surface, not a spacing in front of it, so it is the same surface at
// every spacing. Unfiltered: the reading of the last force pass (sampled each step with
// `probes_every: step`, a bandwidth of 1 / (2 dt)). nan when no wall particle is behind the face.
template <int D>
double wall_load(const Scene& scene, const ProbeSpec& probe, const sph::ParticleStore& s, const sph::FieldIds& ids,
                 const sph::PhysicsParams& params) {
  using V = sph::Vec<D>;
  if (ids.structure_force < 0) return std::nan("");
  const V* x = s.data<V>(ids.position);
  const V* force = s.data<V>(ids.structure_force);
  const std::uint8_t* kind = s.data<std::uint8_t>(ids.kind);
  const FaceFrame f = face_frame<D>(probe.sensor_normal);
  const double dx = scene.particle_spacing, d = probe.sensor_diameter, depth = 2 * params.max_smoothing_length + dx;
  // Share of [s - dx/2, s + dx/2] (2D), or of the dx x dx square around (u, v) (3D, 8 x 8 points),
  // on the face.
  auto share = [&](double u, double v) {
    if constexpr (D == 2) {
      const double lo = std::max(u - 0.5 * dx, -0.5 * d), hi = std::min(u + 0.5 * dx, 0.5 * d);
      return hi > lo ? (hi - lo) / dx : 0.0;
    } else {
      constexpr int k = 8;
      int in = 0;
      for (int i = 0; i < k; ++i)
        for (int j = 0; j < k; ++j) {
          const double uu = u + dx * ((i + 0.5) / k - 0.5), vv = v + dx * ((j + 0.5) / k - 0.5);
          in += uu * uu + vv * vv <= 0.25 * d * d;
        }
      return double(in) / (k * k);
    }
  };
  double normal_force = 0;
  bool behind = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != std::uint8_t(sph::Kind::wall) && kind[i] != std::uint8_t(sph::Kind::structure)) continue;
    double r[3] = {0, 0, 0};
    for (int k = 0; k < D; ++k) r[k] = double(x[i][k]) - probe.point[std::size_t(k)];
    double rn = 0, u = 0, v = 0, fn = 0;
    for (int k = 0; k < D; ++k) {
      rn += r[k] * f.n[std::size_t(k)];
      u += r[k] * f.a[std::size_t(k)];
      v += r[k] * f.b[std::size_t(k)];
      fn += double(force[i][k]) * f.n[std::size_t(k)];
    }
    if (rn >= 0 || rn < -depth) continue;
    const double w = share(u, v);
    if (w <= 0) continue;
    behind = true;
    normal_force += w * fn;
  }
  const double area = D == 2 ? d : 0.25 * 3.14159265358979323846 * d * d;
  return behind ? -normal_force / area : std::nan("");
}

// A wave gauge's reading at a station: the fluid fraction f(z) = sum_j W(|x_j - (X, z)|, h) V_j
// along the vertical through the station, counting fluid (of the probe's material when given) and
// walls and structures (the bed is not air), is 1 inside the water and 1/2 on a flat free surface.
// From the lowest fluid particle near the station upwards, the first height where f falls below
// 1/2 is the surface (found on a dx/2 grid and refined by bisection to dx/256): a jet or splash
// above an air gap is not water level. No fluid near the station, or no height with f >= 1/2
// (a film too thin to fill half a kernel), gives nan.
template <int D>
double gauge_elevation(const Scene& scene, const ProbeSpec& probe, const sph::ParticleStore& s,
                       const sph::FieldIds& ids, const sph::PhysicsParams& params) {
  using sph::Real;
  using V = sph::Vec<D>;
  const std::size_t n = s.size();
  const V* x = s.data<V>(ids.position);
  const Real* rho = s.data<Real>(ids.density);
  const Real* m = s.data<Real>(ids.mass);
  const std::uint8_t* mat = s.data<std::uint8_t>(ids.material);
  const std::uint8_t* kind = s.data<std::uint8_t>(ids.kind);
  const int want = probe.material.empty() ? -1 : material_index(scene, probe.material);
  const int up = probe.axis;
  const double h = params.smoothing_length, reach = 2 * h, dx = scene.particle_spacing;
  // The particles within the kernel's reach of the vertical line, and where the fluid among them starts.
  std::vector<std::size_t> near;
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (std::size_t i = 0; i < n; ++i) {
    const bool is_fluid = kind[i] == std::uint8_t(sph::Kind::fluid);
    if (is_fluid && want >= 0 && mat[i] != want) continue;
    double r2 = 0;
    for (int k = 0; k < D; ++k)
      if (k != up) r2 += (double(x[i][k]) - probe.point[std::size_t(k)]) * (double(x[i][k]) - probe.point[std::size_t(k)]);
    if (r2 >= reach * reach) continue;
    near.push_back(i);
    if (is_fluid) {
      lowest = std::min(lowest, double(x[i][up]));
      highest = std::max(highest, double(x[i][up]));
    }
  }
  if (!std::isfinite(lowest)) return std::nan("");
  double result = std::nan("");
  sph::dispatch_kernel<D>(params, [&](auto kernel_tag, auto) {
    using K = typename decltype(kernel_tag)::type;
    auto fraction = [&](double z) {
      V at;
      for (int k = 0; k < D; ++k) at[k] = Real(probe.point[std::size_t(k)]);
      at[up] = Real(z);
      double f = 0;
      for (std::size_t i : near) {
        const double r = std::sqrt(double(sph::norm2(x[i] - at)));
        if (r < reach) f += K::w(Real(r), Real(h)) * double(m[i]) / double(rho[i]);
      }
      return f;
    };
    const double step = 0.5 * dx;
    double z = lowest;
    bool in_water = false;
    for (; z <= highest + reach; z += step) {
      const double f = fraction(z);
      if (!in_water) {
        in_water = f >= 0.5;
        continue;
      }
      if (f < 0.5) {
        double lo = z - step, hi = z;  // f(lo) >= 1/2 > f(hi)
        for (int it = 0; it < 7; ++it) {
          const double mid = 0.5 * (lo + hi);
          (fraction(mid) >= 0.5 ? lo : hi) = mid;
        }
        result = 0.5 * (lo + hi);
        return;
      }
    }
  });
  return result;
}

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
      const double h = params.smoothing_length;
      // The fluid within reach of the point or of any point of the sensor's face.
      const double reach = 2 * h + 0.5 * std::max(0.0, probe.sensor_diameter);
      V centre;
      for (int k = 0; k < D; ++k) centre[k] = Real(probe.point[std::size_t(k)]);
      std::vector<std::size_t> near;
      for (std::size_t i = 0; i < n; ++i)
        if (fluid(i) && double(sph::norm2(x[i] - centre)) < reach * reach) near.push_back(i);
      // Shepard interpolation of fluid pressure at one point: sum p_j W V_j / sum W V_j, or nan
      // where too little fluid is near it (a dry sensor, one stray particle).
      auto at_point = [&](const std::array<double, 3>& q) {
        double num = 0, den = 0;
        V at;
        for (int k = 0; k < D; ++k) at[k] = Real(q[std::size_t(k)]);
        sph::dispatch_kernel<D>(params, [&](auto kernel_tag, auto) {
          using K = typename decltype(kernel_tag)::type;
          for (std::size_t i : near) {
            const double r = std::sqrt(double(sph::norm2(x[i] - at)));
            if (r >= 2 * h) continue;
            const double w = K::w(Real(r), Real(h)) * double(m[i]) / double(rho[i]);
            num += w * p[i];
            den += w;
          }
        });
        return den > 0 && den >= probe.min_kernel_sum ? num / den : std::nan("");
      };
      if (probe.sensor_diameter <= 0) return at_point(probe.point);
      // A wall sensor: the mean over its face, each sample standing for an equal share of the area,
      // and each sample the mean over its kernel of what is there: water at its pressure, air at
      // ambient 0. The walls' share of the kernel, sum_b W V_b over boundary particles, is neither,
      // so a sample reads sum_j p_j W V_j / max(sum_j W V_j, 1 - walls): in water (the fluid fills
      // what the walls leave) the Shepard value, where a spray sheet one particle thick fills a
      // tenth of the kernel a tenth of its pressure. (The Shepard value alone spreads the sheet's
      // pressure over the whole kernel, 2h wide at every spacing: the reading of a face larger
      // than the sheet then did not fall as the spacing, and the sheet, shrank.) A face with no
      // fluid within reach reads nan.
      std::vector<std::size_t> walls;
      for (std::size_t i = 0; i < n; ++i)
        if (!fluid(i) && double(sph::norm2(x[i] - centre)) < reach * reach) walls.push_back(i);
      const auto samples = sensor_face_points<D>(probe.point, probe.sensor_normal, probe.sensor_diameter,
                                                 scene.particle_spacing);
      double sum = 0, fluid_sum = 0;
      sph::dispatch_kernel<D>(params, [&](auto kernel_tag, auto) {
        using K = typename decltype(kernel_tag)::type;
        auto kernel_sum = [&](const std::vector<std::size_t>& list, const V& at, double* weighted) {
          double total = 0, with_p = 0;
          for (std::size_t i : list) {
            const double r = std::sqrt(double(sph::norm2(x[i] - at)));
            if (r >= 2 * h) continue;
            const double w = K::w(Real(r), Real(h)) * double(m[i]) / double(rho[i]);
            total += w;
            if (weighted) with_p += w * p[i];
          }
          if (weighted) *weighted = with_p;
          return total;
        };
        for (const auto& q : samples) {
          V at;
          for (int k = 0; k < D; ++k) at[k] = Real(q[std::size_t(k)]);
          double num = 0;
          const double den = kernel_sum(near, at, &num);
          if (!(den > 0)) continue;
          const double open = 1.0 - kernel_sum(walls, at, nullptr);
          sum += num / std::max(den, open);
          fluid_sum += den;
        }
      });
      return fluid_sum > 0 ? sum / double(samples.size()) : std::nan("");
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
    case ProbeSpec::Type::surface_elevation:
      return gauge_elevation<D>(scene, probe, s, ids, params);
    case ProbeSpec::Type::highest_particle: {
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
    case ProbeSpec::Type::wall_load:
      return wall_load<D>(scene, probe, s, ids, params);
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

const char* probe_unit(ProbeSpec::Type t, int dimensions) {
  const bool two_d = dimensions == 2;
  switch (t) {
    case ProbeSpec::Type::front_position: return "m";
    case ProbeSpec::Type::pressure: return "Pa";
    case ProbeSpec::Type::max_speed: return "m/s";
    case ProbeSpec::Type::kinetic_energy: return two_d ? "J/m" : "J";
    case ProbeSpec::Type::fluid_particles: return "-";
    case ProbeSpec::Type::surface_elevation: return "m";
    case ProbeSpec::Type::highest_particle: return "m";
    case ProbeSpec::Type::material_mass: return two_d ? "kg/m" : "kg";
    case ProbeSpec::Type::wall_load: return "Pa";
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
