// The path of a structure with `motion: prescribed` (scene.hpp, PrescribedPathSpec): its
// displacement d(t) from the scene position and its rotation R(t) about its reference point, with
// their exact time derivatives, so that the particles x = x_ref + d(t) + R(t) r0 carry the velocity
// v = d'(t) + w(t) x (R(t) r0), w the angular velocity in the world frame (R' R^T = [w]x).
//
//  - velocity:    d = v t, R = exp(t [w]x) (a rotation by |w| t about w / |w|);
//  - oscillation: d = A (sin(Omega t + phi) - sin phi), Omega = 2 pi / T, and the same for the
//                 angles (about x, then y, then z), so the path starts where the scene puts the
//                 structure;
//  - samples:     each of the six channels (dx, dy, dz, ax, ay, az) is interpolated in time:
//                 spline: the clamped cubic spline (zero slope at the first and last samples): it
//                   passes through every sample, its velocity and acceleration are continuous
//                   inside, and its velocity meets the hold (zero) continuously at both ends, so
//                   the particles' velocity is the derivative of their positions everywhere and the
//                   fluid sees no velocity jump (docs/choices.md);
//                 linear: piecewise linear, velocity piecewise constant (at a sample time the next
//                   interval's); no overshoot between samples, but velocity jumps at every sample.
//                 Before the first and after the last sample the structure holds (velocity 0).
//   Angles a = (ax, ay, az) give R = Rz(az) Ry(ay) Rx(ax) (the order of a structure's `rotation`),
//   w = az' e_z + ay' Rz e_y + ax' Rz Ry e_x.
// All in double precision. No I/O here.
#pragma once
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fsi/scene.hpp"

namespace turbid::fsi {

struct PathState {
  Eigen::Vector3d displacement = Eigen::Vector3d::Zero();      // d(t) [m]
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();      // R(t), body frame (world at t = 0) -> world
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // R(t), continuous in t (no sign flips)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();          // d'(t) [m/s]
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // w(t), world frame [rad/s]
};

class PrescribedPath {
 public:
  // Throws std::invalid_argument for a spec it cannot follow: samples fewer than 2, times not
  // strictly increasing or not finite, channels of another length, a period that is not positive.
  explicit PrescribedPath(const PrescribedPathSpec& spec);

  PathState at(double t) const;
  const PrescribedPathSpec& spec() const { return spec_; }

 private:
  // Value and time derivative of channel c (0..2 displacement, 3..5 angles) of the samples at t.
  void sample(int c, double t, double& value, double& rate) const;

  PrescribedPathSpec spec_;
  std::vector<double> y_[6];   // samples per channel
  std::vector<double> m_[6];   // spline: second derivatives at the samples
};

// Rz(a[2]) Ry(a[1]) Rx(a[0]) and the world angular velocity for angle rates `rate`.
Eigen::Quaterniond rotation_from_angles(const Eigen::Vector3d& a);
Eigen::Vector3d angular_velocity_from_angle_rates(const Eigen::Vector3d& a, const Eigen::Vector3d& rate);

}  // namespace turbid::fsi
