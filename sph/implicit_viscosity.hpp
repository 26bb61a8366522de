// Implicit (backward Euler) laminar viscosity for stiff materials, shared by all backends.
//
// Why: a yield-stress material's regularised viscosity reaches m tau_y + K at rest (1e5 Pa s for
// the landslide's debris); the explicit viscous limit dt <= 0.125 h^2 rho / mu would then be ~100
// times below the acoustic one. Capping mu at what the explicit limit allows made the material
// depend on h (issue #20). Instead the viscous terms of such materials are integrated implicitly:
// with the pair operator T_ij of pair::ViscousPair (Morris' s_ij I, or the central form
// k_ij r_ij r_ij^T; negative semidefinite and symmetric in i, j),
//
//   v_i - dt sum_j T_ij (v_i - v_j) = v*_i          (v* after the half-kick of the explicit forces)
//
// over the pairs implicit_pair() selects: i of an implicit material with j of an implicit
// material (unknown v_j) or a boundary particle (known: the velocity it shows viscous terms). The
// matrix is symmetric in the mass-weighted inner product (m_i T_ij = m_j T_ji: pair h, harmonic
// viscosity and kernel are symmetric) and positive definite (identity minus dt times a negative
// semidefinite operator), so the backend solves it with conjugate gradients preconditioned by its
// diagonal (per component). Viscosities are those of the last rheology pass
// (lagged one step, the usual linearisation of a generalised Newtonian fluid).
//
// The update itself is the explicit pair sum evaluated with the solution x:
//   v_i = v*_i + dt sum_j T_ij (x_i - x_j),
// which equals x_i up to the solver's residual and conserves momentum to rounding (the pair terms
// are antisymmetric), whatever the tolerance. A structure particle b gets the exact reaction,
// -sum_i m_i T_ib (x_i - v_b) (ViscousReactionPass; StructureForcePass adds it to b's force).
#pragma once
#include <cmath>
#include <cstdint>

#include "sph/config.hpp"
#include "sph/full_stress.hpp"
#include "sph/pair_physics.hpp"
#include "sph/passes.hpp"

namespace turbid::sph {

// Whether fluid particle i takes part in the implicit system.
template <int D>
TURBID_HD inline bool in_viscous_system(const ParticleView<D>& P, const PhysicsParams& prm, std::uint32_t i) {
  return P.kind[i] == std::uint8_t(Kind::fluid) && prm.materials[P.material[i]].implicit_viscosity;
}

// Calls f(j, T_ij, boundary_j) for every implicit pair of system particle i in the pair form (see
// above); the pairs of a full-stress particle with F(i) are left to full_stress.hpp.
template <int D, class K, bool UniformH, class Visit>
TURBID_HD inline void for_each_implicit_pair(const ParticleView<D>& P, const GridView<D>& G, const NeighbourList& L,
                                             const PhysicsParams& prm, std::uint32_t i, Visit&& f) {
  const Vec<D> xi = P.position[i];
  const Real rho_i = P.density[i];
  const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
  const MaterialParams& Mi = prm.materials[P.material[i]];
  const Real mu_i = P.effective_viscosity ? P.effective_viscosity[i] : Mi.dynamic_viscosity;
  const bool full_i = full_stress_particle<D>(P, prm, i);
  for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
    const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
    if (!UniformH && r2 >= Real(4) * h * h) return;
    const bool fluid_j = P.kind[j] == std::uint8_t(Kind::fluid);
    if (!fluid_j && P.free_slip && P.free_slip[j]) return;  // a free-slip wall exerts no shear
    const MaterialParams& Mj = prm.materials[fluid_j ? int(P.material[j]) : prm.wall_material];
    if (!implicit_pair(Mi, Mj, fluid_j)) return;
    if (full_i && full_stress_neighbour<D>(P, prm, j)) return;  // in the full-stress form (full_stress.hpp)
    const Real mu_j = !fluid_j ? mu_i : (P.effective_viscosity ? P.effective_viscosity[j] : Mj.dynamic_viscosity);
    const Real F = K::f_inv(std::sqrt(r2), Real(1) / h);
    f(j,
      pair::viscous_pair<D>(central_stress_pair(Mi, Mj, fluid_j), P.mass[j], mu_i, mu_j, rho_i, P.density[j], r2,
                            kEta2Factor * h * h, F, rij),
      !fluid_j);
  });
}

// Whether particle i is in the system: its diagonal is at least 1 then, 0 otherwise.
template <int D>
TURBID_HD inline bool in_system(const Vec<D>* diag, std::uint32_t i) {
  return diag[i][0] != Real(0);
}

// The system's diagonal 1 - dt sum_j diag(T_ij) (per component) and right-hand side
// v*_i - dt sum_boundary T_ij v_j for system particles; diagonal 0 (not in the system) for the others.
template <int D, class K, bool UniformH>
struct ViscousSystemPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  Real dt;
  Vec<D>* diag;
  Vec<D>* rhs;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (!in_viscous_system<D>(P, prm, i)) {
      diag[i] = Vec<D>::zero();
      rhs[i] = Vec<D>::zero();
      return;
    }
    Vec<D> sum = Vec<D>::zero();
    Vec<D> known = Vec<D>::zero();
    for_each_implicit_pair<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const pair::ViscousPair<D>& T, bool boundary) {
      sum += T.diagonal();
      if (boundary) known += T.apply(viscous_velocity_of<D>(P, j));
    });
    // The full-stress part's diagonal, estimated as twice Morris' (stress and pair residual terms):
    // a preconditioner needs only be positive.
    if (full_stress_particle<D>(P, prm, i)) {
      Real c_sum = 0;
      const Real mu_i = P.effective_viscosity ? P.effective_viscosity[i] : prm.materials[P.material[i]].dynamic_viscosity;
      for_each_full_stress_neighbour<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const Vec<D>& rij, Real F, Real h, bool) {
        const Real r2 = dot(rij, rij);
        c_sum += P.mass[j] / P.density[j] * (-F) * r2 / (r2 + kEta2Factor * h * h);
      });
      for (int a = 0; a < D; ++a) sum[a] -= Real(4) * mu_i * c_sum / P.density[i];
    }
    Vec<D> d;
    for (int a = 0; a < D; ++a) d[a] = Real(1) - dt * sum[a];
    diag[i] = d;
    rhs[i] = P.velocity[i] - dt * known;
  }
};

// out_i = (A x)_i = x_i - dt sum_j T_ij (x_i - x_j) + dt sum_boundary T_ij v_j - dt a^full_i(x), i.e.
// A x without the known boundary velocities, for system particles; 0 for the others. a^full: the
// full-stress acceleration -dR/du / m of x with the boundary velocities left out (full: dR/du; null:
// none).
template <int D, class K, bool UniformH>
struct ViscousApplyPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  Real dt;
  const Vec<D>* diag;
  const Vec<D>* x;
  const Vec<D>* full;
  Vec<D>* out;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (!in_system<D>(diag, i)) {
      out[i] = Vec<D>::zero();
      return;
    }
    // (1 - dt sum_j diag(T_ij)) x_i + dt sum_fluid T_ij x_j, minus dt times the off-diagonal part of
    // sum_j T_ij x_i (central pairs only); the same operations, in the same order, as before the
    // pair operator could be a tensor, so a Laplacian-form run keeps its bits.
    const Vec<D> xi = x[i];
    Vec<D> dsum = Vec<D>::zero();
    Vec<D> off = Vec<D>::zero();
    Vec<D> cross = Vec<D>::zero();
    bool central = false;
    for_each_implicit_pair<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const pair::ViscousPair<D>& T, bool boundary) {
      const Vec<D> d = T.diagonal();
      dsum += d;
      if (!boundary) off += T.apply(x[j]);
      if (T.central) {
        central = true;
        Vec<D> c = T.apply(xi);
        for (int a = 0; a < D; ++a) c[a] -= d[a] * xi[a];
        cross += c;
      }
    });
    Vec<D> o;
    for (int a = 0; a < D; ++a) o[a] = (Real(1) - dt * dsum[a]) * xi[a];
    o += dt * off;
    if (central) o -= dt * cross;
    if (full) o += (dt / P.mass[i]) * full[i];
    out[i] = o;
  }
};

// The update: v_i = v*_i + dt [sum_j T_ij (x_i - x_j) + a^full_i(x)] for system particles (boundary
// j with the velocity they show viscous terms; a^full with them). Reads x and boundary velocities,
// writes fluid velocities.
template <int D, class K, bool UniformH>
struct ViscousUpdatePass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  Real dt;
  const Vec<D>* diag;
  const Vec<D>* x;
  const Vec<D>* full;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (!in_system<D>(diag, i)) return;
    const Vec<D> xi = x[i];
    Vec<D> a = Vec<D>::zero();
    for_each_implicit_pair<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const pair::ViscousPair<D>& T, bool boundary) {
      a += T.apply(xi - (boundary ? viscous_velocity_of<D>(P, j) : x[j]));
    });
    if (full) a -= (Real(1) / P.mass[i]) * full[i];
    P.velocity[i] += dt * a;
  }
};

// Structure particle b: the reaction of the implicit viscous force its fluid neighbours got,
// -sum_i m_i T_ib (x_i - v_b) [N/m in 2D, N in 3D], with T_ib evaluated from the same arguments as
// for_each_implicit_pair gives it on i's side, times this update's share of the fluid step.
// The step's load on b (what the structure force passes add to b's force until the next step's
// first update) is the first half-step update's share plus the second half-step update's share of
// the step before: the first update writes load = pending + share f, the second pending = share f.
// Force passes between steps (a split's) so see the same viscous load as the step's own.
template <int D, class K, bool UniformH>
struct ViscousReactionPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  const Vec<D>* diag;
  const Vec<D>* x;
  Real share;        // this update's share of the fluid step (its dt / the step's dt)
  bool first_half;   // the step's first update (else its second)
  const Vec<D>* full_dR = nullptr;  // dR/du of the full-stress evaluation at x (null: none)

  TURBID_HD void operator()(std::uint32_t b) const {
    Vec<D> f = Vec<D>::zero();
    int c[D] = {};
    if (P.kind[b] == std::uint8_t(Kind::structure) && !(P.free_slip && P.free_slip[b]) && G.cell_of(P.position[b], c) &&
        G.fluid_near(c)) {
      const Vec<D> vb = viscous_velocity_of<D>(P, b);
      for_each_neighbour<D>(P, G, NeighbourList{}, prm, b, P.position[b], [&](std::uint32_t i, const Vec<D>& rbi, Real r2) {
        if (!in_system<D>(diag, i)) return;  // not an implicit fluid particle
        if (full_stress_particle<D>(P, prm, i)) return;  // its pair with b is in the full-stress form
        const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
        const Real h = pair_h<D, K>(P, prm, UniformH, h_i, b);
        if (!UniformH && r2 >= Real(4) * h * h) return;
        const MaterialParams& Mi = prm.materials[P.material[i]];
        const Real mu_i = P.effective_viscosity ? P.effective_viscosity[i] : Mi.dynamic_viscosity;
        const Real F = K::f_inv(std::sqrt(r2), Real(1) / h);
        const pair::ViscousPair<D> T = pair::viscous_pair<D>(central_stress_pair(Mi, Mi, false), P.mass[b], mu_i, mu_i,
                                                             P.density[i], P.density[b], r2, kEta2Factor * h * h, F,
                                                             Real(-1) * rbi);
        f -= P.mass[i] * T.apply(x[i] - vb);
      });
    }
    if (full_dR && P.kind[b] == std::uint8_t(Kind::structure)) f -= full_dR[b];
    if (first_half) P.viscous_load[b] = P.viscous_pending[b] + share * f;
    else P.viscous_pending[b] = share * f;
  }
};

}  // namespace turbid::sph
