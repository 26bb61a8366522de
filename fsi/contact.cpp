// DEM contact law; see contact.hpp.
#include "fsi/contact.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace turbid::fsi {

namespace {

// 1/x that maps infinity (a wall, a flat face, a rigid material) to 0.
double reciprocal(double x) { return std::isinf(x) ? 0.0 : 1.0 / x; }

// Right-hand side of the dimensionless contact X'' (contact.hpp); the clamp is that of the force.
double contact_acceleration(double alpha, double X, double V) {
  if (X <= 0) return 0;
  const double f = 1.25 * X * std::sqrt(X) + alpha * std::sqrt(1.25) * std::sqrt(std::sqrt(X)) * V;
  return f > 0 ? -f : 0.0;
}

}  // namespace

double effective_modulus(double youngs_1, double poisson_1, double youngs_2, double poisson_2) {
  return 1.0 / ((1 - poisson_1 * poisson_1) * reciprocal(youngs_1) + (1 - poisson_2 * poisson_2) * reciprocal(youngs_2));
}

double effective_shear_modulus(double youngs_1, double poisson_1, double youngs_2, double poisson_2) {
  return 1.0 / (2 * (2 - poisson_1) * (1 + poisson_1) * reciprocal(youngs_1) +
                2 * (2 - poisson_2) * (1 + poisson_2) * reciprocal(youngs_2));
}

double hertz_normal_force(double effective_modulus, double effective_radius, double overlap) {
  if (!(overlap > 0)) return 0;
  return 4.0 / 3.0 * effective_modulus * std::sqrt(effective_radius) * overlap * std::sqrt(overlap);
}

double restitution_of_damping(double alpha) {
  if (!(alpha >= 0)) throw std::invalid_argument("restitution_of_damping: the damping factor must be >= 0");
  // RK4 across the contact. The dimensionless contact lasts about 3 (2.94 undamped, less with
  // damping); the cap only guards against a loop that never leaves.
  constexpr double dtau = 1e-3;
  constexpr int max_steps = 1000000;
  double X = 0, V = 1;
  for (int n = 0; n < max_steps; ++n) {
    const double k1x = V, k1v = contact_acceleration(alpha, X, V);
    const double k2x = V + 0.5 * dtau * k1v, k2v = contact_acceleration(alpha, X + 0.5 * dtau * k1x, V + 0.5 * dtau * k1v);
    const double k3x = V + 0.5 * dtau * k2v, k3v = contact_acceleration(alpha, X + 0.5 * dtau * k2x, V + 0.5 * dtau * k2v);
    const double k4x = V + dtau * k3v, k4v = contact_acceleration(alpha, X + dtau * k3x, V + dtau * k3v);
    X += dtau / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    V += dtau / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    // Once the clamped force is zero on the way out it stays zero (the spring term only shrinks
    // with X while V is constant), so the exit speed is known from here on.
    if (V < 0 && (X <= 0 || contact_acceleration(alpha, X, V) == 0)) return -V;
  }
  return 0;
}

double damping_of_restitution(double restitution) {
  if (!(restitution > 0 && restitution <= 1))
    throw std::invalid_argument("damping_of_restitution: the restitution must lie in (0, 1]");
  if (restitution == 1) return 0;
  // e(alpha) falls monotonically from 1 at alpha = 0; bracket, then bisect to the precision the
  // integration itself reaches.
  double lo = 0, hi = 1;
  while (restitution_of_damping(hi) > restitution) {
    lo = hi;
    hi *= 2;
    if (hi > 1e6) throw std::invalid_argument("damping_of_restitution: restitution too small to reach");
  }
  for (int i = 0; i < 40 && hi - lo > 1e-9 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (restitution_of_damping(mid) > restitution ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

ContactLaw make_contact_law(const ContactSide& s1, const ContactSide& s2, double restitution, double friction) {
  const auto check = [](const ContactSide& s) {
    if (!(s.youngs_modulus > 0)) throw std::invalid_argument("make_contact_law: Young's modulus must be positive");
    if (!(s.poisson_ratio >= 0 && s.poisson_ratio <= 0.5))
      throw std::invalid_argument("make_contact_law: Poisson's ratio must lie in [0, 0.5]");
    if (!(s.radius > 0)) throw std::invalid_argument("make_contact_law: the radius must be positive");
    if (!(s.mass > 0)) throw std::invalid_argument("make_contact_law: the mass must be positive");
  };
  check(s1);
  check(s2);
  if (std::isinf(s1.radius) && std::isinf(s2.radius))
    throw std::invalid_argument("make_contact_law: two flat faces have no Hertz contact");
  if (std::isinf(s1.mass) && std::isinf(s2.mass))
    throw std::invalid_argument("make_contact_law: two fixed sides cannot collide");
  if (std::isinf(s1.youngs_modulus) && std::isinf(s2.youngs_modulus))
    throw std::invalid_argument("make_contact_law: two rigid materials have no Hertz contact");
  if (!(friction >= 0) || std::isinf(friction))
    throw std::invalid_argument("make_contact_law: the friction coefficient must be >= 0 and finite");
  ContactLaw law;
  law.effective_modulus = effective_modulus(s1.youngs_modulus, s1.poisson_ratio, s2.youngs_modulus, s2.poisson_ratio);
  law.effective_shear_modulus =
      effective_shear_modulus(s1.youngs_modulus, s1.poisson_ratio, s2.youngs_modulus, s2.poisson_ratio);
  law.effective_radius = 1.0 / (reciprocal(s1.radius) + reciprocal(s2.radius));
  law.effective_mass = 1.0 / (reciprocal(s1.mass) + reciprocal(s2.mass));
  law.damping_factor = damping_of_restitution(restitution);
  law.restitution = restitution;
  law.friction = friction;
  return law;
}

ContactForce contact_force(const ContactLaw& law, double overlap, const Eigen::Vector3d& normal,
                           const Eigen::Vector3d& relative_velocity, TangentialSpring& spring, double dt) {
  ContactForce out;
  if (!(overlap > 0)) {
    spring.elongation.setZero();
    return out;
  }
  const double root_overlap = std::sqrt(overlap);
  const double quarter_overlap = std::sqrt(root_overlap);
  const double root_radius = std::sqrt(law.effective_radius);

  const double normal_speed = relative_velocity.dot(normal);  // < 0 while approaching
  const double k_n = 4.0 / 3.0 * law.effective_modulus * root_radius;
  const double eta_n = law.damping_factor * std::sqrt(law.effective_mass * k_n) * quarter_overlap;
  out.normal_force = std::max(0.0, k_n * overlap * root_overlap - eta_n * normal_speed);

  // The contact plane turns with the bodies; the spring keeps its length in the new plane so that
  // a rotation alone stores no energy in it.
  const Eigen::Vector3d v_t = relative_velocity - normal_speed * normal;
  const double stored = spring.elongation.norm();
  Eigen::Vector3d xi = spring.elongation - spring.elongation.dot(normal) * normal;
  const double projected = xi.norm();
  if (projected > 0) xi *= stored / projected;
  xi += dt * v_t;

  const double k_t_coefficient = 8.0 * law.effective_shear_modulus * root_radius;
  const double k_t = k_t_coefficient * root_overlap;
  const double eta_t = law.damping_factor * std::sqrt(law.effective_mass * k_t_coefficient) * quarter_overlap;
  Eigen::Vector3d f_t = -k_t * xi - eta_t * v_t;
  const double cap = law.friction * out.normal_force;
  const double f_t_norm = f_t.norm();
  if (f_t_norm > cap) {
    f_t *= f_t_norm > 0 ? cap / f_t_norm : 0.0;
    xi = -(f_t + eta_t * v_t) / k_t;
    out.sliding = true;
  }
  spring.elongation = xi;
  out.force = out.normal_force * normal + f_t;
  return out;
}

double hertz_contact_duration(const ContactLaw& law, double approach_speed) {
  if (!(approach_speed > 0)) throw std::invalid_argument("hertz_contact_duration: the approach speed must be positive");
  const double k_n = 4.0 / 3.0 * law.effective_modulus * std::sqrt(law.effective_radius);
  const double tau_c = 0.8 * std::tgamma(0.4) * std::tgamma(0.5) / std::tgamma(0.9);
  return tau_c * std::pow(5.0 * law.effective_mass / (4.0 * k_n), 0.4) * std::pow(approach_speed, -0.2);
}

double contact_time_step(const ContactLaw& law, double approach_speed, double steps_per_contact) {
  if (!(steps_per_contact > 0)) throw std::invalid_argument("contact_time_step: steps_per_contact must be positive");
  return hertz_contact_duration(law, approach_speed) / steps_per_contact;
}

ContactGeometry sphere_plane(const Eigen::Vector3d& centre, double radius, const Eigen::Vector3d& plane_point,
                             const Eigen::Vector3d& plane_normal) {
  ContactGeometry g;
  g.normal = plane_normal;
  g.overlap = radius - (centre - plane_point).dot(plane_normal);
  g.point = centre - (radius - 0.5 * g.overlap) * plane_normal;
  return g;
}

ContactGeometry sphere_sphere(const Eigen::Vector3d& centre_1, double radius_1, const Eigen::Vector3d& centre_2,
                              double radius_2) {
  ContactGeometry g;
  const Eigen::Vector3d d = centre_1 - centre_2;
  const double distance = d.norm();
  g.overlap = radius_1 + radius_2 - distance;
  if (distance > 0) g.normal = d / distance;
  g.point = centre_1 - (radius_1 - 0.5 * g.overlap) * g.normal;
  return g;
}

PairWrench contact_wrench(const Eigen::Vector3d& force_on_1, const Eigen::Vector3d& point, const RigidBody* body_1,
                          const RigidBody* body_2) {
  PairWrench w;
  if (body_1) {
    w.on_a.force = force_on_1;
    w.on_a.torque = (point - body_1->position()).cross(force_on_1);
  }
  if (body_2) {
    w.on_b.force = -force_on_1;
    w.on_b.torque = (point - body_2->position()).cross(-force_on_1);
  }
  return w;
}

}  // namespace turbid::fsi
