// Rigid bodies in the fluid's time step; see body_coupling.hpp.
#include "fsi/body_coupling.hpp"

#include <utility>

#include "fsi/bullet_world.hpp"

namespace turbid::fsi {

BodyCoupling::BodyCoupling(std::vector<std::optional<RigidBody>> bodies, const Eigen::Vector3d& gravity)
    : bodies_(std::move(bodies)), gravity_(gravity), fluid_(bodies_.size()), placement_(bodies_.size()) {}

BodyCoupling::~BodyCoupling() = default;

void BodyCoupling::set_bullet(std::unique_ptr<BulletWorld> world) {
  bullet_ = std::move(world);  // both at rest at the centres of mass
}

bool BodyCoupling::is_bullet(std::size_t k) const { return bullet_ && bodies_[k] && bullet_->has(k); }

void BodyCoupling::restored() {
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (is_bullet(k)) bullet_->read_mirror(k, *bodies_[k]);
}

Wrench BodyCoupling::total_load(std::size_t k) const {
  Wrench w = fluid_[k];
  if (bodies_[k]) w.force += bodies_[k]->mass() * gravity_;
  return w;
}

void BodyCoupling::place(sph::Backend& backend, bool move) const {
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    sph::BodyPlacement& p = placement_[k];
    p.moving = bodies_[k].has_value();
    if (!p.moving) continue;
    const RigidBody& b = *bodies_[k];
    const Eigen::Matrix3d R = b.orientation().toRotationMatrix();
    const Eigen::Vector3d w = b.angular_velocity();
    for (int a = 0; a < 3; ++a) {
      p.centre[a] = b.position()[a];
      p.velocity[a] = b.velocity()[a];
      p.angular_velocity[a] = w[a];
      for (int c = 0; c < 3; ++c) p.rotation[a][c] = R(a, c);
    }
  }
  backend.place_bodies(placement_, move);
}

void BodyCoupling::after_kick(sph::Backend& backend, double half_dt) {
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (bodies_[k]) bodies_[k]->kick(half_dt, total_load(k));
  if (bullet_) {
    std::vector<Wrench> loads(bodies_.size());
    for (std::size_t k = 0; k < bodies_.size(); ++k)
      if (is_bullet(k)) loads[k] = total_load(k);
    bullet_->kick(half_dt, loads);
    if (!drifted_) {
      // The step's first half-kick: Bullet steps now by the whole dt (2 half_dt is exact) with the
      // impulses of this and the last half-kick; the particles carry its half-step velocity, hinge
      // and contact impulses included, through the continuity pass. Its positions wait for the drift.
      bullet_->step(2 * half_dt);
      for (std::size_t k = 0; k < bodies_.size(); ++k)
        if (is_bullet(k)) bullet_->write_mirror_velocity(k, *bodies_[k]);
    }
  }
  drifted_ = false;
  place(backend, false);
}

void BodyCoupling::after_drift(sph::Backend& backend, double dt) {
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (bodies_[k] && !is_bullet(k)) bodies_[k]->drift(dt);
  if (bullet_)
    for (std::size_t k = 0; k < bodies_.size(); ++k)
      if (is_bullet(k)) bullet_->write_mirror(k, *bodies_[k]);
  drifted_ = true;
  place(backend, true);
}

void BodyCoupling::after_forces(sph::Backend& backend) {
  std::vector<std::array<double, 3>> reference(bodies_.size(), {0, 0, 0});
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (bodies_[k])
      for (int a = 0; a < 3; ++a) reference[k][std::size_t(a)] = bodies_[k]->position()[a];
  const std::vector<sph::BodyLoad> loads = backend.body_loads(reference);
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    fluid_[k] = Wrench{};
    if (!bodies_[k]) continue;
    for (int a = 0; a < 3; ++a) {
      fluid_[k].force[a] = loads[k].force[std::size_t(a)];
      fluid_[k].torque[a] = loads[k].torque[std::size_t(a)];
    }
  }
}

}  // namespace turbid::fsi
