// What a backend supplies to the time loop: neighbour search (sort by cell), the physics passes run
// over all particles, integration kernels and reductions. The physics itself lives in the shared
// headers (passes.hpp, pair_physics.hpp); a backend only decides where and how loops run.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sph/body_loads.hpp"
#include "sph/body_motion.hpp"
#include "sph/fields.hpp"
#include "sph/grid_layout.hpp"
#include "sph/open_boundary.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"
#include "sph/split_params.hpp"

namespace turbid::sph {


struct StepStats {
  double max_speed = 0;         // largest fluid speed [m/s]
  double max_acceleration = 0;  // largest fluid acceleration [m/s^2]
};

struct ViscousSolve {
  int iterations = 0;
  bool converged = true;
  double residual = 0;  // final relative residual |b - A x|_m / |b|_m
};

// What the impermeable-wall pass did to the fluid since the backend was bound (WallConstraintPass,
// booked by WallConstraintLoadPass): the momentum it took from the fluid, which walls and
// structures received [N s, 2D: N s/m], and the kinetic energy it removed [J, 2D: J/m].
struct WallConstraintTotals {
  double impulse[3] = {0, 0, 0};
  double energy = 0;
};

struct HealthIssue {
  std::size_t index = 0;  // position in the store
  std::uint32_t id = 0;   // particle id (stable across sorts)
  std::string field;
  double value = 0;
};

// The health check and the statistics the next time step needs, of one state.
struct StepCheck {
  std::optional<HealthIssue> issue;
  StepStats stats;
  // Particles that left the domain at a neighbour update inside the step and were counted only
  // now (Backend::update_neighbours_in_step); 0 on backends that count them at the update.
  std::size_t removed = 0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  virtual int threads() const = 0;
  virtual void bind(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain) = 0;
  // Sorts particles by cell and drops those outside the domain (or with non-finite position);
  // returns how many were dropped.
  virtual std::size_t update_neighbours() = 0;
  virtual void compute_density_rate() = 0;  // density gradient if needed, continuity with diffusion
  virtual void compute_forces() = 0;        // pressure from density, momentum
  virtual void kick(double half_dt) = 0;    // v += half_dt a (fluid)
  virtual void drift(double dt) = 0;        // x += dt v (fluid); rho += dt drho/dt (all)
  // Fluid particles the drift put back on a wall's surface since bind (impermeable walls; one per
  // particle and drift), a diagnostic of how much the walls' pressure alone would have let through.
  virtual std::uint64_t wall_put_backs() { return 0; }
  virtual WallConstraintTotals wall_constraint_totals() { return {}; }
  // A resumed run goes on adding to the checkpoint's totals (the same additions in the same order
  // as the run it continues: the same bits).
  virtual void restore_wall_constraint_totals(const WallConstraintTotals&) {}
  // After the drift, with open boundaries: particles crossing buffer-zone planes (open_boundary.hpp).
  virtual OpenBoundaryCounts update_open_boundaries() = 0;
  virtual StepStats stats() = 0;
  // First particle with a non-finite value or a density ratio |rho/rho0 - 1| above the limit.
  virtual std::optional<HealthIssue> check_health(double density_ratio_limit) = 0;
  // Both at once: the device backend does them in one reduction (one value back per step).
  virtual StepCheck check_step(double density_ratio_limit) {
    StepCheck c;
    c.issue = check_health(density_ratio_limit);
    if (!c.issue) c.stats = stats();
    return c;
  }
  // The neighbour update inside a time step, between the drift and the force pass: as
  // update_neighbours, but a backend may leave the count of the particles that left the domain to
  // the step's check_step (StepCheck::removed) instead of waiting for it here; the device backend
  // does, so that a step waits for the device once (issue #22). Returns the count it knows now.
  virtual std::size_t update_neighbours_in_step() { return update_neighbours(); }
  // Times the host has waited for the device since construction: a copy to or from device memory,
  // a reduction's value, a compaction's count, an algorithm run with a blocking policy (0 where
  // host and device are one). On the OpenMP device build it counts the calls that block on CUDA.
  virtual std::uint64_t host_waits() const { return 0; }
  virtual void sync_to_host() = 0;    // make the store current (no-op on the CPU)
  virtual void sync_from_host() = 0;  // the store was edited on the host (resume)
  // After a resume's neighbour update: rebuild whatever the last force pass left for the next
  // continuity pass (the CPU's neighbour list), so the resumed run matches bit for bit.
  virtual void prepare_resume() {}
  // Bytes copied between host and device memory since construction (0 where they are one).
  virtual std::uint64_t host_device_bytes() const { return 0; }
  // Blocks of device memory allocated for temporary storage (sorts, scans, reductions) since
  // construction; the device backend caches them, so steady steps add none (0 on the CPU).
  virtual std::size_t temporary_allocations() const { return 0; }
  // Bytes of device memory held now: buffers and cached temporary storage (0 on the CPU).
  virtual std::size_t device_bytes() const { return 0; }
  virtual std::size_t pair_count() = 0;  // neighbour pairs within the support in the last force pass
  // Force and torque of the fluid on each structure, from the last force pass (the exact reaction
  // of the fluid's accelerations); reference[k] is the point structure k's torque is taken about.
  virtual std::vector<BodyLoad> body_loads(const std::vector<std::array<double, 3>>& reference) = 0;
  // Moves the particles of every structure with bodies[k].moving rigidly with it and gives them its
  // velocity (sph/body_motion.hpp); needs the fields body_offset (and body_normal with mDBC). A
  // backend that cannot throws std::runtime_error; supports_moving_bodies says so beforehand.
  // move false: velocities only (the bodies were kicked, not drifted).
  virtual void place_bodies(const std::vector<BodyPlacement>& bodies, bool move);
  virtual bool supports_moving_bodies() const { return false; }
  // Splits the fluid particles that meet a rule (sph/splitting.hpp: flag, exclusive scan, ordered
  // writes; mothers beyond the store's capacity are refused). Reads the shear stress of the last
  // force pass. Afterwards the grid is stale: the caller updates neighbours and forces.
  virtual SplitCounts split(const SplitParams& rules);
  virtual bool supports_splitting() const { return false; }
  // Relaxes the daughters of the last split and the fluid around them (sph/splitting.hpp: the zone,
  // then rules.relax_iterations Jacobi steps); needs the neighbours updated after the split.
  // Returns the number of particles in the zone.
  virtual std::size_t relax_split(const SplitParams& rules);
  // The implicit viscous update of the materials marked implicit_viscosity (sph/implicit_viscosity.hpp),
  // on the velocities as they are, over dt, on the positions and neighbour list of the last force
  // pass. Structure particles take `share` x the reaction force (the share of the fluid step this
  // update covers) into the step's viscous load: the first update of a step into viscous_load, the
  // second into viscous_pending (ViscousReactionPass). Returns the conjugate-gradient iterations and
  // whether the tolerance was reached.
  virtual ViscousSolve solve_viscosity(double dt, double share, bool first_half);
  virtual bool supports_implicit_viscosity() const { return false; }
};

std::unique_ptr<Backend> make_cpu_backend(int threads);
bool cuda_backend_compiled();
// Number of CUDA devices usable now (0 without a driver/GPU or in a CPU-only build), with a reason.
int cuda_device_count(std::string* reason);
std::unique_ptr<Backend> make_cuda_backend();  // throws std::runtime_error if unavailable
// The device backend's code built for Thrust's OpenMP system ("device-omp", backend/omp_device/):
// the GPU code path run on CPU threads, so that it is tested without a GPU. Slower than "cpu".
bool omp_device_backend_compiled();
std::unique_ptr<Backend> make_omp_device_backend(int threads);  // throws std::runtime_error if not compiled

}  // namespace turbid::sph
