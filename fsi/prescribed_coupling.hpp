// Moves the structures with `motion: prescribed` (prescribed_path.hpp) inside the fluid's
// kick-drift-kick step (sph/solver.hpp, StepCoupling), lined up with the free bodies of
// body_coupling.hpp so that the fluid sees a prescribed body exactly as it would see a free body
// following the same path. With t(n) the solver's time at the start of the step:
//   after the first half-kick:  the particles take the path's velocity at t(n) + dt/2
//                               (v = d' + w x R r0, R at t(n) where they still are), as a free
//                               body's carry v(n+1/2);
//   after the drift:            the particles are placed at t(n+1) = t(n) + dt, x = x_ref + d + R r0,
//                               keeping the half-step velocity: the density rate and the forces of
//                               the new step see positions at t(n+1) and velocities at t(n+1/2),
//                               the fluid's own particles' alignment. The path's velocity at the
//                               half step is its mean velocity over the step to O(dt^2), so the
//                               velocity the walls carry is consistent with how they moved;
//   after the second half-kick: the particles take the path's velocity at t(n+1) (outputs,
//                               forces.csv and checkpoints show the state at t(n+1)).
// Positions and velocities come from the path at the solver's time each step (never accumulated),
// so a resumed run needs no state beyond the time and the particles. Nothing happens after the
// force pass: the fluid's load is only reported (Simulation::structure_loads, torque about the
// moving reference point). No I/O here.
#pragma once
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "fsi/forces.hpp"
#include "fsi/prescribed_path.hpp"
#include "sph/backend.hpp"
#include "sph/fields.hpp"
#include "sph/grid_layout.hpp"
#include "sph/particle_store.hpp"
#include "sph/solver.hpp"

namespace turbid::fsi {

struct PrescribedBody {
  PrescribedPath path;
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // the reference point at t = 0 [m]
};

bool has_prescribed_structures(const Scene& scene);

// The first time in [0, end] at which a particle of the body (its offsets r0 from the reference
// point) leaves the domain on an axis that is not periodic, or a negative number when none does.
// Checked at `count` even steps and at the path's sample times: particles that leave the domain are
// removed from the run, so a path that would carry the structure out is refused before it starts.
double first_exit_time(const PrescribedBody& body, const std::vector<Eigen::Vector3d>& offsets, int dims,
                       const sph::Domain& domain, double end, int count = 1000);

class PrescribedCoupling final : public sph::StepCoupling {
 public:
  // One entry per structure in scene order (none for structures that are not prescribed).
  // `clock` gives the solver's time, t(n) during a step.
  PrescribedCoupling(std::vector<std::optional<PrescribedBody>> bodies, std::function<double()> clock);

  void after_kick(sph::Backend& backend, double half_dt) override;
  void after_drift(sph::Backend& backend, double dt) override;
  void after_forces(sph::Backend&) override {}

  // Places the particles at time t with the path's velocity at t (the start of a run).
  void place_at(sph::Backend& backend, double t) const { place(backend, t, t, true); }

  std::size_t structure_count() const { return bodies_.size(); }
  bool is_prescribed(std::size_t k) const { return bodies_[k].has_value(); }
  // The reference point of structure k at time t [m], and its kinematics for forces.csv
  // (position: the reference point; orientation: R(t) as a unit quaternion).
  Eigen::Vector3d reference_point(std::size_t k, double t) const;
  BodyKinematics kinematics(std::size_t k, double t) const;

 private:
  // Positions (when `move`) and the lever arms R r0 of the velocities from the path at t_position;
  // the velocity and angular velocity at t_velocity.
  void place(sph::Backend& backend, double t_position, double t_velocity, bool move) const;

  std::vector<std::optional<PrescribedBody>> bodies_;
  std::function<double()> clock_;
  bool drifted_ = false;  // between the drift and the second half-kick of a step
  double half_time_ = 0;  // t(n) + dt/2 of the step in progress
  double new_time_ = 0;   // t(n) + dt
  mutable std::vector<sph::BodyPlacement> placement_;
};

// The coupling of a scene's prescribed structures, from the store as built (the structure
// particles' offsets r0, fields body_offset and body). Throws std::invalid_argument
// "FILE:LINE:COL: error: structure 'NAME': ..." at the structure's path for a path it cannot follow
// or one that leaves `domain` before the scene's end time (first_exit_time).
std::unique_ptr<PrescribedCoupling> make_prescribed_coupling(const Scene& scene, const sph::ParticleStore& store,
                                                             const sph::FieldIds& ids, const sph::Domain& domain,
                                                             std::function<double()> clock);

// Runs several couplings in turn (free and prescribed bodies in one scene); each places only its
// own structures' particles.
class CouplingChain final : public sph::StepCoupling {
 public:
  void add(sph::StepCoupling* c) { links_.push_back(c); }
  void after_kick(sph::Backend& b, double half_dt) override {
    for (auto* c : links_) c->after_kick(b, half_dt);
  }
  void after_drift(sph::Backend& b, double dt) override {
    for (auto* c : links_) c->after_drift(b, dt);
  }
  void after_forces(sph::Backend& b) override {
    for (auto* c : links_) c->after_forces(b);
  }

 private:
  std::vector<sph::StepCoupling*> links_;
};

}  // namespace turbid::fsi
