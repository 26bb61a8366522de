// The built-in 6-degree-of-freedom rigid body (motion: free): its state in double precision and the
// kick and drift maps that slot into the fluid's kick-drift-kick step (sph/solver.hpp).
//
// State, all in the world frame: position x of the centre of mass [m], unit quaternion q (body frame
// -> world), velocity v [m/s] and angular momentum L about the centre [kg m^2/s]. The body frame is
// the world's axes at the moment the mass properties were taken (mass_properties.hpp), so a point of
// the body at world position p0 then is at x + R(q) (p0 - x0) later. The inertia tensor about the
// centre in the world frame is I = R I0 R^T and the angular velocity w = I^-1 L.
//
// One coupled step of size dt, lined up with the fluid's (docs/choices.md, "Time integration"):
//   kick(dt/2, F(n))         with the fluid's first half-kick: v(n+1/2), L(n+1/2)
//   drift(dt)                with the fluid's drift: x(n+1), q(n+1); the body's particles follow
//   F(n+1) = fluid + gravity + springs + contacts at x(n+1), with the half-step velocities
//   kick(dt/2, F(n+1))       with the fluid's second half-kick: v(n+1), L(n+1)
// so the body's particles carry v(n+1/2) while the fluid's density rate is computed, as the fluid's
// own particles do. Velocity-dependent forces (dampers, contact damping) see the half-step velocity,
// as the fluid's viscosity does.
//
// Drift. Translation is exact for the kicked velocity. Rotation is the exact flow of the torque-free
// body with L fixed in the world, approximated by the symmetric splitting of the kinetic energy into
// the three principal-axis terms (Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107, 5840, 1997):
// rotations about principal axes 1, 2 by dt/2, 3 by dt, 2, 1 by dt/2, each exact (angle
// dt pi_k / I_k with the body-frame momentum pi = R^T L). It keeps L exactly (the drift does not touch
// it), is symplectic and time-reversible, and its energy error stays bounded, O((|w| dt)^2), instead
// of drifting. The quaternion is renormalised after every drift.
//
// Locked degrees of freedom are a mask of world axes. A locked translation keeps its velocity at 0,
// so its coordinate never changes (bit for bit). Locked rotations keep the world components of w
// along them at 0: the free components follow w_F = (I)_FF^-1 L_F with L_F kicked by the free torque
// components, and the locked components of L are whatever the reaction torque makes them, I w.
//  - none locked: the splitting above;
//  - one free axis k: rotation about the world axis k by dt L_k / I_kk (I_kk does not change under
//    that rotation, so this is exact);
//  - two free axes: not a free-body flow; an explicit midpoint rotation (second order), w from the
//    orientation at the half step;
//  - all locked: no rotation.
// A 2D body (dims 2) always has z translation and x, y rotation locked: it moves in the plane z = 0
// and turns about z, with I_zz of its lamina.
#pragma once
#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fsi/mass_properties.hpp"

namespace turbid::fsi {

// Force [N] and torque about the centre of mass [N m], world frame (2D: per metre of depth).
struct Wrench {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();

  Wrench& operator+=(const Wrench& o) {
    force += o.force;
    torque += o.torque;
    return *this;
  }
};

// What an interaction between two ends (bodies, anchors, walls) does to each; each wrench is about
// its own body's centre of mass and zero for an end that is not a body.
struct PairWrench {
  Wrench on_a;
  Wrench on_b;
};

// true = free. Axes are the world's x, y, z.
struct DofMask {
  std::array<bool, 3> translation{true, true, true};
  std::array<bool, 3> rotation{true, true, true};
};

class RigidBody {
 public:
  // At rest, at the centre of mass, orientation identity. dims 2 adds the planar locks (see above).
  // Throws std::invalid_argument for a mass that is not positive and finite, or an inertia that is
  // not symmetric positive definite in its free rotations (3D free body: all three principal moments
  // > 0; 2D: I_zz > 0).
  explicit RigidBody(const MassProperties& mass_properties, const DofMask& mask = {});

  int dims() const { return dims_; }
  double mass() const { return mass_; }
  const DofMask& mask() const { return mask_; }
  // Body-frame inertia about the centre [kg m^2].
  const Eigen::Matrix3d& body_inertia() const { return inertia_body_; }

  const Eigen::Vector3d& position() const { return x_; }
  const Eigen::Quaterniond& orientation() const { return q_; }
  const Eigen::Vector3d& velocity() const { return v_; }
  Eigen::Vector3d linear_momentum() const { return mass_ * v_; }
  const Eigen::Vector3d& angular_momentum() const { return L_; }
  Eigen::Vector3d angular_velocity() const;  // [rad/s], world frame
  Eigen::Matrix3d world_inertia() const;     // R I0 R^T
  double kinetic_energy() const;             // 1/2 m v^2 + 1/2 w . L [J] (2D: [J/m])

  // Setters keep the locks: locked components of a velocity are dropped, a locked coordinate is not
  // set. An orientation is normalised; with locked rotations the caller must give one that the
  // locks allow (it is not projected).
  void set_position(const Eigen::Vector3d& x);
  void set_orientation(const Eigen::Quaterniond& q);
  void set_velocity(const Eigen::Vector3d& v);
  void set_angular_velocity(const Eigen::Vector3d& w);

  // The exact state as saved (checkpoints): no normalisation, no projection onto the locks.
  void restore_state(const Eigen::Vector3d& x, const Eigen::Quaterniond& q, const Eigen::Vector3d& v,
                     const Eigen::Vector3d& L) {
    x_ = x;
    q_ = q;
    v_ = v;
    L_ = L;
  }

  // World position of a body-frame point (relative to the centre, body axes) and the velocity of
  // the body at a world point.
  Eigen::Vector3d to_world(const Eigen::Vector3d& body_point) const { return x_ + q_ * body_point; }
  Eigen::Vector3d velocity_at(const Eigen::Vector3d& world_point) const {
    return v_ + angular_velocity().cross(world_point - x_);
  }

  // v += dt F / m and L += dt torque on the free axes; dt is the kick's own length (dt/2 in a step).
  void kick(double dt, const Wrench& load);
  // x += dt v; orientation advanced by the rotation described above, L fixed (up to the locked
  // components, which follow the new orientation).
  void drift(double dt);

 private:
  bool all_rotations_free() const { return mask_.rotation[0] && mask_.rotation[1] && mask_.rotation[2]; }
  int free_rotation_count() const { return int(mask_.rotation[0]) + int(mask_.rotation[1]) + int(mask_.rotation[2]); }
  Eigen::Vector3d angular_velocity_at(const Eigen::Quaterniond& q) const;
  void rotate_about_principal_axis(int k, double dt);
  void update_locked_momentum();

  int dims_ = 3;
  double mass_ = 0;
  DofMask mask_;
  Eigen::Matrix3d inertia_body_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d inverse_inertia_body_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d principal_axes_ = Eigen::Matrix3d::Identity();  // columns, body frame, det +1
  Eigen::Vector3d principal_moments_ = Eigen::Vector3d::Ones();
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d L_ = Eigen::Vector3d::Zero();
};

}  // namespace turbid::fsi
