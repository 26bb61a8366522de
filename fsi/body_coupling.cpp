// Rigid bodies in the fluid's time step; see body_coupling.hpp.
#include "fsi/body_coupling.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "fsi/bullet_world.hpp"

namespace turbid::fsi {

BodyCoupling::BodyCoupling(std::vector<std::optional<RigidBody>> bodies, const Eigen::Vector3d& gravity)
    : bodies_(std::move(bodies)),
      gravity_(gravity),
      fluid_(bodies_.size()),
      placement_(bodies_.size()),
      contact_mean_(bodies_.size()) {}

void BodyCoupling::set_fast_forces(std::vector<BodyConstraint> constraints, std::unique_ptr<BodyContacts> contacts) {
  constraints_ = std::move(constraints);
  contacts_ = contacts && contacts->any() ? std::move(contacts) : nullptr;
}

std::vector<Wrench> BodyCoupling::fast_load(double dt, std::vector<Wrench>* contact) {
  std::vector<Wrench> load(bodies_.size());
  for (const auto& c : constraints_) add_constraint_wrench(c, bodies_, load);
  if (contacts_) {
    std::vector<Wrench> touch(bodies_.size());
    contacts_->evaluate(bodies_, dt, touch);
    for (std::size_t k = 0; k < load.size(); ++k) load[k] += touch[k];
    if (contact) *contact = std::move(touch);
  } else if (contact) {
    contact->assign(bodies_.size(), Wrench{});
  }
  return load;
}

BodyCoupling::~BodyCoupling() = default;

void BodyCoupling::set_obstacle_motion(ObstacleMotionAt motion, std::function<double()> clock) {
  obstacle_motion_ = std::move(motion);
  clock_ = std::move(clock);
  if (bullet_ && obstacle_motion_) {
    const double t = clock_();
    bullet_->place_prescribed([&](std::size_t k) { return obstacle_motion_(k, t); });
  }
}

void BodyCoupling::set_bullet(std::unique_ptr<BulletWorld> world) {
  bullet_ = std::move(world);  // both at rest at the centres of mass
}

bool BodyCoupling::is_bullet(std::size_t k) const { return bullet_ && bodies_[k] && bullet_->has(k); }

void BodyCoupling::restored() {
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (is_bullet(k)) bullet_->read_mirror(k, *bodies_[k]);
  if (bullet_ && obstacle_motion_) {
    const double t = clock_();
    bullet_->place_prescribed([&](std::size_t k) { return obstacle_motion_(k, t); });
  }
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
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    if (!bodies_[k]) continue;
    Wrench load = total_load(k);
    // A bullet body's mirror, kicked alone in the step's second half-kick (the first is overwritten
    // by Bullet's velocity), takes Bullet's mean contact force too, so a body at rest on a wall
    // reports v = 0, not -g dt/2.
    if (drifted_ && is_bullet(k)) load += contact_mean_[k];
    bodies_[k]->kick(half_dt, load);
  }
  if (bullet_) {
    std::vector<Wrench> loads(bodies_.size());
    for (std::size_t k = 0; k < bodies_.size(); ++k)
      if (is_bullet(k)) loads[k] = total_load(k);
    bullet_->kick(half_dt, loads);
    if (!drifted_) {
      // The step's first half-kick: Bullet steps now by the whole dt (2 half_dt is exact) with the
      // impulses of this and the last half-kick; the particles carry its half-step velocity, hinge
      // and contact impulses included, through the continuity pass. Its positions wait for the drift.
      if (obstacle_motion_) {
        const double t_end = clock_() + 2 * half_dt;
        bullet_->move_prescribed([&](std::size_t k) { return obstacle_motion_(k, t_end); });
      }
      bullet_->step(2 * half_dt);
      for (std::size_t k = 0; k < bodies_.size(); ++k)
        if (is_bullet(k)) {
          bullet_->write_mirror_velocity(k, *bodies_[k]);
          contact_mean_[k] = bullet_->contact_load(k);
        }
    }
  }
  drifted_ = false;
  place(backend, false);
}

void BodyCoupling::after_drift(sph::Backend& backend, double dt) {
  // Bullet bodies have stepped at the first half-kick; their mirrors take Bullet's x(n+1), q(n+1).
  if (bullet_)
    for (std::size_t k = 0; k < bodies_.size(); ++k)
      if (is_bullet(k)) bullet_->write_mirror(k, *bodies_[k]);
  drifted_ = true;
  if (!has_fast_forces()) {
    for (std::size_t k = 0; k < bodies_.size(); ++k)
      if (bodies_[k] && !is_bullet(k)) bodies_[k]->drift(dt);
    place(backend, true);
    return;
  }
  // Prescribed obstacles at the time of each evaluation: t(n), then the end of each substep.
  const double t0 = clock_ ? clock_() : 0.0;
  const auto move_obstacles = [&](double t) {
    if (contacts_ && obstacle_motion_) contacts_->move_prescribed([&](std::size_t k) { return obstacle_motion_(k, t); });
  };
  move_obstacles(t0);
  // The substep: the smallest of the constraints' and contacts' limits (body_constraints.hpp,
  // body_contacts.hpp), at the state after the slow half-kick.
  double h = dt;
  // Which constraint (its scene item) or contact (its structure) sets h, for the message below.
  auto source = SubstepLimitError::Source::constraint;
  int limiting = -1;
  for (const auto& c : constraints_) {
    const double hc = constraint_substep(c, bodies_);
    if (hc < h) {
      h = hc;
      source = SubstepLimitError::Source::constraint;
      limiting = c.scene_index;
    }
  }
  if (contacts_) {
    std::vector<Wrench> slow(bodies_.size());
    for (std::size_t k = 0; k < bodies_.size(); ++k) slow[k] = total_load(k);
    std::size_t structure = 0;
    const double hc = contacts_->max_substep(bodies_, slow, gravity_.norm(), &structure);
    if (hc < h) {
      h = hc;
      source = SubstepLimitError::Source::contact;
      limiting = int(structure);
    }
  }
  const double wanted = std::ceil(dt / h);
  if (!(wanted <= kMaxSubsteps))
    throw SubstepLimitError("the body contacts or constraints need " + std::to_string(wanted) +
                                " substeps in a fluid step of " + std::to_string(dt) +
                                " s; lower the contacts' youngs_modulus or the constraints' stiffness",
                            source, limiting, h, wanted, dt);
  const int n = std::max(1, int(wanted));
  const double sub = dt / n;
  std::vector<Wrench> contact, impulse(bodies_.size());
  std::vector<Wrench> fast = fast_load(0.0, &contact);
  last_max_overlap_ = contacts_ ? contacts_->last_max_overlap() : 0.0;
  for (int s = 0; s < n; ++s) {
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
      if (!bodies_[k] || is_bullet(k)) continue;
      bodies_[k]->kick(0.5 * sub, fast[k]);
      impulse[k].force += 0.5 * sub * contact[k].force;
      impulse[k].torque += 0.5 * sub * contact[k].torque;
      bodies_[k]->drift(sub);
    }
    move_obstacles(t0 + (s + 1) * sub);
    fast = fast_load(sub, &contact);
    if (contacts_) last_max_overlap_ = std::max(last_max_overlap_, contacts_->last_max_overlap());
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
      if (!bodies_[k] || is_bullet(k)) continue;
      bodies_[k]->kick(0.5 * sub, fast[k]);
      impulse[k].force += 0.5 * sub * contact[k].force;
      impulse[k].torque += 0.5 * sub * contact[k].torque;
    }
  }
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    if (is_bullet(k)) continue;  // Bullet's, from its step
    contact_mean_[k].force = impulse[k].force / dt;
    contact_mean_[k].torque = impulse[k].torque / dt;
  }
  last_substeps_ = n;
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
