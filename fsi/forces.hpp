// The columns of forces.csv: for every structure its force, torque about its reference point and,
// when the scene gives reference values, drag, lift and their coefficients. No I/O here.
#pragma once
#include <string>
#include <vector>

#include "fsi/scene.hpp"
#include "sph/body_loads.hpp"

namespace turbid::fsi {

// Column names with units, e.g. "cylinder.Fx [N/m]" (2D: per metre of depth).
//   2D: Fx, Fy, Mz;  3D: Fx, Fy, Fz, Mx, My, Mz;  with coefficients also drag, lift, C_D, C_L.
std::vector<std::string> force_columns(const Scene& scene);

// The values of one row, in the order of force_columns. Drag F.e_flow and lift F.e_lift;
// C = 2 F / (rho U^2 A), A = reference length (2D) or reference area (3D).
std::vector<double> force_row(const Scene& scene, const std::vector<sph::BodyLoad>& loads);

}  // namespace turbid::fsi
