// The columns of forces.csv: for every structure its force, torque about its reference point and,
// when the scene gives reference values, drag, lift and their coefficients. No I/O here.
#pragma once
#include <string>
#include <vector>

#include "fsi/scene.hpp"
#include "sph/body_loads.hpp"

namespace turbid::fsi {

// The state of a moving structure's rigid body (world frame).
struct BodyKinematics {
  Vec3d position{0, 0, 0};                  // centre of mass (prescribed: reference point) [m]
  std::array<double, 4> orientation{1, 0, 0, 0};  // unit quaternion w, x, y, z (body -> world) [-]
  Vec3d velocity{0, 0, 0};                  // of the centre of mass [m/s]
  Vec3d angular_velocity{0, 0, 0};          // [rad/s]
  Vec3d contact_force{0, 0, 0};             // DEM contacts, mean over the last step [N] (2D: [N/m])
};

// Column names with units, e.g. "cylinder.Fx [N/m]" (2D: per metre of depth).
//   2D: Fx, Fy, Mz;  3D: Fx, Fy, Fz, Mx, My, Mz;  with coefficients also drag, lift, C_D, C_L.
// A moving structure (motion: free) adds its body's state: 2D x, y [m], qw, qz [-], vx, vy [m/s],
// wz [rad/s], contact_Fx, contact_Fy [N/m]; 3D x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz,
// contact_Fx, contact_Fy, contact_Fz [N] (the DEM contact force from walls and other structures,
// its impulse over the last step / dt; zero without a contact material). Its torque (the fluid's)
// is about its centre of mass. A prescribed structure (motion: prescribed) adds the same columns
// for its path: x, y (, z) is its moving reference point, about which its torque is taken; its
// contact columns are zero (prescribed structures take part in no contact yet).
std::vector<std::string> force_columns(const Scene& scene);

// The values of one row, in the order of force_columns. Drag F.e_flow and lift F.e_lift;
// C = 2 F / (rho U^2 A), A = reference length (2D) or reference area (3D). `kinematics`: one per
// structure (read for the moving ones; may be empty when none moves).
std::vector<double> force_row(const Scene& scene, const std::vector<sph::BodyLoad>& loads,
                              const std::vector<BodyKinematics>& kinematics = {});

}  // namespace turbid::fsi
