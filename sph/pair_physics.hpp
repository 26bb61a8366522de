// Per-pair terms of the weakly compressible δ-SPH equations, shared by all backends.
// Notation (physics.md C): r_ij = x_i - x_j, grad_i W_ij = F_ij r_ij with F = (1/r) dW/dr < 0,
// V_j = m_j / rho_j, v_ij = v_i - v_j.
#pragma once
#include <cmath>

#include "sph/config.hpp"
#include "sph/vec.hpp"

namespace turbid::sph::pair {

// Continuity in the volume form suited to several materials (Colagrossi & Landrini 2003, C10):
// D rho_i / Dt += rho_i V_j v_ij . grad_i W_ij
TURBID_HD inline Real continuity(Real rho_i, Real vol_j, Real vij_dot_rij, Real F) {
  return rho_i * vol_j * vij_dot_rij * F;
}

// Molteni & Colagrossi (2009) diffusion, psi_ij = 2 (rho_j - rho_i) r_ji / r^2 (C3, first term):
// delta h c0 psi . grad_i W V_j = delta h c0 * 2 (rho_i - rho_j) F V_j.
TURBID_HD inline Real diffusion_molteni(Real delta_h_c0, Real rho_i, Real rho_j, Real vol_j, Real F) {
  return delta_h_c0 * Real(2) * (rho_i - rho_j) * F * vol_j;
}

// Antuono et al. (2010) δ-SPH with renormalised density gradients (C3):
// psi . grad_i W = 2 (rho_i - rho_j) F - F (grad_rho_i + grad_rho_j) . r_ij
template <int D>
TURBID_HD inline Real diffusion_antuono(Real delta_h_c0, Real rho_i, Real rho_j, const Vec<D>& grad_i,
                                        const Vec<D>& grad_j, const Vec<D>& rij, Real vol_j, Real F) {
  return delta_h_c0 * F * vol_j * (Real(2) * (rho_i - rho_j) - dot(grad_i + grad_j, rij));
}

// The hydrostatic density difference rho^H = rho_j - rho_i expected between two points of one
// material at rest, from g . r_ij: rho0 [(1 + x)^(1/gamma) - 1] with x = -rho0 g.r_ij / B, to second
// order in x (|x| <= 2h gamma g / c0^2 < 1e-2 for c0 >= 10 sqrt(gH); error below 1e-6 rho0).
// hydro_k = rho0 / B.
TURBID_HD inline Real hydrostatic_difference(Real rho0, Real inv_gamma, Real hydro_k, Real g_dot_rij) {
  const Real x = -hydro_k * g_dot_rij;
  return rho0 * inv_gamma * x * (Real(1) + Real(0.5) * (inv_gamma - Real(1)) * x);
}

// Fourtakas et al. (2019) diffusion of the dynamic density only (C4): the hydrostatic density
// difference rho^H_ij = rho0 [(1 + rho0 g (z_i - z_j) / B)^(1/gamma) - 1] is removed first.
// Sign: diffusive when rho_j - rho_i exceeds the hydrostatic difference.
TURBID_HD inline Real diffusion_fourtakas(Real delta_2h_c0, Real rho_i, Real rho_j, Real rho_h_ij, Real r2,
                                          Real eta2, Real vol_j, Real F) {
  return -delta_2h_c0 * ((rho_j - rho_i) - rho_h_ij) * F * r2 / (r2 + eta2) * vol_j;
}

// Pressure acceleration, symmetric form -m_j (p_i + p_j)/(rho_i rho_j) grad_i W (C10, DualSPHysics):
// returns the scalar s so that a_i += s r_ij. Antisymmetric in i, j: momentum is conserved.
TURBID_HD inline Real pressure(Real m_j, Real p_i, Real p_j, Real rho_i, Real rho_j, Real F) {
  return -m_j * (p_i + p_j) / (rho_i * rho_j) * F;
}

// Monaghan (1992) artificial viscosity, active for approaching pairs: returns s with a_i += s r_ij.
// Pi_ij = -alpha c_mean mu_ij / rho_mean with mu_ij = h v_ij.r_ij / (r^2 + eta^2), folded into one
// division.
TURBID_HD inline Real artificial_viscosity(Real alpha, Real h, Real c_mean, Real rho_mean, Real m_j,
                                           Real vij_dot_rij, Real r2, Real eta2, Real F) {
  if (vij_dot_rij >= Real(0)) return Real(0);
  return m_j * alpha * c_mean * h * vij_dot_rij * F / ((r2 + eta2) * rho_mean);
}

// Wall function (docs/choices.md, "Wall friction"): the squared friction velocity u*^2 = tau_w / rho of a wall
// under fluid sliding at tangential speed u_t (relative to the wall) at distance y from its
// surface, kinematic viscosity nu, roughness length z_r = k_s / 30 (0: hydraulically smooth).
// The larger of the viscous sublayer's u*^2 = nu u_t / y and the log law's
//   u_t / u* = ln(y / z0) / kappa,  z0 = nu / (E u*) + z_r   (kappa = 0.41, E = 9.8),
// which meet near y+ = 11 for a smooth wall and give u+ = ln(E y+) / kappa above it. The log law
// is solved by fixed-point iteration (the log's argument varies slowly: 6 iterations settle it to
// 1e-4 relative for 11 < y+ < 1e5); ln(y / z0) is held at 1 or more, where the law is invalid
// (y within the roughness) and the sublayer or a u+ of 1 / kappa bounds the stress.
TURBID_HD inline Real wall_friction_velocity2(Real u_t, Real y, Real nu, Real z_r) {
  constexpr Real kappa = Real(0.41);
  constexpr Real E = Real(9.8);
  const Real laminar = nu * u_t / y;
  if (u_t <= Real(0)) return Real(0);
  // Start from u+ = 20, a typical value (and a positive one where nu = 0).
  Real us = std::sqrt(laminar);
  us = us > Real(0.05) * u_t ? us : Real(0.05) * u_t;
  for (int it = 0; it < 6; ++it) {
    const Real z0 = nu / (E * us) + z_r;
    Real l = std::log(y / z0);
    l = l < Real(1) ? Real(1) : l;
    us = kappa * u_t / l;
  }
  const Real log_law = us * us;
  return log_law > laminar ? log_law : laminar;
}

// Twice the viscosity of a pair, 2 mu_ij: the harmonic mean mu_ij = 2 mu_i mu_j / (mu_i + mu_j)
// (Hu & Adams 2006, physics.md C10), which lets the less viscous side set the shear stress across
// an interface, as for layers in series. Equal viscosities give mu_i + mu_j, bit for bit.
TURBID_HD inline Real pair_viscosity_sum(Real mu_i, Real mu_j) {
  if (mu_i == mu_j) return mu_i + mu_j;
  const Real sum = mu_i + mu_j;
  return sum > Real(0) ? Real(4) * mu_i * mu_j / sum : Real(0);
}

// Morris, Fox & Zhu (1997) laminar viscosity: a_i += s v_ij with
// s = m_j 2 mu_ij r_ij . grad_i W / (rho_i rho_j (r^2 + eta^2)). With a viscosity per particle
// (generalised Newtonian rheology) this is the SPH form of div(mu grad v).
TURBID_HD inline Real laminar_viscosity(Real m_j, Real mu_i, Real mu_j, Real rho_i, Real rho_j, Real r2, Real eta2,
                                        Real F) {
  return m_j * pair_viscosity_sum(mu_i, mu_j) * F * r2 / (rho_i * rho_j * (r2 + eta2));
}

// The laminar viscous term of one pair as an operator on the relative velocity v_ij: a_i += apply(v_ij).
//  - Laplacian form (Morris et al. 1997): apply(v) = s v with s = laminar_viscosity(...), the SPH
//    form of div(mu grad v).
//  - Central form: apply(v) = k (r_ij . v) r_ij with k = (D + 2) m_j 2 mu_ij F / (rho_i rho_j
//    (r^2 + eta^2)), a pair force along r_ij (the central member of Espanol & Revenga's 2003
//    family). With the kernel's isotropic fourth moment its continuum limit is the divergence of
//      mu (grad v + grad v^T) + mu (div v) I,
//    the full deviatoric stress 2 mu D' plus a bulk viscosity zeta = (1 + 2/D) mu; it conserves
//    angular momentum and gives a rigid rotation no force. On a lattice the fourth moment is not
//    isotropic: a shear along a lattice axis sees a viscosity 5% (h = 2 dx) to 20% (h = 1.3 dx)
//    low (docs/choices.md), which is why it is not the default.
// Both are symmetric in i, j and negative semidefinite (s <= 0, k <= 0), which the implicit update
// (sph/implicit_viscosity.hpp) relies on; diagonal() is the pair's contribution to d a_i / d v_i.
template <int D>
struct ViscousPair {
  Real k = 0;
  Vec<D> r = Vec<D>::zero();
  bool central = false;
  TURBID_HD Vec<D> apply(const Vec<D>& v) const { return central ? (k * dot(r, v)) * r : k * v; }
  TURBID_HD Vec<D> diagonal() const {
    Vec<D> d;
    for (int a = 0; a < D; ++a) d[a] = central ? k * r[a] * r[a] : k;
    return d;
  }
};

template <int D>
TURBID_HD inline ViscousPair<D> viscous_pair(bool central, Real m_j, Real mu_i, Real mu_j, Real rho_i, Real rho_j,
                                             Real r2, Real eta2, Real F, const Vec<D>& rij) {
  ViscousPair<D> p;
  p.central = central;
  if (central) {
    p.k = Real(D + 2) * m_j * pair_viscosity_sum(mu_i, mu_j) * F / (rho_i * rho_j * (r2 + eta2));
    p.r = rij;
  } else {
    p.k = laminar_viscosity(m_j, mu_i, mu_j, rho_i, rho_j, r2, eta2, F);
  }
  return p;
}

}  // namespace turbid::sph::pair
