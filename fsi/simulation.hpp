// The Simulation: builds the particle world from a Scene, composes the fluid solver the scene
// needs, runs the time loop and hands results to observers (writers registered by tools/).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fsi/body_coupling.hpp"
#include "fsi/forces.hpp"
#include "fsi/mass_properties.hpp"
#include "fsi/prescribed_coupling.hpp"
#include "fsi/scene.hpp"
#include "fsi/wall_penetration.hpp"
#include "sph/backend.hpp"
#include "sph/backend/memory_plan.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/solver.hpp"

namespace turbid::fsi {

struct RunOptions {
  std::string backend = "auto";  // auto | cpu | cuda
  int threads = 0;               // CPU threads; 0 = OpenMP default
};

// A structure as sampled: what `turbid check` and run.json report.
struct StructureSummary {
  std::string name;
  std::size_t particles = 0;
  double surface_area = 0;  // of the sampled surface [m^2] (perimeter [m] in 2D)
  double volume = 0;        // of the sampled solid [m^3] (area [m^2] in 2D)
};

// A free (or bullet) structure's mass properties as the run uses them (sampled or from the scene).
struct FreeBodySummary {
  std::size_t structure = 0;  // index in scene.structures
  std::string name;
  MassProperties mass_properties;
};

// Counts and derived values a user sees in `turbid check` and run.json.
struct WorldSummary {
  std::size_t fluid_particles = 0;
  std::size_t wall_particles = 0;
  std::size_t structure_particles = 0;
  std::size_t buffer_particles = 0;  // open-boundary zones
  std::size_t fluid_removed_by_structures = 0;  // fluid lattice points inside or touching a structure
  double fluid_volume_restored = 0;  // the part of their cells outside the structures, given to neighbours [m^d]
  std::vector<StructureSummary> structures;
  std::vector<FreeBodySummary> free_bodies;
  std::vector<std::size_t> particles_per_material;
  double smoothing_length = 0;     // [m]
  std::vector<double> sound_speed; // per material [m/s]
  // On the CPU backend, per particle (sph/backend/memory_plan.hpp): fields, sort, neighbour list.
  sph::CpuMemory cpu_memory;
  // On a device backend (GPU, or device-omp): per particle of capacity (sph/backend/memory_plan.hpp).
  sph::DeviceMemory device_memory;
  sph::Domain domain;
  // "file:line:col: warning: ..." for layouts a user may mean but should know about (overlapping
  // fixed structures, fluid with nothing beneath it); `turbid check` and `run` print them.
  std::vector<std::string> warnings;
  // Each fluid block and box wall as stated and as built (issue #27 item 8): the lattice rounds a
  // box to whole cells from its min corner, so it may end up to dx/2 short or long per axis.
  struct Extent {
    std::string what;        // "fluid block" | "container" | "solid box"
    SourceLocation where;
    Box stated, built;       // built: the cells of its particles (a container: its inner box)
    double stated_volume = 0, built_volume = 0;  // [m^d]; fluid: particles' volume, walls: inner/solid
  };
  std::vector<Extent> extents;
  std::size_t fluid_removed_by_walls = 0;  // fluid lattice points whose cells lie mostly in a wall's cells
};

class Simulation;

// Receives the run's events. Called on the host with the store synchronised.
class Observer {
 public:
  virtual ~Observer() = default;
  virtual void on_output(Simulation&) {}      // at t = 0 and every output interval
  virtual void on_checkpoint(Simulation&) {}  // every checkpoint interval
  virtual void on_progress(const Simulation&) {}  // about twice a second of wall time
  virtual void on_forces(Simulation&) {}          // every forces interval (scenes with structures)
  virtual void on_probes(Simulation&) {}          // every probes interval (scenes with probes)
  virtual void on_finish(Simulation&) {}
  // Polled after each step's outputs; true ends the run there, after an on_checkpoint (the
  // runner answers Ctrl-C and SIGTERM this way, so the work up to that step is kept).
  virtual bool stop_requested() const { return false; }
};

// The mass properties of a free structure: from its filled sampling at the scene's spacing and its
// density (or mass / sampled volume), with the scene's centre of mass (the sampled inertia moved to
// it by the parallel-axis theorem) and inertia where given. Throws std::invalid_argument.
MassProperties structure_mass_properties(const Scene& scene, const StructureSpec& st);
// Structures coupled to the fluid as rigid bodies: motion free or bullet.
bool has_free_structures(const Scene& scene);
bool has_bullet_structures(const Scene& scene);

// Resolves scene defaults (automatic sound speed, wall layers) and converts to engine parameters.
sph::PhysicsParams physics_params(const Scene& scene);
int wall_layers(const Scene& scene, const WallSpec& wall);
// The splitting rules of the scene's transitions (material indices, level bound).
sph::SplitParams split_params(const Scene& scene);
// Particles the store reserves room for: the initial count, or with transitions the scene's capacity.
std::size_t particle_capacity(const Scene& scene, std::size_t initial);

class Simulation {
 public:
  // Builds particles; throws std::invalid_argument with a readable message for impossible geometry.
  Simulation(Scene scene, const RunOptions& options);

  const Scene& scene() const { return scene_; }
  const WorldSummary& summary() const { return summary_; }
  sph::ParticleStore& store() { return store_; }
  const sph::ParticleStore& store() const { return store_; }
  const sph::FieldIds& fields() const { return ids_; }
  const sph::PhysicsParams& params() const { return params_; }
  sph::Backend& backend() { return solver_->backend(); }
  std::string backend_name() const { return backend_name_; }
  int threads() const { return threads_; }

  double time() const { return solver_->time(); }
  double end_time() const { return scene_.end_time; }
  std::uint64_t steps() const { return solver_->steps(); }
  std::uint64_t removed() const { return solver_->removed(); }
  std::uint64_t inflow() const { return solver_->inflow(); }    // particles created at inlets
  std::uint64_t outflow() const { return solver_->outflow(); }  // particles gone through outlets
  void restore_open_boundary_counts(std::uint64_t inflow, std::uint64_t outflow) {
    solver_->restore_open_boundary_counts(inflow, outflow);
  }
  double last_time_step() const { return solver_->last_time_step(); }
  // Splitting since the start (transitions): splits, daughters, refused splits.
  const sph::SplitCounts& split_totals() const { return solver_->split_totals(); }
  double split_seconds() const { return solver_->split_seconds(); }  // [s], this process
  const sph::Solver& solver() const { return *solver_; }
  double step_seconds() const { return solver_->step_seconds(); }    // [s], this process, with transitions
  void restore_split_totals(const sph::SplitCounts& c) { solver_->restore_split_totals(c); }
  double wall_seconds() const { return wall_seconds_; }
  double particle_steps_per_second() const;
  // Steps times fluid particles (not walls, structures or buffers), per second of wall time.
  double fluid_particle_steps_per_second() const;
  std::uint64_t fluid_particle_steps() const { return fluid_particle_steps_; }
  void restore_fluid_particle_steps(std::uint64_t n) { fluid_particle_steps_ = n; }
  // Fluid particles impermeable walls put back on a surface, summed over the drifts of the whole
  // run (a particle counts once per drift); 0 with `impermeable: false`.
  std::uint64_t wall_put_backs() { return wall_put_backs_before_ + solver_->backend().wall_put_backs(); }
  void restore_wall_put_backs(std::uint64_t n) { wall_put_backs_before_ = n; }
  // What those put-backs took from the fluid over the whole run: the momentum the walls and
  // structures received (booked on them, in forces.csv and bodies' loads) and the kinetic energy.
  sph::WallConstraintTotals wall_constraint_totals() { return solver_->backend().wall_constraint_totals(); }
  void restore_wall_constraint_totals(const sph::WallConstraintTotals& t) {
    solver_->backend().restore_wall_constraint_totals(t);
  }

  // Output bookkeeping, saved in checkpoints so a resumed run writes the same frames.
  std::uint64_t output_index() const { return output_index_; }
  std::uint64_t checkpoint_index() const { return checkpoint_index_; }
  std::uint64_t particle_steps() const { return particle_steps_; }

  // Fresh start: forces at t = 0. Or continue after the store was filled from a checkpoint.
  void start();
  void resume(double time, std::uint64_t steps, std::uint64_t removed, std::uint64_t output_index,
              std::uint64_t checkpoint_index, std::uint64_t particle_steps, double wall_seconds = 0);

  // Runs to the end time; throws sph::BlowUp (after telling no observer) on a numerical failure.
  void run(Observer& observer);
  // The last run() ended early because its observer asked it to stop.
  bool interrupted() const { return interrupted_; }
  void step();  // one stable time step
  // One time step of at most max_dt [s] (run() lands its last step on the end time this way).
  void step(double max_dt);

  std::vector<double> probe_values();  // evaluated now (synchronises the store)
  // Force and torque of the fluid on every structure (scene order), from the last force pass.
  // Free structures: torque about the body's current centre of mass.
  std::vector<sph::BodyLoad> structure_loads();
  // One per structure (forces.csv); zeros for fixed ones.
  std::vector<BodyKinematics> body_kinematics() const;
  // The rigid bodies of the free structures; nullptr when every structure is fixed.
  const BodyCoupling* bodies() const { return bodies_.get(); }
  BodyCoupling* bodies() { return bodies_.get(); }
  // The prescribed structures' paths; nullptr when none is prescribed.
  const PrescribedCoupling* prescribed() const { return prescribed_.get(); }
  std::uint64_t forces_index() const { return forces_index_; }
  void sync_to_host() { solver_->backend().sync_to_host(); }
  // Fluid particles behind a wall or structure surface now (fsi/wall_penetration.hpp; synchronises
  // the store). run() measures it at every output; the last measurement is fluid_behind_walls().
  FluidBehindWalls measure_fluid_behind_walls();
  const FluidBehindWalls& fluid_behind_walls() const { return behind_walls_; }

 private:
  void build_particles();
  void check_fluid_behind_walls();

  Scene scene_;
  sph::PhysicsParams params_;
  sph::ParticleStore store_;
  sph::FieldIds ids_;
  WorldSummary summary_;
  std::vector<std::vector<Eigen::Vector3d>> surface_layers_;  // per structure, layer 0 at t = 0 (contacts)
  std::unique_ptr<BodyCoupling> bodies_;  // before solver_: the solver points at it
  std::unique_ptr<PrescribedCoupling> prescribed_;  // motion: prescribed (prescribed_coupling.hpp)
  std::unique_ptr<CouplingChain> chain_;            // free and prescribed bodies in one scene
  std::unique_ptr<sph::Solver> solver_;
  std::string backend_name_;
  int threads_ = 1;
  double wall_seconds_ = 0;
  std::uint64_t output_index_ = 0;
  std::uint64_t checkpoint_index_ = 0;
  std::uint64_t forces_index_ = 0;
  std::uint64_t probes_index_ = 0;
  std::uint64_t particle_steps_ = 0;
  std::uint64_t fluid_particle_steps_ = 0;
  std::uint64_t wall_put_backs_before_ = 0;  // from the checkpoint a run resumed from
  bool interrupted_ = false;
  // Ghost offsets at t = 0 of the wall and structure particles (ids from boundary_first_id_ on):
  // the surfaces the count of fluid behind walls measures against.
  std::vector<std::array<float, 3>> boundary_ghost0_;
  std::uint32_t boundary_first_id_ = 0;
  FluidBehindWalls behind_walls_;
};

// The smallest k >= from with k * every > time [s]: the index of the next entry of a periodic
// output schedule, in constant time whatever time / every is.
std::uint64_t next_index_after(double time, double every, std::uint64_t from);

}  // namespace turbid::fsi
