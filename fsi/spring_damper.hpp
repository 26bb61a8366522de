// Linear springs and dashpots that tie a point of a rigid body to a fixed anchor or to a point of
// another body (a pipeline on its moorings), as forces and torques for RigidBody::kick.
//
// With d = p_b - p_a between the two end points, L = |d| and u = d / L, the force on end a is
//   F_a = (k (L - L0) + c dL/dt) u,   dL/dt = u . (v_b - v_a),   F_b = -F_a,
// i.e. a stretched spring or an opening dashpot pulls the ends together. The pair of forces is
// central (along d), so it exerts no net torque on the system; each body gets (p - x_com) x F.
// Where the ends coincide (L = 0) the direction is undefined and the force is taken as zero.
#pragma once
#include <Eigen/Core>

#include "fsi/rigid_body.hpp"

namespace turbid::fsi {

struct SpringDamper {
  double stiffness = 0;    // k [N/m] (2D: per metre of depth, [N/m/m])
  double rest_length = 0;  // L0 [m]
  double damping = 0;      // c [N s/m] (2D: per metre of depth)
};

// One end: a point of a body given in the body frame (relative to its centre of mass, body axes),
// or, without a body, a fixed anchor in the world.
struct Attachment {
  const RigidBody* body = nullptr;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();

  Eigen::Vector3d position() const { return body ? body->to_world(point) : point; }
  Eigen::Vector3d velocity() const {
    return body ? body->velocity_at(body->to_world(point)) : Eigen::Vector3d::Zero();
  }
};

// Force on end a from the end positions and velocities [m], [m/s] (see above).
Eigen::Vector3d spring_damper_force(const SpringDamper& spring, const Eigen::Vector3d& position_a,
                                    const Eigen::Vector3d& velocity_a, const Eigen::Vector3d& position_b,
                                    const Eigen::Vector3d& velocity_b);

// Forces and torques on both ends' bodies.
PairWrench spring_damper(const SpringDamper& spring, const Attachment& a, const Attachment& b);

}  // namespace turbid::fsi
