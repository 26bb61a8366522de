// Smoothing kernels with support 2h (physics.md C1): Wendland C2 and the cubic B-spline.
// Each kernel gives W(r, h) and F(r, h) = (1/r) dW/dr, so that grad_i W_ij = F * r_ij.
#pragma once
#include "sph/config.hpp"

namespace turbid::sph {

enum class KernelKind { wendland_c2, cubic_spline };

inline constexpr Real kPi = Real(3.14159265358979323846);

template <int D>
struct WendlandC2 {
  // alpha_d: 7/(4 pi h^2) in 2D, 21/(16 pi h^3) in 3D (physics.md C1).
  TURBID_HD static Real norm(Real h) {
    if constexpr (D == 2) return Real(7) / (Real(4) * kPi * h * h);
    else return Real(21) / (Real(16) * kPi * h * h * h);
  }
  TURBID_HD static Real w(Real r, Real h) {
    const Real q = r / h;
    if (q >= Real(2)) return Real(0);
    const Real a = Real(1) - Real(0.5) * q;
    const Real a2 = a * a;
    return norm(h) * a2 * a2 * (Real(2) * q + Real(1));
  }
  // (1/r) dW/dr = -5 alpha_d / h^2 (1 - q/2)^3
  TURBID_HD static Real f(Real r, Real h) { return f_q(r / h, Real(1) / h); }
  // The same from 1/h, without divisions: the form the pair loops use.
  TURBID_HD static Real f_inv(Real r, Real inv_h) { return f_q(r * inv_h, inv_h); }
  // Written without branches (selects only), so that pair loops can be vectorised.
  TURBID_HD static Real f_q(Real q, Real inv_h) {
    const Real a = Real(1) - Real(0.5) * q;
    const Real v = Real(-5) * norm_inv(inv_h) * inv_h * inv_h * a * a * a;
    return q >= Real(2) ? Real(0) : v;
  }
  TURBID_HD static Real norm_inv(Real inv_h) {
    if constexpr (D == 2) return Real(7) / (Real(4) * kPi) * inv_h * inv_h;
    else return Real(21) / (Real(16) * kPi) * inv_h * inv_h * inv_h;
  }
};

template <int D>
struct CubicSpline {
  // Monaghan & Lattanzio (1985): sigma = 10/(7 pi h^2) in 2D, 1/(pi h^3) in 3D.
  TURBID_HD static Real norm(Real h) {
    if constexpr (D == 2) return Real(10) / (Real(7) * kPi * h * h);
    else return Real(1) / (kPi * h * h * h);
  }
  TURBID_HD static Real w(Real r, Real h) {
    const Real q = r / h;
    if (q >= Real(2)) return Real(0);
    if (q < Real(1)) return norm(h) * (Real(1) - Real(1.5) * q * q + Real(0.75) * q * q * q);
    const Real b = Real(2) - q;
    return norm(h) * Real(0.25) * b * b * b;
  }
  TURBID_HD static Real f(Real r, Real h) { return f_q(r / h, Real(1) / h); }
  // The same from 1/h: the form the pair loops use (one division, for q >= 1).
  TURBID_HD static Real f_inv(Real r, Real inv_h) { return f_q(r * inv_h, inv_h); }
  // Written without branches (both pieces evaluated, then selected), so that pair loops can be
  // vectorised.
  TURBID_HD static Real f_q(Real q, Real inv_h) {
    const Real c = norm_inv(inv_h) * inv_h * inv_h;
    // dW/dq / (q h^2): (-3 + 2.25 q) for q < 1, -0.75 (2 - q)^2 / q for 1 <= q < 2
    const Real inner = Real(-3) + Real(2.25) * q;
    const Real b = Real(2) - q;
    const Real outer = Real(-0.75) * b * b / q;
    const Real v = c * (q < Real(1) ? inner : outer);
    return q >= Real(2) ? Real(0) : v;
  }
  TURBID_HD static Real norm_inv(Real inv_h) {
    if constexpr (D == 2) return Real(10) / (Real(7) * kPi) * inv_h * inv_h;
    else return Real(1) / kPi * inv_h * inv_h * inv_h;
  }
};

}  // namespace turbid::sph
