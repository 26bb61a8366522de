// The conjugate-gradient solve of the implicit viscous system (implicit_viscosity.hpp), written
// once for every backend: the algorithm is here, the per-particle steps are TURBID_HD functors,
// and a backend supplies only how a pass runs over the particles and how a dot product is summed
// (Exec::run(n, f) and Exec::sum(n, f) -> double). The CPU sums in blocks of fixed order (the same
// bits for any thread count); the device backend in a Thrust reduction (the last bits may differ,
// and so, rarely, the iteration count by one).
//
// Jacobi-preconditioned (per component), in the inner product weighted by particle mass, in which
// the system is symmetric; it starts from the current velocities.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "sph/backend.hpp"
#include "sph/full_stress.hpp"
#include "sph/implicit_viscosity.hpp"

namespace turbid::sph {

// The solve's work arrays, n each (the backend owns them).
template <int D>
struct ViscousWork {
  Vec<D>* x = nullptr;  // the solution
  Vec<D>* r = nullptr;  // the residual
  Vec<D>* z = nullptr;  // the preconditioned residual
  Vec<D>* p = nullptr;  // the search direction
  Vec<D>* q = nullptr;  // the operator applied to p
  Vec<D>* diag = nullptr;
  Vec<D>* direct = nullptr;   // the full stress's direct part (full_stress.hpp)
  Vec<D>* full_dR = nullptr;  // the full stress's dR/du, with the full-stress form only
  Mat<D>* fs[3] = {nullptr, nullptr, nullptr};  // renormalisation, gradient, Q (full stress only)
  Real* carrier = nullptr;                      // full stress only

  // The arrays laid out in blocks of `stride` particles: `vectors` holds the eight vector arrays
  // above in their order, `tensors` (null without the full stress) the three tensor arrays, and
  // `carrier_mu` the carriers' viscosity.
  static ViscousWork over(Vec<D>* vectors, Mat<D>* tensors, Real* carrier_mu, std::size_t stride) {
    ViscousWork w;
    Vec<D>** v[8] = {&w.x, &w.r, &w.z, &w.p, &w.q, &w.diag, &w.direct, &w.full_dR};
    for (std::size_t k = 0; k < 8; ++k) *v[k] = vectors + k * stride;
    if (tensors) {
      for (std::size_t k = 0; k < 3; ++k) w.fs[k] = tensors + k * stride;
      w.carrier = carrier_mu;
    }
    return w;
  }
};

namespace cg {

template <int D>
TURBID_HD inline void precondition(const Vec<D>* diag, const Vec<D>* r, Vec<D>* z, std::uint32_t i) {
  for (int c = 0; c < D; ++c) z[i][c] = (Real(1) / diag[i][c]) * r[i][c];
}

template <int D>
struct CopyVelocity {
  const Vec<D>* v;
  Vec<D>* x;
  TURBID_HD void operator()(std::uint32_t i) const { x[i] = v[i]; }
};

// The boundary velocities' part of the full stress goes to the right-hand side.
template <int D>
struct FullStressRhs {
  const Vec<D>* diag;
  const Real* mass;
  const Vec<D>* full_dR;
  Vec<D>* r;
  Real dt;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (in_system<D>(diag, i)) r[i] -= (dt / mass[i]) * full_dR[i];
  }
};

// r = b - A x0, z = r / diag, p = z (zero outside the system).
template <int D>
struct Start {
  const Vec<D>* diag;
  const Vec<D>* q;
  Vec<D>* r;
  Vec<D>* z;
  Vec<D>* p;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (in_system<D>(diag, i)) {
      r[i] -= q[i];
      precondition<D>(diag, r, z, i);
    } else {
      r[i] = z[i] = Vec<D>::zero();
    }
    p[i] = z[i];
  }
};

template <int D>
struct Update {
  const Vec<D>* diag;
  const Vec<D>* p;
  const Vec<D>* q;
  Vec<D>* x;
  Vec<D>* r;
  Vec<D>* z;
  Real alpha;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (!in_system<D>(diag, i)) return;
    x[i] += alpha * p[i];
    r[i] -= alpha * q[i];
    precondition<D>(diag, r, z, i);
  }
};

template <int D>
struct Direction {
  const Vec<D>* diag;
  const Vec<D>* z;
  Vec<D>* p;
  Real beta;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (in_system<D>(diag, i)) p[i] = z[i] + beta * p[i];
  }
};

// m_i a_i . b_i for system particles (the mass-weighted inner product), 0 for the others.
template <int D>
struct MassDot {
  const Real* mass;
  const Vec<D>* diag;
  const Vec<D>* a;
  const Vec<D>* b;
  TURBID_HD double operator()(std::uint32_t i) const {
    return in_system<D>(diag, i) ? double(mass[i]) * double(dot(a[i], b[i])) : 0.0;
  }
};

}  // namespace cg

// The solve and the update of the velocities (and the structures' reactions), as
// Backend::solve_viscosity describes; K and UniformH as the passes'.
template <int D, class K, bool UniformH, class Exec>
ViscousSolve solve_implicit_viscosity(Exec& ex, const ParticleView<D>& P, const GridView<D>& G, const NeighbourList& L,
                                      const PhysicsParams& prm, Real dt, Real share, bool first_half, const ViscousWork<D>& w) {
  const std::uint32_t n = P.count;
  ViscousSolve out;
  const bool full = prm.full_stress;
  Vec<D>* full_dR = full ? w.full_dR : nullptr;
  const auto dot = [&](const Vec<D>* a, const Vec<D>* b) { return ex.sum(n, cg::MassDot<D>{P.mass, w.diag, a, b}); };
  // dR/du of the full-stress form (sph/full_stress.hpp) into full_dR; linear in (u, known):
  // dR(x; known) = dR(x; 0) + dR(0; known).
  const auto full_eval = [&](const Vec<D>* u, bool known, bool structures = false) {
    ex.run(n, FullStressGradientPass<D, K, UniformH>{P, G, prm, L, u, known, w.carrier, w.fs[0], w.fs[1]});
    ex.run(n, FullStressStressPass<D, K, UniformH>{P, G, prm, L, u, known, w.carrier, w.fs[0], w.fs[1], w.fs[2], w.direct});
    ex.run(n, FullStressForcePass<D, K, UniformH>{P, G, prm, L, w.carrier, w.fs[2], w.direct, structures, full_dR});
  };
  const auto apply = [&](const Vec<D>* u, Vec<D>* result) {
    if (full) full_eval(u, false);
    ex.run(n, ViscousApplyPass<D, K, UniformH>{P, G, prm, L, dt, w.diag, u, full_dR, result});
  };
  ex.run(n, ViscousSystemPass<D, K, UniformH>{P, G, prm, L, dt, w.diag, w.r});  // r = b for now
  if (full) {
    ex.run(n, FullStressSetupPass<D, K, UniformH>{P, G, prm, L, w.carrier, w.fs[0]});
    full_eval(nullptr, true);  // the boundary velocities' part goes to the right-hand side
    ex.run(n, cg::FullStressRhs<D>{w.diag, P.mass, full_dR, w.r, dt});
  }
  ex.run(n, cg::CopyVelocity<D>{P.velocity, w.x});
  apply(w.x, w.q);
  const double b_norm = std::sqrt(dot(w.r, w.r));
  ex.run(n, cg::Start<D>{w.diag, w.q, w.r, w.z, w.p});
  double rz = dot(w.r, w.z);
  double res = b_norm > 0 ? std::sqrt(dot(w.r, w.r)) / b_norm : 0.0;
  const double tol = double(prm.implicit_tolerance);
  int k = 0;
  while (res > tol && k < prm.implicit_max_iterations) {
    apply(w.p, w.q);
    const double pq = dot(w.p, w.q);
    if (!(pq > 0)) break;
    const Real alpha = Real(rz / pq);
    ex.run(n, cg::Update<D>{w.diag, w.p, w.q, w.x, w.r, w.z, alpha});
    ++k;
    res = std::sqrt(dot(w.r, w.r)) / b_norm;
    const double rz_next = dot(w.r, w.z);
    const Real beta = Real(rz_next / rz);
    rz = rz_next;
    ex.run(n, cg::Direction<D>{w.diag, w.z, w.p, beta});
  }
  out.iterations = k;
  out.residual = res;
  out.converged = res <= tol;
  if (full) full_eval(w.x, true, P.viscous_load != nullptr);  // the update's and the reactions' evaluation
  ex.run(n, ViscousUpdatePass<D, K, UniformH>{P, G, prm, L, dt, w.diag, w.x, full_dR});
  if (P.viscous_load) ex.run(n, ViscousReactionPass<D, K, UniformH>{P, G, prm, w.diag, w.x, share, first_half, full_dR});
  return out;
}

}  // namespace turbid::sph
