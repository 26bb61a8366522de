// Couples the built-in rigid bodies (motion: free, rigid_body.hpp) to the fluid's kick-drift-kick
// step (sph/solver.hpp, StepCoupling):
//   after the fluid's half-kick:  each body is kicked by half_dt with the load of the last force
//                                 pass; its particles take the new rigid velocity v + w x r;
//   after the fluid's drift:      each body drifts by dt; its particles are placed rigidly,
//                                 x = x_c + R r0, with the rigid velocity (sph/body_motion.hpp);
//   after the force pass:         load = the fluid's force and torque about the body's current
//                                 centre of mass (Backend::body_loads, the exact reaction of the
//                                 fluid's pair terms: Newton's third law) + m g.
// So the body's particles carry v(n+1/2) while the fluid's density rate and forces are computed,
// as the fluid's own particles do. Fixed structures are left alone, and a scene without free
// bodies never builds one of these (no field, no pass). No I/O here.
//
// Constraints and contacts (body_constraints.hpp, body_contacts.hpp) are fast forces: a stiff
// contact lasts a few milliseconds and needs ~50 steps, a mooring spring may be stiffer than the
// fluid step resolves. With any of them the drift becomes n body substeps of size h = dt / n
// (multiple time stepping, r-RESPA: Tuckerman, Berne & Martyna, J. Chem. Phys. 97, 1990 (1992)):
//   after the fluid's half-kick:  kick(dt/2) with the slow load (fluid + gravity) only;
//   after the fluid's drift:      n times { kick(h/2, fast); drift(h); fast at the new state;
//                                 kick(h/2, fast) }, the fast load (springs, pivots, contacts)
//                                 evaluated at every substep with the fluid load held;
//   second half-kick:             kick(dt/2) with the new slow load.
// This is symplectic and time-reversible like the plain step (it reduces to it for n = 1 without
// fast forces) and keeps the fluid's step: h comes from the contacts' Hertz duration (t_c / 50 at
// the present approach speeds, BodyContacts::max_substep) and the constraints' periods, so a
// contact costs body substeps, not fluid steps. Tangential springs advance once per substep.
// Without constraints and contacts the step is the plain one above, bit for bit.
// motion: bullet structures (bullet_world.hpp) keep a RigidBody here too, a mirror of Bullet's state
// that placement, forces.csv and checkpoints read as for free bodies. Bullet takes the same two
// half-kick impulses and steps by dt at the step's first half-kick (the load F(n) is known then);
// the mirror takes Bullet's half-step velocity there (v, L = I w; the particles carry it through the
// continuity pass) and Bullet's x(n+1), q(n+1) at the drift. The second half-kick kicks the mirror
// as a free body, so its velocity at the end of a step is the synchronised one.
#pragma once
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fsi/body_constraints.hpp"
#include "fsi/body_contacts.hpp"
#include "fsi/rigid_body.hpp"
#include "sph/backend.hpp"
#include "sph/solver.hpp"

namespace turbid::fsi {

// A constraint or a contact that needs more body substeps in one fluid step than the coupling
// allows (BodyCoupling::kMaxSubsteps). Simulation::step turns it into a message that names the
// scene's constraint or structure, its key and its value.
struct SubstepLimitError : std::runtime_error {
  enum class Source { constraint, contact };
  SubstepLimitError(const std::string& what, Source s, int i, double sub, double n, double fluid_dt)
      : std::runtime_error(what), source(s), index(i), substep(sub), wanted(n), dt(fluid_dt) {}
  Source source;
  int index;       // constraint: its item in the scene's `constraints`; contact: the structure
  double substep;  // the largest stable substep it allows [s]
  double wanted;   // the substeps it needs in this fluid step
  double dt;       // the fluid step [s]
};

class BulletWorld;

class BodyCoupling final : public sph::StepCoupling {
 public:
  // At most this many body substeps in one fluid step (a constraint or contact past it is refused).
  static constexpr double kMaxSubsteps = 100000;
  // One entry per structure in scene order: a body for a free structure, none for a fixed one.
  // gravity [m/s^2].
  BodyCoupling(std::vector<std::optional<RigidBody>> bodies, const Eigen::Vector3d& gravity);
  ~BodyCoupling() override;

  // Bullet integrates the structures it has (their entries in `bodies` are then mirrors).
  void set_bullet(std::unique_ptr<BulletWorld> world);
  bool is_bullet(std::size_t k) const;
  BulletWorld* bullet() { return bullet_.get(); }
  const BulletWorld* bullet() const { return bullet_.get(); }
  // After a checkpoint restored the mirrors: Bullet takes their state (bullet_world.hpp).
  void restored();

  void after_kick(sph::Backend& backend, double half_dt) override;
  void after_drift(sph::Backend& backend, double dt) override;
  void after_forces(sph::Backend& backend) override;

  // Puts the particles where the bodies are now (move) or only gives them the bodies' velocity.
  void place(sph::Backend& backend, bool move) const;

  std::size_t structure_count() const { return bodies_.size(); }
  bool is_free(std::size_t k) const { return bodies_[k].has_value(); }
  const RigidBody& body(std::size_t k) const { return *bodies_[k]; }
  RigidBody& body(std::size_t k) { return *bodies_[k]; }
  // The fluid's force and torque about the centre of mass of body k from the last force pass
  // (zero for fixed structures), and the whole load its next kick uses (fluid + gravity).
  const Wrench& fluid_load(std::size_t k) const { return fluid_[k]; }
  Wrench total_load(std::size_t k) const;
  // Checkpoints: a resumed run gets back the last force pass's fluid loads, which the first kick
  // after the resume needs (the per-particle structure forces are not checkpointed).
  void restore_fluid_load(std::size_t k, const Wrench& w) { fluid_[k] = w; }

  // Prescribed structures as contact obstacles (body_contacts.hpp, bullet_world.hpp): where
  // structure k is at time t, and the solver's clock (t(n) during a step). The DEM contacts take
  // them at each substep's time, Bullet at the end of its step. Without it they stay at t = 0.
  using ObstacleMotionAt = std::function<ObstacleMotion(std::size_t structure, double t)>;
  void set_obstacle_motion(ObstacleMotionAt motion, std::function<double()> clock);

  // Fast forces (see above): constraints, and contacts (kept when some body has a contact material).
  void set_fast_forces(std::vector<BodyConstraint> constraints, std::unique_ptr<BodyContacts> contacts);
  bool has_fast_forces() const { return !constraints_.empty() || contacts_; }
  const std::vector<BodyConstraint>& constraints() const { return constraints_; }
  const BodyContacts* contacts() const { return contacts_.get(); }
  BodyContacts* contacts() { return contacts_.get(); }
  // The contact wrench on body k averaged over the last step (its impulse / dt) [N], [N m].
  const Wrench& contact_load(std::size_t k) const { return contact_mean_[k]; }
  void restore_contact_load(std::size_t k, const Wrench& w) { contact_mean_[k] = w; }
  // Body substeps of the last step, and the deepest contact overlap met in it [m].
  int last_substeps() const { return last_substeps_; }
  double last_max_overlap() const { return last_max_overlap_; }
  // The fast load (springs, pivots, contacts) on every structure now; `dt` advances the contacts'
  // tangential springs (0: evaluate only). `contact` receives the contact part alone when given.
  std::vector<Wrench> fast_load(double dt, std::vector<Wrench>* contact = nullptr);

 private:
  std::vector<std::optional<RigidBody>> bodies_;
  Eigen::Vector3d gravity_;
  std::vector<Wrench> fluid_;
  mutable std::vector<sph::BodyPlacement> placement_;
  std::vector<BodyConstraint> constraints_;
  std::unique_ptr<BodyContacts> contacts_;
  std::vector<Wrench> contact_mean_;
  int last_substeps_ = 0;
  double last_max_overlap_ = 0;
  std::unique_ptr<BulletWorld> bullet_;
  ObstacleMotionAt obstacle_motion_;
  std::function<double()> clock_;
  bool drifted_ = false;  // a drift since the last half-kick: the next half-kick is the step's second
};

}  // namespace turbid::fsi
