// Springs and pivots on the built-in rigid bodies; see body_constraints.hpp.
#include "fsi/body_constraints.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace turbid::fsi {

namespace {

Attachment end_of(int structure, const Eigen::Vector3d& point, const std::vector<std::optional<RigidBody>>& bodies) {
  Attachment a;
  a.point = point;
  if (structure >= 0) a.body = &*bodies[std::size_t(structure)];
  return a;
}

}  // namespace

double effective_mass_at(const RigidBody& b, const Eigen::Vector3d& point) {
  double moment = b.body_inertia()(2, 2);
  if (b.dims() == 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(b.body_inertia(), Eigen::EigenvaluesOnly);
    moment = eig.eigenvalues().minCoeff();
  }
  const double r2 = (point - b.position()).squaredNorm();
  return 1.0 / (1.0 / b.mass() + r2 / moment);
}

void add_constraint_wrench(const BodyConstraint& c, const std::vector<std::optional<RigidBody>>& bodies,
                           std::vector<Wrench>& out) {
  const Attachment a = end_of(c.structure_a, c.point_a, bodies);
  const Attachment b = end_of(c.structure_b, c.point_b, bodies);
  PairWrench w;
  if (c.kind == BodyConstraint::Kind::spring) {
    w = spring_damper(SpringDamper{c.stiffness, c.rest_length, c.damping}, a, b);
  } else {
    const Eigen::Vector3d pa = a.position(), pb = b.position();
    const Eigen::Vector3d force_a = c.stiffness * (pb - pa) + c.damping * (b.velocity() - a.velocity());
    if (a.body) w.on_a = {force_a, (pa - a.body->position()).cross(force_a)};
    if (b.body) w.on_b = {-force_a, (pb - b.body->position()).cross(-force_a)};
  }
  if (c.structure_a >= 0) out[std::size_t(c.structure_a)] += w.on_a;
  if (c.structure_b >= 0) out[std::size_t(c.structure_b)] += w.on_b;
}

double constraint_substep(const BodyConstraint& c, const std::vector<std::optional<RigidBody>>& bodies) {
  double inverse_mass = 0;
  for (const auto& [s, p] : {std::pair{c.structure_a, c.point_a}, std::pair{c.structure_b, c.point_b}}) {
    if (s < 0) continue;
    const RigidBody& b = *bodies[std::size_t(s)];
    inverse_mass += 1.0 / effective_mass_at(b, b.to_world(p));
  }
  const double m = 1.0 / inverse_mass;
  double h = std::numeric_limits<double>::infinity();
  if (c.stiffness > 0) h = std::min(h, 2 * std::numbers::pi * std::sqrt(m / c.stiffness) / 50);
  if (c.damping > 0) h = std::min(h, 0.5 * m / c.damping);
  return h;
}

}  // namespace turbid::fsi
