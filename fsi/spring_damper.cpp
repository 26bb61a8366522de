// Springs and dashpots between bodies and anchors; see spring_damper.hpp.
#include "fsi/spring_damper.hpp"

namespace turbid::fsi {

Eigen::Vector3d spring_damper_force(const SpringDamper& spring, const Eigen::Vector3d& position_a,
                                    const Eigen::Vector3d& velocity_a, const Eigen::Vector3d& position_b,
                                    const Eigen::Vector3d& velocity_b) {
  const Eigen::Vector3d d = position_b - position_a;
  const double length = d.norm();
  if (!(length > 0)) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d u = d / length;
  const double opening_rate = u.dot(velocity_b - velocity_a);
  return (spring.stiffness * (length - spring.rest_length) + spring.damping * opening_rate) * u;
}

PairWrench spring_damper(const SpringDamper& spring, const Attachment& a, const Attachment& b) {
  const Eigen::Vector3d pa = a.position();
  const Eigen::Vector3d pb = b.position();
  const Eigen::Vector3d force_a = spring_damper_force(spring, pa, a.velocity(), pb, b.velocity());
  PairWrench w;
  if (a.body) {
    w.on_a.force = force_a;
    w.on_a.torque = (pa - a.body->position()).cross(force_a);
  }
  if (b.body) {
    w.on_b.force = -force_a;
    w.on_b.torque = (pb - b.body->position()).cross(-force_a);
  }
  return w;
}

}  // namespace turbid::fsi
