// Mass, centre of mass and inertia tensor of a rigid structure from its particle sampling, for the
// built-in rigid-body integrator (rigid_body.hpp).
//
// The samplers of geometry/ give every particle the exact measure of its own cell, so that for a
// filled sampling (layers <= 0) the volumes tile the solid: they sum to the analytic volume of a
// primitive and to the sampled volume of a mesh (geometry/primitives.hpp, geometry/mesh.hpp). Mass
// is then exact to rounding and only the moments carry a sampling error. A shell sampling (the
// structure's boundary layers, layers > 0) misses the interior, so the caller must pass a filled
// one: the function cannot tell the two apart from the points alone.
//
// Each particle is a point mass m_i = rho V_i plus the self-inertia of its cell, taken as a cube
// (2D: a square) of the same volume: m_i V_i^(2/3) / 6 about every axis (2D: m_i A_i / 12 about x
// and y, m_i A_i / 6 about z). Without it the sum of point masses underestimates the moments by
// about (dx / size)^2 relative (1% at ten cells across); with it a box of cubic cells is exact and
// the other shapes keep a smaller O(dx^2) error (see the unit tests).
#pragma once
#include <Eigen/Core>

#include "geometry/primitives.hpp"

namespace turbid::fsi {

struct MassProperties {
  int dims = 3;
  // 3D: [kg]; 2D: per metre of depth [kg/m].
  double mass = 0;
  // [m]; 2D: z = 0.
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();
  // About the centre of mass, in the axes of the sampled (placed) geometry: I = sum m (|r|^2 1 - r r^T)
  // [kg m^2]; 2D: the tensor of a lamina per metre of depth [kg m^2/m] (I_zz = I_xx + I_yy, I_xz =
  // I_yz = 0), of which only I_zz enters planar motion.
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();

  double inertia_zz() const { return inertia(2, 2); }
};

// From a filled sampling (see above) and a uniform density [kg/m^3]. dims is 2 or 3 (a 2D sampling
// has z = 0 and areas for volumes). Throws std::invalid_argument for dims not 2 or 3, a density
// that is not positive and finite, or a sampling without volume.
MassProperties mass_properties(const geometry::SampledBody& filled, double density, int dims);

}  // namespace turbid::fsi
