// Tait (Cole) equation of state with background pressure (physics.md C2) and the consistent
// hydrostatic initial density (physics.md D8).
#pragma once
#include <cmath>

#include "sph/config.hpp"

namespace turbid::sph {

struct TaitEos {
  Real rest_density;        // rho0 [kg/m^3]
  Real stiffness;           // B = c0^2 rho0 / gamma [Pa]
  Real gamma;               // polytropic exponent [-]
  Real background_pressure; // p_b [Pa]

  static TaitEos make(double rest_density, double sound_speed, double gamma, double background_pressure) {
    TaitEos e;
    e.rest_density = Real(rest_density);
    e.stiffness = Real(sound_speed * sound_speed * rest_density / gamma);
    e.gamma = Real(gamma);
    e.background_pressure = Real(background_pressure);
    return e;
  }
  TURBID_HD Real pressure(Real rho) const {
    return stiffness * (std::pow(rho / rest_density, gamma) - Real(1)) + background_pressure;
  }
  TURBID_HD Real density(Real p) const {
    return rest_density * std::pow((p - background_pressure) / stiffness + Real(1), Real(1) / gamma);
  }
  // density(p), for any p: a pressure below -B + p_b (more tension than the equation of state can
  // describe) gives density 0 instead of the NaN of a negative base.
  TURBID_HD Real density_at(Real p) const {
    const Real base = (p - background_pressure) / stiffness + Real(1);
    return base > Real(0) ? rest_density * std::pow(base, Real(1) / gamma) : Real(0);
  }
  // Density at zero absolute pressure, the lowest a wall may take (walls carry no tension: a wall
  // that pulled fluid towards it would let it through, and a free surface over a wall would stick).
  // rho0 without background pressure; below rho0 with one, so that a wall under suction (behind a
  // cylinder in a channel) follows the fluid down to p = 0.
  TURBID_HD Real no_tension_density() const { return density(Real(0)); }
  // Density at gauge pressure p >= 0 (above the background pressure) [kg/m^3], in double.
  double density_at_gauge(double p) const {
    return double(rest_density) * std::pow(1.0 + p / double(stiffness), 1.0 / double(gamma));
  }
  // Density that balances the hydrostatic pressure rho0 g depth (depth >= 0 below the surface).
  double hydrostatic_density(double gravity, double depth) const {
    return double(rest_density) * std::pow(1.0 + double(rest_density) * gravity * depth / double(stiffness),
                                           1.0 / double(gamma));
  }
};

}  // namespace turbid::sph
