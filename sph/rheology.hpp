// Rheology of the fluid materials (physics.md C8), per particle and shared by all backends:
// Herschel-Bulkley with Papanastasiou's regularisation (HBP), which contains Bingham (n = 1) and
// Newtonian (tau_y = 0, n = 1) as special cases.
//
//   mu_eff(gamma_dot) = K gamma_dot^(n - 1) + tau_y (1 - exp(-m gamma_dot)) / gamma_dot
//
// with the shear rate gamma_dot = sqrt(2 D:D) of the strain-rate tensor D = (grad v + grad v^T) / 2,
// the viscous stress tau = 2 mu_eff D and the effective shear stress sqrt(J2(tau)) =
// sqrt(tau:tau / 2) = mu_eff gamma_dot.
#pragma once
#include <cmath>
#include <limits>

#include "sph/config.hpp"

namespace turbid::sph {

struct Rheology {
  Real yield_stress = 0;   // tau_y [Pa]
  Real consistency = 0;    // K [Pa s^n]; the dynamic viscosity of a Newtonian or Bingham material
  Real flow_index = 1;     // n [-]
  Real regularisation = 0; // Papanastasiou exponent m [s]
  Real max_viscosity = 0;  // cap on mu_eff [Pa s] (keeps the viscous time step finite); 0: none

  // mu_eff at shear rate gamma_dot >= 0 [Pa s]. At gamma_dot -> 0 the yield term tends to m tau_y
  // (1 - exp(-x) = -expm1(-x) keeps its digits at small x). A shear-thinning power law (n < 1)
  // would tend to infinity: with a Papanastasiou exponent it is taken at max(gamma_dot, 1/m), the
  // shear rate below which the yield term is regularised too (K m^(1-n) at rest), and without one
  // it needs a stated cap. All bounds are the material's: none depends on h or dt.
  TURBID_HD Real effective_viscosity(Real gamma_dot) const {
    Real mu = consistency;
    if (flow_index != Real(1)) {
      Real g = gamma_dot;
      if (flow_index < Real(1) && regularisation > Real(0) && g * regularisation < Real(1)) g = Real(1) / regularisation;
      mu = g > Real(0) ? consistency * std::pow(g, flow_index - Real(1)) : (flow_index < Real(1) ? max_viscosity : Real(0));
    }
    if (yield_stress > Real(0)) {
      const Real yield_term = gamma_dot > Real(0) ? yield_stress * -std::expm1(-regularisation * gamma_dot) / gamma_dot
                                                  : yield_stress * regularisation;
      mu += yield_term;
    }
    return max_viscosity > Real(0) && mu > max_viscosity ? max_viscosity : mu;
  }

  // The largest mu_eff over all shear rates [Pa s]: the cap if one is set, else the value at rest
  // (Bingham, regularised shear-thinning); infinite for a shear-thickening power law without a cap,
  // and for a shear-thinning one with neither a Papanastasiou exponent nor a cap.
  double bound() const {
    if (max_viscosity > Real(0)) return double(max_viscosity);
    if (flow_index > Real(1) || (flow_index < Real(1) && !(regularisation > Real(0))))
      return std::numeric_limits<double>::infinity();
    return double(effective_viscosity(Real(0)));
  }
};

// gamma_dot = sqrt(2 D:D) of the symmetric part of a velocity gradient g[a][b] = d v_a / d x_b.
template <int D>
TURBID_HD inline Real shear_rate(const Real (&g)[D][D]) {
  Real s = 0;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) {
      const Real d = Real(0.5) * (g[a][b] + g[b][a]);
      s += d * d;
    }
  return std::sqrt(Real(2) * s);
}

}  // namespace turbid::sph
