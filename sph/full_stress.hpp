// The full viscous stress of implicit materials (issue #20 item 2), shared by all backends.
//
// Why: Morris' pair form is div(mu grad v). Where mu jumps by orders of magnitude across a yield
// surface in a flow that turns, the missing div(mu (grad v)^T) part is not small. Here the viscous
// force of a material with MaterialParams::full_stress (always integrated implicitly) comes from the
// dissipation function
//
//   R(u) = sum_{carriers i} V_i mu_i |D'_i|^2  +  1/2 sum_{stabilised pairs} c_ij |d_ij|^2,
//
//  - carriers: the full-stress fluid particles, and the boundary particles (walls, structures;
//    not free-slip walls) within a support of one of them, with the mean viscosity of those fluid
//    neighbours: a wall carries the stress of the fluid it bounds (without it the fluid's own
//    dissipation would treat the wall as a free surface and pull on the first rows);
//  - g_i = [sum_{j in F(i)} V_j (u_j - u_i) (x) grad_i W_ij] L_i: the velocity gradient (difference
//    form, renormalised by L_i = M_i^-1, M_i = sum_j V_j (x_j - x_i) (x) grad_i W_ij, so it is exact
//    for a linear field wherever the neighbourhood spans the space) over F(i): full-stress fluid and
//    boundary particles (not free-slip walls). Particles of other materials are not in F: a pair of
//    debris and water stays in the Laplacian pair form, explicit (harmonic mean: the softer side
//    sets the interface's stress, and the water sees no stiff term);
//  - D'_i = sym(g_i) - tr(g_i)/D I and tau_i = 2 mu_i D'_i, the deviatoric stress (mu_i of the last
//    rheology pass: the usual lagged linearisation of a generalised Newtonian fluid);
//  - d_ij = u_i - u_j - (g_i + g_j)/2 r_ij over the pairs of two carriers of which one is fluid: what
//    the pair's velocity difference has beyond the gradients' prediction. It is zero for any
//    quadratic field on a lattice and for rigid motion, so it does not change the stress of a
//    resolved flow; it damps the modes a gradient cannot see (a field that alternates from particle
//    to particle has zero SPH gradient), with Morris' pair weight c_ij = V_i V_j 2 mu_ij |F| r^2 /
//    (r^2 + eta^2) (mu_ij harmonic).
//
// The force on particle k is -dR/du_k. With P_i = dR/dg_i = V_i tau_i - 1/2 sum_j c_ij d_ij (x) r_ij
// and Q_i = P_i L_i (L symmetric),
//
//   dR/du_k = sum_j c_kj d_kj  +  V_k sum_{i in F(k)} Q_i grad_i W_ik  -  Q_k sum_{l in F(k)} V_l grad_k W_kl,
//
// which for c = 0 and L = I is the familiar symmetric divergence (1/rho_k) sum_j V_j (tau_k + tau_j)
// grad_k W_kj (Shao & Lo 2003). R is a sum of squares of linear functions of u, so its Hessian is
// symmetric positive semidefinite: the implicit update (sph/implicit_viscosity.hpp) stays symmetric
// positive definite and the viscous force never feeds energy into any mode, whatever the particle
// arrangement. R does not change when every velocity is shifted by a constant, so the dR/du of all
// particles sum to zero: the fluid's momentum change and the structures' reactions -dR/du_b (walls'
// are not booked) cancel to rounding.
//
// Three gathers per evaluation (gradient, stress, force), one evaluation per conjugate-gradient
// iteration; the stencil of a divergence of gradients reaches 4h.
#pragma once
#include <cmath>
#include <cstdint>

#include "sph/config.hpp"
#include "sph/passes.hpp"

namespace turbid::sph {

template <int D>
struct Mat {
  Real c[D][D];
  TURBID_HD static Mat zero() {
    Mat m;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) m.c[a][b] = Real(0);
    return m;
  }
  TURBID_HD static Mat identity() {
    Mat m = zero();
    for (int a = 0; a < D; ++a) m.c[a][a] = Real(1);
    return m;
  }
  // M v
  TURBID_HD Vec<D> operator*(const Vec<D>& v) const {
    Vec<D> r;
    for (int a = 0; a < D; ++a) {
      Real s = 0;
      for (int b = 0; b < D; ++b) s += c[a][b] * v[b];
      r[a] = s;
    }
    return r;
  }
};

// a b (a as a plain array, as the passes accumulate it).
template <int D>
TURBID_HD inline Mat<D> product(const Real (&a)[D][D], const Mat<D>& b) {
  Mat<D> out;
  for (int r = 0; r < D; ++r)
    for (int c = 0; c < D; ++c) {
      Real s = 0;
      for (int k = 0; k < D; ++k) s += a[r][k] * b.c[k][c];
      out.c[r][c] = s;
    }
  return out;
}

// Whether fluid particle i has a full-stress implicit material.
template <int D>
TURBID_HD inline bool full_stress_particle(const ParticleView<D>& P, const PhysicsParams& prm, std::uint32_t i) {
  if (P.kind[i] != std::uint8_t(Kind::fluid)) return false;
  const MaterialParams& M = prm.materials[P.material[i]];
  return M.implicit_viscosity && M.full_stress;
}

// Whether j is in F(i), the neighbours of a stress carrier's gradient: a full-stress fluid particle,
// or a boundary particle that is not a free-slip wall.
template <int D>
TURBID_HD inline bool full_stress_neighbour(const ParticleView<D>& P, const PhysicsParams& prm, std::uint32_t j) {
  if (P.kind[j] == std::uint8_t(Kind::fluid)) return full_stress_particle<D>(P, prm, j);
  return !(P.free_slip && P.free_slip[j]);
}

// Calls f(j, r_ij, F_ij, h_ij, boundary_j) for every j in F(i).
template <int D, class K, bool UniformH, class Visit>
TURBID_HD inline void for_each_full_stress_neighbour(const ParticleView<D>& P, const GridView<D>& G,
                                                     const NeighbourList& L, const PhysicsParams& prm,
                                                     std::uint32_t i, Visit&& f) {
  const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
  for_each_neighbour<D>(P, G, L, prm, i, P.position[i], [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
    const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
    if (!UniformH && r2 >= Real(4) * h * h) return;
    if (!full_stress_neighbour<D>(P, prm, j)) return;
    f(j, rij, K::f_inv(std::sqrt(r2), Real(1) / h), h, P.kind[j] != std::uint8_t(Kind::fluid));
  });
}

// The velocity u_j of an evaluation: x for system particles (zero when x is null), the velocity a
// boundary particle shows viscous terms when the known velocities are included, else zero.
template <int D>
TURBID_HD inline Vec<D> full_stress_velocity(const ParticleView<D>& P, const Vec<D>* x, bool known, std::uint32_t j,
                                             bool boundary) {
  if (boundary) return known ? viscous_velocity_of<D>(P, j) : Vec<D>::zero();
  return x ? x[j] : Vec<D>::zero();
}

// Per solve: the carriers' viscosity mu_c (0: not a carrier) and renormalisation L = M^-1.
// Carriers are the full-stress particles (their mu_eff of the last rheology pass) and the boundary
// particles in F of at least one of them (the mean of those neighbours' mu weighted by V |F|): a
// wall carries the stress of the fluid it bounds, so the fluid next to it sees no spurious
// traction (without it the dissipation of the fluid alone would treat the wall as a free surface).
// M_i = sum_{j in F(i)} V_j (x_j - x_i) (x) grad_i W_ij (symmetric); L = I where M is nearly
// singular (det below 1e-3: few neighbours).
template <int D, class K, bool UniformH>
struct FullStressSetupPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  Real* carrier_mu;
  Mat<D>* renorm;

  TURBID_HD void operator()(std::uint32_t i) const {
    renorm[i] = Mat<D>::identity();
    carrier_mu[i] = Real(0);
    const bool fluid = P.kind[i] == std::uint8_t(Kind::fluid);
    if (fluid ? !full_stress_particle<D>(P, prm, i) : !full_stress_neighbour<D>(P, prm, i)) return;
    Real m[D][D] = {};
    Real mu_sum = 0, w_sum = 0;
    for_each_full_stress_neighbour<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const Vec<D>& rij, Real F, Real, bool boundary) {
      const Real VF = -F * P.mass[j] / P.density[j];
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) m[a][b] += VF * rij[a] * rij[b];
      if (!fluid && !boundary) {
        mu_sum += VF * (P.effective_viscosity ? P.effective_viscosity[j] : prm.materials[P.material[j]].dynamic_viscosity);
        w_sum += VF;
      }
    });
    if (fluid) {
      carrier_mu[i] = P.effective_viscosity ? P.effective_viscosity[i] : prm.materials[P.material[i]].dynamic_viscosity;
    } else {
      if (!(w_sum > Real(0))) return;  // no full-stress fluid near: not a carrier
      carrier_mu[i] = mu_sum / w_sum;
    }
    Mat<D> inv = Mat<D>::identity();
    if constexpr (D == 2) {
      const Real det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
      if (det > Real(1e-3)) {
        inv.c[0][0] = m[1][1] / det;
        inv.c[1][1] = m[0][0] / det;
        inv.c[0][1] = -m[0][1] / det;
        inv.c[1][0] = -m[1][0] / det;
      }
    } else {
      const Real c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
      const Real c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
      const Real c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
      const Real det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
      if (det > Real(1e-3)) {
        const Real s = Real(1) / det;
        inv.c[0][0] = c00 * s;
        inv.c[1][0] = c01 * s;
        inv.c[2][0] = c02 * s;
        inv.c[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * s;
        inv.c[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * s;
        inv.c[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * s;
        inv.c[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * s;
        inv.c[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * s;
        inv.c[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * s;
      }
    }
    renorm[i] = inv;
  }
};

// The share of Morris' pair weight the stabilising term takes.
constexpr Real kFullStressStabilisation = Real(1);

// The stabilising pair weight c_ij = V_i V_j 2 mu_ij |F| r^2 / (r^2 + eta^2) (Morris' pair weight,
// mu_ij the harmonic mean of the carriers' viscosities).
template <int D>
TURBID_HD inline Real full_stress_weight(const ParticleView<D>& P, const Real* carrier_mu, std::uint32_t i,
                                         std::uint32_t j, Real F, Real r2, Real h) {
  const Real Vi = P.mass[i] / P.density[i];
  const Real Vj = P.mass[j] / P.density[j];
  return kFullStressStabilisation * Vi * Vj * pair::pair_viscosity_sum(carrier_mu[i], carrier_mu[j]) * (-F) * r2 /
         (r2 + kEta2Factor * h * h);
}

// g_i = [sum_{j in F(i)} V_j (u_j - u_i) (x) grad_i W_ij] L_i for carriers (zero for the others).
template <int D, class K, bool UniformH>
struct FullStressGradientPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  const Vec<D>* x;  // null: zero
  bool known;       // include the boundary particles' velocities
  const Real* carrier_mu;
  const Mat<D>* renorm;
  Mat<D>* grad;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (carrier_mu[i] == Real(0)) {
      grad[i] = Mat<D>::zero();
      return;
    }
    const Vec<D> ui = full_stress_velocity<D>(P, x, known, i, P.kind[i] != std::uint8_t(Kind::fluid));
    Real g[D][D] = {};
    for_each_full_stress_neighbour<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const Vec<D>& rij, Real F, Real, bool boundary) {
      const Vec<D> du = full_stress_velocity<D>(P, x, known, j, boundary) - ui;
      const Real VF = F * P.mass[j] / P.density[j];
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) g[a][b] += du[a] * VF * rij[b];
    });
    grad[i] = product<D>(g, renorm[i]);
  }
};

// Q_i = P_i L_i with P_i = V_i 2 mu_c,i D'(g_i) - 1/2 sum_j c_ij d_ij (x) r_ij, and the pair part of
// dR/du_i, sum_j c_ij d_ij, for carriers; the pair sums run over the stabilised pairs, those of a
// carrier with a carrier where one of the two is fluid (two boundary particles' velocities are
// known: their pair does not enter R), with d_ij = u_i - u_j - (g_i + g_j)/2 r_ij.
template <int D, class K, bool UniformH>
struct FullStressStressPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  const Vec<D>* x;
  bool known;
  const Real* carrier_mu;
  const Mat<D>* renorm;
  const Mat<D>* grad;
  Mat<D>* q;
  Vec<D>* direct;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (carrier_mu[i] == Real(0)) {
      q[i] = Mat<D>::zero();
      direct[i] = Vec<D>::zero();
      return;
    }
    const bool fluid_i = P.kind[i] == std::uint8_t(Kind::fluid);
    const Mat<D> gi = grad[i];
    const Real Vi = P.mass[i] / P.density[i];
    Real trace = 0;
    for (int a = 0; a < D; ++a) trace += gi.c[a][a];
    Real p[D][D];
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b)
        p[a][b] = Vi * carrier_mu[i] * (gi.c[a][b] + gi.c[b][a] - (a == b ? Real(2) * trace / Real(D) : Real(0)));
    const Vec<D> ui = full_stress_velocity<D>(P, x, known, i, !fluid_i);
    Vec<D> dir = Vec<D>::zero();
    for_each_full_stress_neighbour<D, K, UniformH>(P, G, L, prm, i, [&](std::uint32_t j, const Vec<D>& rij, Real F, Real h, bool boundary) {
      if (!fluid_i && boundary) return;   // two boundary particles
      if (carrier_mu[j] == Real(0)) return;
      const Real c = full_stress_weight<D>(P, carrier_mu, i, j, F, dot(rij, rij), h);
      const Vec<D> d = (ui - full_stress_velocity<D>(P, x, known, j, boundary)) - Real(0.5) * (gi * rij + grad[j] * rij);
      dir += c * d;
      for (int a = 0; a < D; ++a)
        for (int b = 0; b < D; ++b) p[a][b] -= Real(0.5) * c * d[a] * rij[b];
    });
    q[i] = product<D>(p, renorm[i]);
    direct[i] = dir;
  }
};

// dR/du_k for fluid carriers, and with `structures` for every structure particle that is not
// free-slip (zero for the others):
//   dR/du_k = direct_k + V_k sum_{i in F(k), carrier} Q_i grad_i W_ik - Q_k sum_{l in F(k)} V_l grad_k W_kl
// (direct and Q are zero for a particle that is not a carrier: a structure particle deeper than the
// carriers still enters their gradients). A fluid carrier's acceleration is -dR/du_k / m_k; a
// structure particle's reaction force -dR/du_k. Over all particles the dR/du sum to zero.
template <int D, class K, bool UniformH>
struct FullStressForcePass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  const Real* carrier_mu;
  const Mat<D>* q;
  const Vec<D>* direct;
  bool structures;
  Vec<D>* dR;

  TURBID_HD void operator()(std::uint32_t k) const {
    const bool fluid = P.kind[k] == std::uint8_t(Kind::fluid);
    const bool wanted = fluid ? carrier_mu[k] != Real(0)
                              : structures && P.kind[k] == std::uint8_t(Kind::structure) &&
                                    full_stress_neighbour<D>(P, prm, k);
    if (!wanted) {
      dR[k] = Vec<D>::zero();
      return;
    }
    const Real Vk = P.mass[k] / P.density[k];
    Vec<D> from_others = Vec<D>::zero();  // sum_i Q_i grad_i W_ik = -sum_i F Q_i r_ki
    Vec<D> own = Vec<D>::zero();          // sum_l V_l grad_k W_kl = sum_l V_l F r_kl
    for_each_full_stress_neighbour<D, K, UniformH>(P, G, L, prm, k, [&](std::uint32_t j, const Vec<D>& rkj, Real F, Real, bool) {
      own += (F * P.mass[j] / P.density[j]) * rkj;
      if (carrier_mu[j] != Real(0)) from_others -= F * (q[j] * rkj);
    });
    dR[k] = direct[k] + Vk * from_others - q[k] * own;
  }
};

}  // namespace turbid::sph
