// The built-in rigid body; see rigid_body.hpp.
#include "fsi/rigid_body.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace turbid::fsi {

namespace {

// Indices of the free rotation axes and the free block of a world-frame matrix.
struct FreeAxes {
  int count = 0;
  int index[3] = {0, 0, 0};
};

FreeAxes free_axes(const DofMask& mask) {
  FreeAxes f;
  for (int k = 0; k < 3; ++k)
    if (mask.rotation[k]) f.index[f.count++] = k;
  return f;
}

}  // namespace

RigidBody::RigidBody(const MassProperties& mp, const DofMask& mask)
    : dims_(mp.dims), mass_(mp.mass), mask_(mask), inertia_body_(mp.inertia), x_(mp.centre_of_mass) {
  if (dims_ != 2 && dims_ != 3) throw std::invalid_argument("RigidBody: dims must be 2 or 3");
  if (!(mass_ > 0) || !std::isfinite(mass_)) throw std::invalid_argument("RigidBody: mass must be positive and finite");
  if (!inertia_body_.allFinite() || (inertia_body_ - inertia_body_.transpose()).norm() > 1e-12 * inertia_body_.norm())
    throw std::invalid_argument("RigidBody: the inertia tensor must be finite and symmetric");
  if (dims_ == 2) {
    mask_.translation[2] = false;
    mask_.rotation[0] = false;
    mask_.rotation[1] = false;
    x_.z() = 0;
  }
  // The splitting rotates about principal axes; a right-handed set keeps q * AngleAxis a rotation.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(inertia_body_);
  principal_moments_ = eig.eigenvalues();
  principal_axes_ = eig.eigenvectors();
  if (principal_axes_.determinant() < 0) principal_axes_.col(2) = -principal_axes_.col(2);

  const FreeAxes f = free_axes(mask_);
  if (f.count == 3) {
    if (!(principal_moments_.minCoeff() > 0))
      throw std::invalid_argument("RigidBody: a body free to rotate about every axis needs positive principal moments");
    inverse_inertia_body_ = inertia_body_.inverse();
  } else if (f.count > 0) {
    Eigen::MatrixXd block(f.count, f.count);
    for (int a = 0; a < f.count; ++a)
      for (int b = 0; b < f.count; ++b) block(a, b) = inertia_body_(f.index[a], f.index[b]);
    if (Eigen::LLT<Eigen::MatrixXd>(block).info() != Eigen::Success)
      throw std::invalid_argument("RigidBody: the inertia about the free rotation axes must be positive definite");
  }
}

Eigen::Matrix3d RigidBody::world_inertia() const {
  const Eigen::Matrix3d R = q_.toRotationMatrix();
  return R * inertia_body_ * R.transpose();
}

Eigen::Vector3d RigidBody::angular_velocity_at(const Eigen::Quaterniond& q) const {
  const FreeAxes f = free_axes(mask_);
  const Eigen::Matrix3d R = q.toRotationMatrix();
  if (f.count == 3) return R * (inverse_inertia_body_ * (R.transpose() * L_));
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
  if (f.count == 0) return w;
  const Eigen::Matrix3d I = R * inertia_body_ * R.transpose();
  if (f.count == 1) {
    const int k = f.index[0];
    w[k] = L_[k] / I(k, k);
    return w;
  }
  Eigen::Matrix2d block;
  Eigen::Vector2d rhs;
  for (int a = 0; a < 2; ++a) {
    rhs[a] = L_[f.index[a]];
    for (int b = 0; b < 2; ++b) block(a, b) = I(f.index[a], f.index[b]);
  }
  const Eigen::Vector2d wf = block.ldlt().solve(rhs);
  w[f.index[0]] = wf[0];
  w[f.index[1]] = wf[1];
  return w;
}

Eigen::Vector3d RigidBody::angular_velocity() const { return angular_velocity_at(q_); }

double RigidBody::kinetic_energy() const {
  return 0.5 * mass_ * v_.squaredNorm() + 0.5 * angular_velocity().dot(L_);
}

void RigidBody::set_position(const Eigen::Vector3d& x) {
  for (int k = 0; k < 3; ++k)
    if (mask_.translation[k]) x_[k] = x[k];
}

void RigidBody::set_orientation(const Eigen::Quaterniond& q) {
  q_ = q.normalized();
  update_locked_momentum();
}

void RigidBody::set_velocity(const Eigen::Vector3d& v) {
  for (int k = 0; k < 3; ++k) v_[k] = mask_.translation[k] ? v[k] : 0.0;
}

void RigidBody::set_angular_velocity(const Eigen::Vector3d& w) {
  Eigen::Vector3d free_w = w;
  for (int k = 0; k < 3; ++k)
    if (!mask_.rotation[k]) free_w[k] = 0;
  L_ = world_inertia() * free_w;
}

// The locked components of L are the reaction's business: they are set to (I w)_k so that L stays
// the body's true angular momentum; the free components, which carry the dynamics, are not touched.
void RigidBody::update_locked_momentum() {
  if (all_rotations_free()) return;
  const Eigen::Vector3d Iw = world_inertia() * angular_velocity();
  for (int k = 0; k < 3; ++k)
    if (!mask_.rotation[k]) L_[k] = Iw[k];
}

void RigidBody::kick(double dt, const Wrench& load) {
  for (int k = 0; k < 3; ++k) {
    if (mask_.translation[k]) v_[k] += dt * load.force[k] / mass_;
    if (mask_.rotation[k]) L_[k] += dt * load.torque[k];
  }
  update_locked_momentum();
}

// Exact flow of the kinetic-energy term pi_k^2 / (2 I_k): pi_k is constant along it, so the body
// turns about its principal axis k by dt pi_k / I_k while L stays fixed in the world.
void RigidBody::rotate_about_principal_axis(int k, double dt) {
  const Eigen::Vector3d axis = principal_axes_.col(k);
  const double pi_k = axis.dot(q_.conjugate() * L_);
  q_ = q_ * Eigen::Quaterniond(Eigen::AngleAxisd(dt * pi_k / principal_moments_[k], axis));
}

void RigidBody::drift(double dt) {
  x_ += dt * v_;
  const FreeAxes f = free_axes(mask_);
  if (f.count == 3) {
    rotate_about_principal_axis(0, 0.5 * dt);
    rotate_about_principal_axis(1, 0.5 * dt);
    rotate_about_principal_axis(2, dt);
    rotate_about_principal_axis(1, 0.5 * dt);
    rotate_about_principal_axis(0, 0.5 * dt);
  } else if (f.count == 1) {
    const int k = f.index[0];
    const double I_kk = world_inertia()(k, k);
    q_ = Eigen::Quaterniond(Eigen::AngleAxisd(dt * L_[k] / I_kk, Eigen::Vector3d::Unit(k))) * q_;
  } else if (f.count == 2) {
    const auto turn = [](const Eigen::Vector3d& w, double t) {
      const double angle = w.norm() * t;
      return angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, w.normalized())) : Eigen::Quaterniond::Identity();
    };
    const Eigen::Quaterniond half = (turn(angular_velocity_at(q_), 0.5 * dt) * q_).normalized();
    q_ = turn(angular_velocity_at(half), dt) * q_;
  }
  q_.normalize();
  update_locked_momentum();
}

}  // namespace turbid::fsi
