// Constraints on the built-in rigid bodies (motion: free), from the scene's `constraints:` list:
//  - spring: a linear spring and dashpot between a point of a body and a fixed anchor or a point
//    of another body (fsi/spring_damper.hpp); central, so between two bodies it conserves momentum.
//  - pivot (a hinge of the built-in integrator): a stiff isotropic spring and dashpot of zero rest
//    length that ties the two ends' points together,
//      F_a = k (p_b - p_a) + c (v_b - v_a),   F_b = -F_a,
//    with k = 1000 m g_ref / dx (m the ends' reduced mass at rest, g_ref = max(|g|, 9.81 m/s^2)), so
//    a load of ten times the body's weight opens the pivot by 1% of dx, and critical damping
//    c = 2 sqrt(k m). The rotations other than about the hinge axis are locked (3D: the axis must be
//    a world axis and the other end an anchor; 2D: the axis is z, turning is free). The body
//    substeps resolve the pivot's period 2 pi sqrt(m_eff / k) (body_coupling.hpp).
// Each end's point is kept in its body's frame (relative to the centre of mass, body axes).
// No I/O here.
#pragma once
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "fsi/rigid_body.hpp"
#include "fsi/spring_damper.hpp"

namespace turbid::fsi {

struct BodyConstraint {
  enum class Kind { spring, pivot };
  Kind kind = Kind::spring;
  int structure_a = -1, structure_b = -1;  // -1: a fixed anchor
  Eigen::Vector3d point_a = Eigen::Vector3d::Zero();  // body frame, or the anchor's world position
  Eigen::Vector3d point_b = Eigen::Vector3d::Zero();
  double stiffness = 0;    // k [N/m]
  double damping = 0;      // c [N s/m]
  double rest_length = 0;  // spring: L0 [m]
  int scene_index = -1;    // its item in the scene's `constraints` list (messages)
};

// Adds the constraint's wrenches to `out` (one per structure).
void add_constraint_wrench(const BodyConstraint& c, const std::vector<std::optional<RigidBody>>& bodies,
                           std::vector<Wrench>& out);

// The largest stable body substep for the constraint [s]: a fiftieth of its period 2 pi sqrt(m_eff / k)
// and half of m_eff / c, with m_eff the ends' reduced mass at the attachment points (an off-centre
// point moves a lighter mass: 1/m_eff = 1/m + r^2 / I_min).
double constraint_substep(const BodyConstraint& c, const std::vector<std::optional<RigidBody>>& bodies);

// The effective mass of body b at a world point, for the substep estimates.
double effective_mass_at(const RigidBody& b, const Eigen::Vector3d& point);

}  // namespace turbid::fsi
