// Per-particle passes (gather: each particle sums over its own neighbours, so results do not
// depend on thread order). Each pass is a functor with `operator()(i)`; a backend only decides
// how the index range is walked (OpenMP loop, CUDA grid).
#pragma once
#include <cmath>
#include <cstdint>

#include "sph/config.hpp"
#if !defined(__CUDA_ARCH__)
#include "sph/cpu_simd.hpp"
#endif
#include "sph/kernels.hpp"
#include "sph/neighbour_grid.hpp"
#include "sph/pair_physics.hpp"
#include "sph/physics_params.hpp"
#include "sph/rheology.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

// Raw pointers to the particle fields a pass may read or write (one SoA array per field).
template <int D>
struct ParticleView {
  Vec<D>* position = nullptr;
  Vec<D>* velocity = nullptr;
  Vec<D>* acceleration = nullptr;
  Real* density = nullptr;
  Real* density_rate = nullptr;
  Real* pressure = nullptr;
  Real* mass = nullptr;
  Real* smoothing_length = nullptr;
  std::uint8_t* material = nullptr;
  std::uint8_t* kind = nullptr;
  Vec<D>* density_gradient = nullptr;  // only with Antuono diffusion
  Vec<D>* boundary_normal = nullptr;   // only with mDBC: ghost node offset x_g - x_b of boundary particles [m]
  Vec<D>* structure_force = nullptr;   // only with structures: force of the fluid on each structure particle
  std::uint8_t* body = nullptr;        // only with structures: structure index (kNoBody for others)
  std::uint8_t* zone = nullptr;        // only with open boundaries: buffer zone index (kNoZone for others)
  Vec<D>* viscous_velocity = nullptr;  // only with no-slip mDBC: the velocity walls show the viscous terms
  std::uint8_t* free_slip = nullptr;   // only with free-slip walls: 1 for their particles
  Vec<D>* shifting_velocity = nullptr; // only with particle shifting: u_s of fluid particles, added in the drift
  Real* shear_rate = nullptr;          // only with a non-Newtonian material: sqrt(2 D:D) [1/s]
  Real* effective_viscosity = nullptr; // only with a non-Newtonian material: mu_eff [Pa s]
  Real* shear_stress = nullptr;        // only with a non-Newtonian material: sqrt(J2(tau)) = mu_eff gamma_dot [Pa]
  std::uint8_t* split_fresh = nullptr; // only with transitions: 1 for the daughters of the last split
  Vec<D>* viscous_load = nullptr;     // only with structures and implicit viscosity: see implicit_viscosity.hpp
  Vec<D>* viscous_pending = nullptr;
  // Only with impermeable walls: see WallConstraintPass and WallConstraintLoadPass.
  Vec<D>* put_back_impulse = nullptr;      // fluid: m (v after - v before) of the last drift's put-back [N s]
  std::uint32_t* put_back_from = nullptr;  // fluid: the boundary particle it is booked to (kNoPutBack: none)
  Vec<D>* constraint_force = nullptr;      // walls, structures: the put-backs booked to them / dt [N]
  Real* constraint_power = nullptr;        // walls, structures: kinetic energy those put-backs removed / dt [W]
  // CPU only: positions as one array per coordinate (component a at a * soa_stride), a copy made
  // at each sort so that distance checks vectorise; valid until the next drift.
  const Real* position_soa = nullptr;
  std::size_t soa_stride = 0;
  std::uint32_t count = 0;
};

// Eta^2 = 0.01 h^2 regularises 1/r^2 terms (Monaghan 1992).
inline constexpr Real kEta2Factor = Real(0.01);

// The pair vector to the nearest periodic image, for vectors not taken from a grid range (which
// carries its image offset): neighbour lists, ghost nodes. Unchanged without periodic axes.
template <int D>
TURBID_HD TURBID_INLINE Vec<D> nearest_image(const PhysicsParams& prm, Vec<D> r) {
  if (!prm.periodic) return r;
  for (int a = 0; a < D; ++a) {
    const Real L = prm.period[a];
    if (L > Real(0)) {
      if (r[a] > Real(0.5) * L) r[a] -= L;
      else if (r[a] < Real(-0.5) * L) r[a] += L;
    }
  }
  return r;
}

// Walls and structures: particles that stand for a solid (not fluid, not an open boundary's buffer).
TURBID_HD inline bool solid_kind(std::uint8_t k) {
  return k == std::uint8_t(Kind::wall) || k == std::uint8_t(Kind::structure);
}

// The smoothing length of the pair (i, j), i a fluid or buffer particle of smoothing length h_i.
// Two particles of different smoothing lengths use the kernel of the mean h (symmetric in i and
// j). A fluid particle and a wall or structure particle use the fluid particle's h: the solid
// stands in for the fluid's own continuation beyond the surface, so its half of the kernel sum
// must be the fluid's half-kernel. With the mean h a split daughter (h/2) next to a wall of the
// parent's spacing (h) saw the wall through a kernel half again as wide as its fluid neighbours':
// the wall's half of sum V grad W then fell short of the fluid's and the daughters settled behind
// the wall surface (2.5e-3 put-backs per fluid particle-step in a resting layer of daughters on a
// DBC floor; issue #47 item 2).
template <int D, class K>
TURBID_HD inline Real pair_h(const ParticleView<D>& P, const PhysicsParams& prm, bool uniform, Real h_i, std::uint32_t j) {
  if (uniform) return prm.smoothing_length;
  return solid_kind(P.kind[j]) ? h_i : Real(0.5) * (h_i + P.smoothing_length[j]);
}

// The same for any i: a wall or structure particle i takes the fluid particle j's h.
template <int D, class K>
TURBID_HD inline Real pair_h(const ParticleView<D>& P, const PhysicsParams& prm, bool uniform, Real h_i, std::uint32_t i,
                             std::uint32_t j) {
  if (uniform) return prm.smoothing_length;
  if (solid_kind(P.kind[i]) && !solid_kind(P.kind[j])) return P.smoothing_length[j];
  return pair_h<D, K>(P, prm, false, h_i, j);
}

// An optional per-particle neighbour list (CPU backend): the momentum pass records, for each
// particle, the indices of its neighbours within the support in grid order; the continuity pass of
// the next step runs on the same positions and reads them instead of searching the grid again.
// A particle with more neighbours than `stride` falls back to the grid (same order, same sums).
struct NeighbourList {
  std::uint32_t* entries = nullptr;  // stride entries per particle
  std::uint32_t* count = nullptr;    // neighbours of each particle (> stride: overflowed)
  std::uint32_t stride = 0;
  bool record = false;               // true: fill the list while searching the grid
};

// Calls f(j, r_ij, r_ij^2) for every j != i with r_ij < 2 h_max, in grid order.
template <int D, class F>
TURBID_HD TURBID_INLINE void for_each_neighbour(const ParticleView<D>& P, const GridView<D>& G, const NeighbourList& L,
                                         const PhysicsParams& prm, std::uint32_t i, const Vec<D>& xi, F&& f) {
  const Real support2 = Real(4) * prm.max_smoothing_length * prm.max_smoothing_length;
  if (L.entries && !L.record && L.count[i] <= L.stride) {
    const std::uint32_t* list = L.entries + std::size_t(i) * L.stride;
    const std::uint32_t n = L.count[i];
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t j = list[k];
      const Vec<D> rij = nearest_image<D>(prm, xi - P.position[j]);
      f(j, rij, norm2(rij));
    }
    return;
  }
  int c[D] = {};
  G.cell_of(xi, c);
  std::uint32_t n = 0;
  std::uint32_t* out = L.record ? L.entries + std::size_t(i) * L.stride : nullptr;
#if !defined(__CUDA_ARCH__)
  if (P.position_soa) {
    // CPU: distances of a whole cell range in one vectorisable loop over coordinate arrays, then
    // the (few) pairs inside the support; same order as the plain loop below.
    constexpr std::uint32_t kChunk = 64;
    Real d[D][kChunk];
    Real r2buf[kChunk];
    G.for_each_neighbour_range(c, [&](std::uint32_t b, std::uint32_t e, const Vec<D>& offset) {
      const Vec<D> xo = xi - offset;  // x_i against the image of the range's particles
      for (std::uint32_t b0 = b; b0 < e; b0 += kChunk) {
        const std::uint32_t len = e - b0 < kChunk ? e - b0 : kChunk;
        for (std::uint32_t k = 0; k < len; ++k) {
          Real r2 = 0;
          for (int a = 0; a < D; ++a) {
            d[a][k] = xo[a] - P.position_soa[std::size_t(a) * P.soa_stride + b0 + k];
            r2 += d[a][k] * d[a][k];
          }
          r2buf[k] = r2;
        }
        // The indices inside the support as a bit mask (eight comparisons at once), then only
        // the pairs: candidates outnumber neighbours about 8 to 1 with cells of 2h.
        std::uint64_t mask = below_mask(r2buf, len, support2);
        if (i >= b0 && i < b0 + len) mask &= ~(std::uint64_t(1) << (i - b0));
        while (mask) {
          const auto k = std::uint32_t(__builtin_ctzll(mask));
          mask &= mask - 1;
          const std::uint32_t j = b0 + k;
          if (out) {
            if (n < L.stride) out[n] = j;
            ++n;
          }
          Vec<D> rij;
          for (int a = 0; a < D; ++a) rij[a] = d[a][k];
          f(j, rij, norm2(rij));
        }
      }
    });
    if (out) L.count[i] = n;
    return;
  }
#endif
  G.for_each_neighbour_range(c, [&](std::uint32_t b, std::uint32_t e, const Vec<D>& offset) {
    const Vec<D> xo = xi - offset;
    for (std::uint32_t j = b; j < e; ++j) {
      const Vec<D> rij = xo - P.position[j];
      const Real r2 = norm2(rij);
      if (r2 >= support2 || j == i) continue;
      if (out) {
        if (n < L.stride) out[n] = j;
        ++n;
      }
      f(j, rij, r2);
    }
  });
  if (out) L.count[i] = n;
}

// Pressure from density with each material's equation of state: fluid and buffer particles their
// own material's, walls and structures wall_material's (with mDBC their density is that of
// wall_material at the fluid's extrapolated pressure, see ghost_interpolation).
template <int D>
struct PressurePass {
  ParticleView<D> P;
  PhysicsParams prm;
  TURBID_HD void operator()(std::uint32_t i) const {
    const bool own = P.kind[i] == std::uint8_t(Kind::fluid) || P.kind[i] == std::uint8_t(Kind::buffer);
    const int m = own ? P.material[i] : prm.wall_material;
    P.pressure[i] = prm.materials[m].eos.pressure(P.density[i]);
  }
};

// Integration steps of the kick-drift-kick scheme (sph/solver.hpp), per particle.
template <int D>
struct KickPass {
  ParticleView<D> P;
  Real half_dt;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (P.kind[i] == std::uint8_t(Kind::fluid)) P.velocity[i] += half_dt * P.acceleration[i];
  }
};

template <int D>
struct DriftPass {
  ParticleView<D> P;
  Real dt;
  Real wall_rho_min;  // TaitEos::no_tension_density of the wall material
  bool periodic = false;
  Real lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, period[3] = {0, 0, 0};

  DriftPass(const ParticleView<D>& view, Real step, Real rho_min, const PhysicsParams& prm)
      : P(view), dt(step), wall_rho_min(rho_min), periodic(prm.periodic) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = prm.periodic_origin[a];
      hi[a] = prm.periodic_end[a];
      period[a] = prm.period[a];
    }
  }
  // Back into [lo, hi) on periodic axes (a fluid particle moves far less than a period per step),
  // hi the domain's upper face as the sort tests it. Float rounding of x -/+ period can land just
  // outside either face: clamped to the lower face then.
  TURBID_HD Vec<D> wrap(Vec<D> x) const {
    for (int a = 0; a < D; ++a) {
      if (period[a] == Real(0)) continue;
      if (x[a] >= hi[a]) x[a] -= period[a];
      else if (x[a] < lo[a]) x[a] += period[a];
      if (x[a] < lo[a]) x[a] = lo[a];
      if (!(x[a] < hi[a])) x[a] = lo[a];
    }
    return x;
  }
  TURBID_HD void operator()(std::uint32_t i) const {
    const Real rho = P.density[i] + dt * P.density_rate[i];
    if (P.kind[i] == std::uint8_t(Kind::fluid)) {
      Vec<D> x = P.position[i] + dt * P.velocity[i];
      if (P.shifting_velocity) x += dt * P.shifting_velocity[i];
      if (periodic) x = wrap(x);
      P.position[i] = x;
      P.density[i] = rho;
    } else if (P.kind[i] == std::uint8_t(Kind::buffer)) {
      P.position[i] += dt * P.velocity[i];  // density and velocity: BufferPass
    } else {
      // DBC walls never fall below zero absolute pressure (TaitEos::no_tension_density).
      P.density[i] = rho < wall_rho_min ? wall_rho_min : rho;
    }
  }
};

// Records the neighbour list exactly as the momentum pass does, without computing anything: used
// after a resume, so that the first continuity pass reads the same list (and gives the same bits)
// as in the run that wrote the checkpoint.
template <int D>
struct RecordNeighboursPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (P.kind[i] != std::uint8_t(Kind::fluid)) {
      L.count[i] = L.stride + 1;
      return;
    }
    for_each_neighbour<D>(P, G, L, prm, i, P.position[i], [](std::uint32_t, const Vec<D>&, Real) {});
  }
};

// Renormalised density gradient for Antuono's δ-SPH (physics.md C3):
// <grad rho>_i = sum_j (rho_j - rho_i) L_i grad_i W_ij V_j, L_i = [sum_j r_ji (x) grad_i W_ij V_j]^-1,
// over fluid neighbours of the same material. Where L_i is near-singular (free surface, isolated
// particles) the plain gradient is used (L_i = I).
template <int D, class K, bool UniformH>
struct DensityGradientPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  TURBID_HD void operator()(std::uint32_t i) const {
    Vec<D> g = Vec<D>::zero();
    if (P.kind[i] != std::uint8_t(Kind::fluid)) {
      P.density_gradient[i] = g;
      return;
    }
    const Vec<D> xi = P.position[i];
    const Real rho_i = P.density[i];
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    const std::uint8_t mat_i = P.material[i];
    Real M[D][D] = {};
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
        if (P.kind[j] != std::uint8_t(Kind::fluid) || P.material[j] != mat_i || r2 == Real(0)) return;
        const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
        if (!UniformH && r2 >= Real(4) * h * h) return;
        const Real F = K::f_inv(std::sqrt(r2), Real(1) / h);
        const Real vol = P.mass[j] / P.density[j];
        for (int a = 0; a < D; ++a) {
          g[a] += (P.density[j] - rho_i) * F * rij[a] * vol;
          for (int b2 = 0; b2 < D; ++b2) M[a][b2] -= rij[a] * F * rij[b2] * vol;  // r_ji (x) grad W
        }
    });
    // Solve M^T-free: L = M^-1 applied to g (M is symmetric here).
    Real det;
    if constexpr (D == 2) {
      det = M[0][0] * M[1][1] - M[0][1] * M[1][0];
      if (det > Real(1e-3)) {
        const Real gx = (M[1][1] * g[0] - M[0][1] * g[1]) / det;
        const Real gy = (-M[1][0] * g[0] + M[0][0] * g[1]) / det;
        g[0] = gx;
        g[1] = gy;
      }
    } else {
      const Real c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1];
      const Real c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2];
      const Real c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
      det = M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02;
      if (det > Real(1e-3)) {
        const Real i00 = c00 / det, i01 = (M[0][2] * M[2][1] - M[0][1] * M[2][2]) / det,
                   i02 = (M[0][1] * M[1][2] - M[0][2] * M[1][1]) / det;
        const Real i10 = c01 / det, i11 = (M[0][0] * M[2][2] - M[0][2] * M[2][0]) / det,
                   i12 = (M[0][2] * M[1][0] - M[0][0] * M[1][2]) / det;
        const Real i20 = c02 / det, i21 = (M[0][1] * M[2][0] - M[0][0] * M[2][1]) / det,
                   i22 = (M[0][0] * M[1][1] - M[0][1] * M[1][0]) / det;
        const Vec<D> g0 = g;
        g[0] = i00 * g0[0] + i01 * g0[1] + i02 * g0[2];
        g[1] = i10 * g0[0] + i11 * g0[1] + i12 * g0[2];
        g[2] = i20 * g0[0] + i21 * g0[1] + i22 * g0[2];
      }
    }
    P.density_gradient[i] = g;
  }
};

// CPU lane evaluation (ContinuityPass::lanes, MomentumPass::lanes): each particle's neighbours are
// copied into contiguous arrays first (scalar loads), so that the pair arithmetic runs on plain
// arrays of kLanes lanes, which the compiler turns into vector instructions; the lanes are added in
// a fixed order, so results stay deterministic.
inline constexpr int kLanes = 8;
inline constexpr std::uint32_t kLaneNeighbours = 1024;  // more neighbours: the plain loop is used

// r_ij and v_ij . r_ij of each lane. A padding lane (beyond the last neighbour) gets the harmless
// distance r = (h, 0, 0) (q = 1); the caller gives it zero mass.
template <int D>
struct LaneGeometry {
  alignas(32) Real r[D][kLaneNeighbours + kLanes];
  alignas(32) Real vr[kLaneNeighbours + kLanes];

  TURBID_INLINE void set(std::uint32_t k, const ParticleView<D>& P, const PhysicsParams& prm, const Vec<D>& xi,
                         const Vec<D>& vi, std::uint32_t j, bool valid, Real h) {
    const Vec<D> rij = nearest_image<D>(prm, xi - P.position[j]);
    Real dot_v = 0;
    for (int a = 0; a < D; ++a) {
      const Real d = rij[a];
      r[a][k] = valid ? d : (a == 0 ? h : Real(0));
      dot_v += (vi[a] - P.velocity[j][a]) * d;
    }
    vr[k] = dot_v;
  }
  // The same in two parts, for a caller that already has r_ij from the neighbour search.
  void set_r(std::uint32_t k, const Vec<D>& rij) {
    for (int a = 0; a < D; ++a) r[a][k] = rij[a];
  }
  void set_pad(std::uint32_t k, Real h) {
    for (int a = 0; a < D; ++a) r[a][k] = a == 0 ? h : Real(0);
  }
  void set_vr(std::uint32_t k, const ParticleView<D>& P, const Vec<D>& vi, std::uint32_t j) {
    Real dot_v = 0;
    for (int a = 0; a < D; ++a) dot_v += (vi[a] - P.velocity[j][a]) * r[a][k];
    vr[k] = dot_v;
  }
  Real r2(std::uint32_t k) const {
    Real s = 0;
    for (int a = 0; a < D; ++a) s += r[a][k] * r[a][k];
    return s;
  }
};

// Continuity with density diffusion (physics.md C3-C4) for every particle. Fluid particles sum
// over all neighbours; wall particles (dynamic boundary condition, DBC) over fluid neighbours only.
// Diffusion acts between fluid particles of the same material.
template <int D, class K, Diffusion Diff, bool UniformH>
struct ContinuityPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;

  TURBID_HD void operator()(std::uint32_t i) const {
    const Vec<D> xi = P.position[i];
    const Vec<D> vi = P.velocity[i];
    const Real rho_i = P.density[i];
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    const bool fluid_i = P.kind[i] == std::uint8_t(Kind::fluid);
    const std::uint8_t mat_i = fluid_i ? P.material[i] : std::uint8_t(prm.wall_material);
    const MaterialParams& Mi = prm.materials[mat_i];
    // Fourtakas: rho^H_ij (pair::hydrostatic_difference).
    const Real inv_gamma = Real(1) / Mi.eos.gamma;
    const Real hydro_k = Mi.eos.rest_density / Mi.eos.stiffness;

    Real drho = 0;
#if !defined(__CUDA_ARCH__)
    if constexpr (UniformH && Diff != Diffusion::antuono) {
      if (fluid_i && L.entries && !L.record && L.count[i] <= L.stride && L.count[i] <= kLaneNeighbours &&
          lanes(i, xi, vi, rho_i, mat_i, Mi, drho)) {
        P.density_rate[i] = drho;
        return;
      }
    }
#endif
    if (!fluid_i) {
      // With mDBC the boundary density is extrapolated from the fluid (MdbcPass), not integrated;
      // buffer particles get theirs from BufferPass.
      if (prm.boundary == Boundary::mdbc || P.kind[i] == std::uint8_t(Kind::buffer)) {
        P.density_rate[i] = Real(0);
        return;
      }
      // A wall particle changes density only through fluid neighbours; most walls have none near.
      int c[D] = {};
      G.cell_of(xi, c);
      if (!G.fluid_near(c)) {
        P.density_rate[i] = Real(0);
        return;
      }
    }
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
        const Real h = pair_h<D, K>(P, prm, UniformH, h_i, i, j);
        if (!UniformH && r2 >= Real(4) * h * h) return;
        const bool fluid_j = P.kind[j] == std::uint8_t(Kind::fluid);
        if (!fluid_i && !fluid_j) return;
        const Real F = K::f_inv(std::sqrt(r2), Real(1) / h);
        const Real rho_j = P.density[j];
        const Real vol_j = P.mass[j] / rho_j;
        drho += pair::continuity(rho_i, vol_j, dot(vi - P.velocity[j], rij), F);
        if constexpr (Diff != Diffusion::none) {
          Real rho_d = rho_j;  // the density of j the diffusion term sees
          bool diffuse = fluid_i && fluid_j && P.material[j] == mat_i;
          if (fluid_i && fluid_j && !diffuse && prm.interface_correction) {
            rho_d = ghost_density(i, xi, rho_i, h, mat_i, rij);
            diffuse = true;
          }
          if (diffuse) {
            if constexpr (Diff == Diffusion::molteni) {
              drho += pair::diffusion_molteni(prm.diffusion_delta * h * Mi.sound_speed, rho_i, rho_d, vol_j, F);
            } else if constexpr (Diff == Diffusion::antuono) {
              // Across an interface the ghost stands for i's material: i's gradient at both ends.
              const Vec<D>& grad_j = P.material[j] == mat_i ? P.density_gradient[j] : P.density_gradient[i];
              drho += pair::diffusion_antuono<D>(prm.diffusion_delta * h * Mi.sound_speed, rho_i, rho_d,
                                                 P.density_gradient[i], grad_j, rij, vol_j, F);
            } else {
              Real gr = 0;
              for (int k = 0; k < D; ++k) gr += prm.hydrostatic_gravity[k] * rij[k];
              const Real rho_h = pair::hydrostatic_difference(Mi.eos.rest_density, inv_gamma, hydro_k, gr);
              drho += pair::diffusion_fourtakas(prm.diffusion_delta * Real(2) * h * Mi.sound_speed, rho_i, rho_d, rho_h,
                                                r2, kEta2Factor * h * h, vol_j, F);
            }
          }
        }
    });
    P.density_rate[i] = drho;
  }

  // The paper's interface correction (seed paper eq. 3, Fig. 1): for a neighbour j of another
  // material, the density of j that i's diffusion term sees is the ghost density
  //   rho_j* = sum_{j' in Phi_i} rho_j' W_jj' V_j' / sum_{j' in Phi_i} W_jj' V_j',
  // a Shepard interpolation at x_j over the particles j' of i's own material in i's neighbourhood
  // Phi_i (i included). x_j - x_j' = r_ij' - r_ij, so the walk is i's own neighbour walk again.
  // With Fourtakas' diffusion each rho_j' is first carried to x_j along i's hydrostatic line
  // (rho_j' + rho^H from x_j' to x_j): the j' lie on i's side of the interface, and their plain
  // average would stand for a point higher than x_j, which the hydrostatic term of the diffusion
  // would then read as a density defect at the interface.
  TURBID_HD Real ghost_density(std::uint32_t i, const Vec<D>& xi, Real rho_i, Real h, std::uint8_t mat_i,
                               const Vec<D>& rij) const {
    const MaterialParams& Mi = prm.materials[mat_i];
    const Real inv_gamma = Real(1) / Mi.eos.gamma;
    const Real hydro_k = Mi.eos.rest_density / Mi.eos.stiffness;
    // rho at x_j expected from rho_k at x_k, r = x_k - x_j
    const auto carried = [&](Real rho_k, const Vec<D>& r) {
      if constexpr (Diff != Diffusion::fourtakas) return rho_k;
      Real gr = 0;
      for (int a = 0; a < D; ++a) gr += prm.hydrostatic_gravity[a] * r[a];
      return rho_k + pair::hydrostatic_difference(Mi.eos.rest_density, inv_gamma, hydro_k, gr);
    };
    const Real w_i = K::w(std::sqrt(norm2(rij)), h) * P.mass[i] / rho_i;  // j' = i: x_i - x_j = r_ij
    Real num = w_i * carried(rho_i, rij), den = w_i;
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t k, const Vec<D>& rik, Real) {
      if (P.kind[k] != std::uint8_t(Kind::fluid) || P.material[k] != mat_i) return;
      const Vec<D> rkj = rij - rik;  // x_k - x_j
      const Real r = std::sqrt(norm2(rkj));
      if (r >= Real(2) * h) return;
      const Real w = K::w(r, h) * P.mass[k] / P.density[k];
      num += w * carried(P.density[k], rkj);
      den += w;
    });
    return den > Real(0) ? num / den : rho_i;
  }

  // CPU, fluid particle with a recorded neighbour list: the same sums in lanes (see kLanes). False
  // (nothing done) when the interface correction needs the generic path (a neighbour of another
  // material).
  static constexpr int W = kLanes;
  bool lanes(std::uint32_t i, const Vec<D>& xi, const Vec<D>& vi, Real rho_i, std::uint8_t mat_i,
             const MaterialParams& Mi, Real& result) const {
    const std::uint32_t* nb = L.entries + std::size_t(i) * L.stride;
    const std::uint32_t m = L.count[i];
    const std::uint32_t padded = (m + W - 1) / W * W;
    const Real h = prm.smoothing_length;
    LaneGeometry<D> g;
    alignas(32) Real rho_j[kLaneNeighbours + W], vol_j[kLaneNeighbours + W], same[kLaneNeighbours + W];
    for (std::uint32_t k = 0; k < padded; ++k) {
      const bool valid = k < m;
      const std::uint32_t j = valid ? nb[k] : i;
      g.set(k, P, prm, xi, vi, j, valid, h);
      rho_j[k] = P.density[j];
      vol_j[k] = (valid ? P.mass[j] : Real(0)) / P.density[j];
      const bool fluid_j = P.kind[j] == std::uint8_t(Kind::fluid);
      const bool s_mat = fluid_j && P.material[j] == mat_i;
      if (fluid_j && !s_mat && prm.interface_correction && Diff != Diffusion::none) return false;
      same[k] = s_mat ? Real(1) : Real(0);
    }
    const Real inv_h = Real(1) / h;
    const Real eta2 = kEta2Factor * h * h;
    const Real inv_gamma = Real(1) / Mi.eos.gamma;
    const Real hydro_k = Mi.eos.rest_density / Mi.eos.stiffness;
    const Real dh = prm.diffusion_delta * h * Mi.sound_speed;
    Real sum[W] = {};
    for (std::uint32_t k0 = 0; k0 < padded; k0 += W) {
      for (int l = 0; l < W; ++l) {
        const std::uint32_t k = k0 + std::uint32_t(l);
        const Real r2 = g.r2(k);
        Real gr = 0;
        for (int a = 0; a < D; ++a) gr += prm.hydrostatic_gravity[a] * g.r[a][k];
        const Real F = K::f_inv(std::sqrt(r2), inv_h);
        Real d = pair::continuity(rho_i, vol_j[k], g.vr[k], F);
        if constexpr (Diff == Diffusion::molteni) {
          d += same[k] * pair::diffusion_molteni(dh, rho_i, rho_j[k], vol_j[k], F);
        } else if constexpr (Diff == Diffusion::fourtakas) {
          const Real rho_h = pair::hydrostatic_difference(Mi.eos.rest_density, inv_gamma, hydro_k, gr);
          d += same[k] * pair::diffusion_fourtakas(Real(2) * dh, rho_i, rho_j[k], rho_h, r2, eta2, vol_j[k], F);
        }
        sum[l] += d;
      }
    }
    Real t = 0;
    for (int l = 0; l < W; ++l) t += sum[l];
    result = t;
    return true;
  }
};

// The velocity particle j shows viscous terms: no-slip mDBC boundary particles show the mirrored
// fluid velocity (viscous_velocity), every other particle its own.
template <int D>
TURBID_HD inline Vec<D> viscous_velocity_of(const ParticleView<D>& P, std::uint32_t j) {
  const bool mirrored = P.viscous_velocity != nullptr && solid_kind(P.kind[j]);
  return mirrored ? P.viscous_velocity[j] : P.velocity[j];
}

// Generalised Newtonian rheology (physics.md C8), before the momentum pass: for every fluid
// particle the velocity gradient in the first-order difference form
//   (grad v)_i = sum_j V_j (v_j - v_i) (x) grad_i W_ij
// over all neighbours (boundary particles with the velocity they show viscous terms, so the
// shear at a no-slip wall is seen), the shear rate gamma_dot = sqrt(2 D:D) of its symmetric part,
// mu_eff(gamma_dot) of the particle's material (capped at dynamic_viscosity) and the effective
// shear stress sqrt(J2(tau)) = mu_eff gamma_dot of tau = 2 mu_eff D. The difference form is exact
// for a uniform velocity whatever the particle arrangement; boundary particles get zeros.
template <int D, class K, bool UniformH>
struct RheologyPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (P.kind[i] != std::uint8_t(Kind::fluid)) {
      P.shear_rate[i] = Real(0);
      P.effective_viscosity[i] = Real(0);
      P.shear_stress[i] = Real(0);
      return;
    }
    const Vec<D> xi = P.position[i];
    const Vec<D> vi = P.velocity[i];
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    Real g[D][D] = {};
    for_each_neighbour<D>(P, G, NeighbourList{}, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
      const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
      if (!UniformH && r2 >= Real(4) * h * h) return;
      // A free-slip wall holds no velocity of its own for the fluid's shear: it is left out (the
      // difference form stays exact for a uniform velocity with the truncated support).
      if (P.free_slip && P.free_slip[j]) return;
      const Real FV = K::f_inv(std::sqrt(r2), Real(1) / h) * P.mass[j] / P.density[j];
      const Vec<D> vji = viscous_velocity_of<D>(P, j) - vi;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) g[a][b] += vji[a] * FV * rij[b];
    });
    const MaterialParams& M = prm.materials[P.material[i]];
    const Real gamma_dot = shear_rate<D>(g);
    const Real mu = M.non_newtonian ? M.rheology.effective_viscosity(gamma_dot) : M.dynamic_viscosity;
    P.shear_rate[i] = gamma_dot;
    P.effective_viscosity[i] = mu;
    P.shear_stress[i] = mu * gamma_dot;
  }
};

// Whether the laminar viscous term of fluid particle i (material Mi) with j (material Mj if fluid_j)
// belongs to the implicit viscous update: i's material is implicit and j is of the same kind of
// material or a boundary particle. A pair of an implicit and an explicit material (debris and
// water) stays explicit: its harmonic-mean viscosity is about twice the explicit side's.
TURBID_HD inline bool implicit_pair(const MaterialParams& Mi, const MaterialParams& Mj, bool fluid_j) {
  return Mi.implicit_viscosity && (!fluid_j || Mj.implicit_viscosity);
}

// Whether the laminar viscous term of fluid particle i with j takes the central form (see
// MaterialParams::central_stress); symmetric in i and j for two fluid particles.
TURBID_HD inline bool central_stress_pair(const MaterialParams& Mi, const MaterialParams& Mj, bool fluid_j) {
  return Mi.central_stress || (fluid_j && Mj.central_stress);
}

// The approach of fluid particle i to boundary particle j along j's normal n_j (its ghost offset),
// (v_ij . n_j)(r_ij . n_j) / |n_j|^2, which the artificial viscosity takes for wall pairs with
// PhysicsParams::wall_viscosity_normal; v_ij . r_ij where j has no normal.
template <int D>
TURBID_HD inline Real wall_normal_approach(const Vec<D>& vij, const Vec<D>& rij, const Vec<D>& nj) {
  const Real n2 = norm2(nj);
  return n2 > Real(0) ? dot(vij, nj) * dot(rij, nj) / n2 : dot(vij, rij);
}

// The direction that artificial viscosity of such a wall pair acts along: r_ij's part along n_j,
// (r_ij . n_j) n_j / |n_j|^2 (r_ij where j has no normal). With the approach above the pair's
// power a_i . v_ij = s (v_ij . n_j)(r_ij . n_j) / |n_j|^2 = s x approach is never positive (s > 0
// only for approach < 0): the pair dissipates. Along r_ij instead, on a curved wall the particles
// behind one sliding past push it forward and outward (issue #47 item 3).
template <int D>
TURBID_HD inline Vec<D> wall_normal_direction(const Vec<D>& rij, const Vec<D>& nj) {
  const Real n2 = norm2(nj);
  return n2 > Real(0) ? (dot(rij, nj) / n2) * nj : rij;
}

// Wall shear of boundary particle j on fluid particle i (PhysicsParams::wall_function):
//   a_i = -2 u*^2 t V_j max(0, -F r_ij . n_j),
// t the direction of i's velocity relative to j along j's wall surface (normal n_j, from
// boundary_normal, the surface half of it beyond x_j), u*^2 from the log law at i's distance
// y = r_ij . n_j - |boundary_normal_j| / 2 from that surface. The weight is the wall's share of
// -d gamma / dy, gamma_i = sum_b V_b W_ib the wall's part of i's kernel: across a plane wall it
// integrates to gamma at the surface, 1/2, so the fluid particles over a unit of wall area take
// rho u*^2 in all, whatever the spacing. The structure-force pass takes the reaction pair by pair.
template <int D>
TURBID_HD inline Vec<D> wall_friction_pair(const ParticleView<D>& P, const PhysicsParams& prm, const Vec<D>& vi,
                                           Real rho_i, Real mu_i, std::uint32_t j, const Vec<D>& rij, Real F) {
  const Vec<D> nb = P.boundary_normal[j];
  const Real n2 = norm2(nb);
  if (!(n2 > Real(0))) return Vec<D>::zero();
  const Real inv_n = Real(1) / std::sqrt(n2);
  const Vec<D> n = inv_n * nb;
  const Real rn = dot(rij, n);
  const Real weight = -F * rn;  // F < 0
  if (!(weight > Real(0))) return Vec<D>::zero();
  const Vec<D> vr = vi - P.velocity[j];
  const Vec<D> vt = vr - dot(vr, n) * n;
  const Real u_t = std::sqrt(norm2(vt));
  if (!(u_t > Real(0))) return Vec<D>::zero();
  Real y = rn - Real(0.5) * n2 * inv_n;
  y = y > prm.wall_function_min_distance ? y : prm.wall_function_min_distance;
  const Real us2 = pair::wall_friction_velocity2(u_t, y, mu_i / rho_i, prm.wall_roughness_length);
  const Real vol_j = P.mass[j] / P.density[j];
  return (Real(-2) * us2 * vol_j * weight / u_t) * vt;
}

// Acceleration of fluid particle i (velocity vi, density rho_i, pressure p_i, smoothing length
// h_i, material Mi, viscosity mu_i) due to particle j at r_ij = x_i - x_j: pressure and viscosity
// (physics.md C10, C2). Boundary particles take the fluid's viscosity mu_i (no-slip in the fluid's
// own rheology). The structure-force pass evaluates the same function for the same pair, so the force on a
// structure is exactly the reaction of what it does to the fluid.
template <int D, class K, bool UniformH>
TURBID_HD inline Vec<D> momentum_pair(const ParticleView<D>& P, const PhysicsParams& prm, const Vec<D>& vi, Real rho_i,
                                      Real p_i, Real h_i, const MaterialParams& Mi, Real mu_i, std::uint32_t j,
                                      const Vec<D>& rij, Real r2) {
  const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
  if (!UniformH && r2 >= Real(4) * h * h) return Vec<D>::zero();
  const Real F = K::f_inv(std::sqrt(r2), Real(1) / h);
  const Real rho_j = P.density[j];
  const Real m_j = P.mass[j];
  const std::uint8_t mat_j = P.kind[j] == std::uint8_t(Kind::fluid) ? P.material[j] : std::uint8_t(prm.wall_material);
  const MaterialParams& Mj = prm.materials[mat_j];
  const Vec<D> vij = vi - viscous_velocity_of<D>(P, j);
  const Real eta2 = kEta2Factor * h * h;
  Real s = pair::pressure(m_j, p_i, P.pressure[j], rho_i, rho_j, F);
  const bool fluid_j = P.kind[j] == std::uint8_t(Kind::fluid);
  const bool free_slip_j = !fluid_j && P.free_slip && P.free_slip[j];
  // The wall function carries the whole wall shear, viscous sublayer included.
  const bool wall_function = prm.wall_function && !fluid_j && !free_slip_j;
  if (prm.viscosity == Viscosity::artificial) {
    const bool normal = prm.wall_viscosity_normal && !fluid_j;
    const Real approach = normal ? wall_normal_approach<D>(vij, rij, P.boundary_normal[j]) : dot(vij, rij);
    const Real s_visc = pair::artificial_viscosity(prm.artificial_viscosity, h, Real(0.5) * (Mi.sound_speed + Mj.sound_speed),
                                                  Real(0.5) * (rho_i + rho_j), m_j, approach, r2, eta2, F);
    Vec<D> a;
    if (normal) a = s * rij + s_visc * wall_normal_direction<D>(rij, P.boundary_normal[j]);
    else a = (s + s_visc) * rij;
    if (wall_function) return a + wall_friction_pair<D>(P, prm, vi, rho_i, mu_i, j, rij, F);
    return a;
  }
  if (free_slip_j) return s * rij;  // a free-slip wall exerts no shear
  if (wall_function) return s * rij + wall_friction_pair<D>(P, prm, vi, rho_i, mu_i, j, rij, F);
  // Pairs of an implicitly integrated material with itself or a boundary: the implicit viscous
  // update has them (sph/implicit_viscosity.hpp).
  if (implicit_pair(Mi, Mj, fluid_j)) return s * rij;
  const Real mu_j = !fluid_j ? mu_i : (P.effective_viscosity ? P.effective_viscosity[j] : Mj.dynamic_viscosity);
  return s * rij +
         pair::viscous_pair<D>(central_stress_pair(Mi, Mj, fluid_j), m_j, mu_i, mu_j, rho_i, rho_j, r2, eta2, F, rij)
             .apply(vij);
}

// Momentum (pressure gradient, viscosity, gravity) for fluid particles; walls get zero.
template <int D, class K, bool UniformH>
struct MomentumPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;

  TURBID_HD void operator()(std::uint32_t i) const {
    Vec<D> acc = Vec<D>::zero();
    if (P.kind[i] != std::uint8_t(Kind::fluid)) {
      P.acceleration[i] = acc;
      if (L.record) L.count[i] = L.stride + 1;  // no list for walls: their continuity searches the grid
      return;
    }
    const Vec<D> xi = P.position[i];
    const Vec<D> vi = P.velocity[i];
    const Real rho_i = P.density[i];
    const Real p_i = P.pressure[i];
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    const MaterialParams& Mi = prm.materials[P.material[i]];
    const Real mu_i = P.effective_viscosity ? P.effective_viscosity[i] : Mi.dynamic_viscosity;
    [[maybe_unused]] const bool artificial = prm.viscosity == Viscosity::artificial;  // the CPU lanes only
#if !defined(__CUDA_ARCH__)
    if constexpr (UniformH) {
      if (artificial && P.viscous_velocity == nullptr && P.shifting_velocity == nullptr && !prm.wall_function &&
          lanes(i, xi, vi, rho_i, p_i, Mi, acc)) {
        for (int k = 0; k < D; ++k) acc[k] += prm.gravity[k];
        P.acceleration[i] = acc;
        return;
      }
    }
#endif
    if (P.shifting_velocity) {
      // Particle shifting: grad C_i = sum_j V_j grad_i W_ij over all neighbours
      // (walls included, so a wall does not look like a free surface) and the position divergence.
      // The velocity gradient grad v_i = sum_j V_j (v_j - v_i) (x) grad_i W_ij gives the particle the
      // velocity of the place it is shifted to (first-order Taylor correction, Lind et al. 2012):
      // a += (u_s . grad) v, so shifting does not smear momentum across a shear layer.
      Vec<D> grad_c = Vec<D>::zero();
      Real div_r = 0;
      Real grad_v[D][D] = {};
      for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
        acc += momentum_pair<D, K, UniformH>(P, prm, vi, rho_i, p_i, h_i, Mi, mu_i, j, rij, r2);
        const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
        if (!UniformH && r2 >= Real(4) * h * h) return;
        const Real FV = K::f_inv(std::sqrt(r2), Real(1) / h) * P.mass[j] / P.density[j];
        grad_c += FV * rij;
        div_r -= FV * r2;
        const Vec<D> vji = viscous_velocity_of<D>(P, j) - vi;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) grad_v[a][b] += vji[a] * FV * rij[b];
      });
      const Vec<D> us = shifting_velocity(prm, h_i, vi, grad_c, div_r);
      P.shifting_velocity[i] = us;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) acc[a] += us[b] * grad_v[a][b];
    } else {
      for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
        acc += momentum_pair<D, K, UniformH>(P, prm, vi, rho_i, p_i, h_i, Mi, mu_i, j, rij, r2);
      });
    }
    for (int k = 0; k < D; ++k) acc[k] += prm.gravity[k];
    P.acceleration[i] = acc;
  }

  // u_s = -A h |v| grad C (Skillen et al. 2013); zero at a free surface (div r below the threshold),
  // where grad C points into the fluid and shifting would pull the surface inwards.
  TURBID_HD static Vec<D> shifting_velocity(const PhysicsParams& prm, Real h, const Vec<D>& v, const Vec<D>& grad_c,
                                            Real div_r) {
    if (div_r < prm.shifting_surface_threshold) return Vec<D>::zero();
    return (-prm.shifting_coefficient * h * std::sqrt(norm2(v))) * grad_c;
  }

  // CPU: the same sums (uniform h, artificial viscosity) in W independent lanes, so that the
  // compiler can evaluate W pairs at once with vector instructions; the lanes are added in a fixed
  // order, so results stay deterministic. Returns false (nothing done) if the neighbours do not fit.
  static constexpr int W = kLanes;
  static constexpr std::uint32_t kMaxNeighbours = kLaneNeighbours;
  bool lanes(std::uint32_t i, const Vec<D>& xi, const Vec<D>& vi, Real rho_i, Real p_i, const MaterialParams& Mi,
             Vec<D>& acc) const {
    std::uint32_t nb[kMaxNeighbours + W];
    LaneGeometry<D> g;
    const Real h = prm.smoothing_length;
    std::uint32_t m = 0;
    bool fits = true;
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real) {
      if (m < kMaxNeighbours) {
        g.set_r(m, rij);
        nb[m++] = j;
      } else {
        fits = false;
      }
    });
    if (!fits) return false;
    const std::uint32_t padded = (m + W - 1) / W * W;
    alignas(32) Real rho_j[kMaxNeighbours + W], p_j[kMaxNeighbours + W], m_j[kMaxNeighbours + W],
        c_j[kMaxNeighbours + W];
    // The viscosity acts along r_ij (along_r = 1, dir = 0) or, for a wall pair with the normal
    // approach, along r_ij's wall-normal part (along_r = 0, dir = that part): other pairs keep
    // the bits they had (x 1, + 0).
    alignas(32) Real along_r[kMaxNeighbours + W], dir[D][kMaxNeighbours + W];
    const Real c_i = Mi.sound_speed;
    // One sound speed for every material (and the walls'): no per-neighbour material lookups.
    const bool one_c = prm.uniform_sound_speed;
    for (std::uint32_t k = 0; k < padded; ++k) {
      const bool valid = k < m;
      const std::uint32_t j = valid ? nb[k] : i;
      if (!valid) g.set_pad(k, h);
      g.set_vr(k, P, vi, j);
      along_r[k] = Real(1);
      for (int a = 0; a < D; ++a) dir[a][k] = Real(0);
      if (prm.wall_viscosity_normal && valid && P.kind[j] != std::uint8_t(Kind::fluid)) {
        // The approach along the wall's normal and the force along it (momentum_pair): vr and
        // dir are read by the viscosity only.
        Vec<D> rij;
        for (int a = 0; a < D; ++a) rij[a] = g.r[a][k];
        g.vr[k] = wall_normal_approach<D>(vi - P.velocity[j], rij, P.boundary_normal[j]);
        const Vec<D> d = wall_normal_direction<D>(rij, P.boundary_normal[j]);
        for (int a = 0; a < D; ++a) dir[a][k] = d[a];
        along_r[k] = Real(0);
      }
      rho_j[k] = P.density[j];
      p_j[k] = P.pressure[j];
      m_j[k] = valid ? P.mass[j] : Real(0);
      c_j[k] = one_c ? c_i
                     : prm.materials[P.kind[j] == std::uint8_t(Kind::fluid) ? int(P.material[j]) : prm.wall_material]
                           .sound_speed;
    }
    const Real inv_h = Real(1) / h;
    const Real eta2 = kEta2Factor * h * h;
    const Real ah = prm.artificial_viscosity * h;
    Real sum[D][W] = {};
    for (std::uint32_t k0 = 0; k0 < padded; k0 += W) {
      for (int l = 0; l < W; ++l) {
        const std::uint32_t k = k0 + std::uint32_t(l);
        const Real r2 = g.r2(k);
        const Real F = K::f_inv(std::sqrt(r2), inv_h);
        const Real c_mean = Real(0.5) * (c_i + c_j[k]);
        const Real press = -(p_i + p_j[k]) / (rho_i * rho_j[k]);
        const Real vr = g.vr[k];
        const Real visc_full = ah * c_mean * vr / ((r2 + eta2) * Real(0.5) * (rho_i + rho_j[k]));
        const Real visc = vr < Real(0) ? visc_full : Real(0);
        const Real s = m_j[k] * F * (press + visc * along_r[k]), sv = m_j[k] * F * visc;
        for (int a = 0; a < D; ++a) sum[a][l] += s * g.r[a][k] + sv * dir[a][k];
      }
    }
    for (int a = 0; a < D; ++a) {
      Real t = 0;
      for (int l = 0; l < W; ++l) t += sum[a][l];
      acc[a] = t;
    }
    return true;
  }
};

}  // namespace turbid::sph
