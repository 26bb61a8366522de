// The time loop of the fluid: kick-drift-kick (Stormer-Verlet) integration in which density is
// a coordinate, drifted with the half-step velocity like position:
//
//   v(n+1/2) = v(n) + dt/2 a(n)
//   drho     = continuity + diffusion at x(n) with v(n+1/2)      (grid of x(n) reused)
//   x(n+1)   = x(n) + dt v(n+1/2),  rho(n+1) = rho(n) + dt drho
//   neighbour update (sort, drop particles outside the domain)
//   a(n+1)   = momentum at x(n+1), rho(n+1), v(n+1/2)
//   v(n+1)   = v(n+1/2) + dt/2 a(n+1)
//
// Kicking density and velocity together from the same evaluation would integrate the acoustic
// pair (rho, v) like explicit Euler, which grows without bound; drifting rho with the new
// velocity keeps the scheme symplectic for it (checked by the hydrostatic tank test).
// The variable time step comes from the CFL, force and viscous limits.
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "sph/backend.hpp"

namespace turbid::sph {

struct TimeStepParams {
  double cfl = 0.2;
  double viscous_factor = 0.125;
  double min_time_step = 1e-9;
  double density_ratio_limit = 0.5;
};

// A numerical blow-up; what() says where and when.
struct BlowUp : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// dt limits (Monaghan 1992; Morris et al. 1997) for every material, with its own smallest h, sound
// speed and (largest) viscosity: acoustic h / (c + v_max), force sqrt(h / a_max), both times the CFL
// number, and the viscous limit factor * h^2 / nu for laminar viscosity.
double stable_time_step(const PhysicsParams& p, const TimeStepParams& t, double max_speed, double max_acceleration);

// Something integrated in step with the fluid (fsi's rigid bodies): called inside Solver::step at
// the points of the kick-drift-kick scheme, after the fluid's own kick, drift and force pass, with
// the backend that holds the particles. The fluid knows nothing else about it.
class StepCoupling {
 public:
  virtual ~StepCoupling() = default;
  virtual void after_kick(Backend& backend, double half_dt) = 0;
  virtual void after_drift(Backend& backend, double dt) = 0;
  virtual void after_forces(Backend& backend) = 0;  // also after the force pass at the start
};

class Solver {
 public:
  Solver(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain,
         const TimeStepParams& time_params, std::unique_ptr<Backend> backend);

  // Fresh start: neighbour update and forces at t = 0.
  void start();
  // Continue from a restored store whose accelerations and rates are those of `time`.
  void resume(double time, std::uint64_t steps, std::uint64_t removed);

  double next_time_step();  // from the current state
  void step(double dt);     // throws BlowUp

  double time() const { return time_; }
  std::uint64_t steps() const { return steps_; }
  std::uint64_t removed() const { return removed_; }
  std::uint64_t inflow() const { return inflow_; }    // particles created at inlets
  std::uint64_t outflow() const { return outflow_; }  // particles gone through outlets
  // A resumed run continues the open-boundary counts of the run that wrote the checkpoint.
  void restore_open_boundary_counts(std::uint64_t inflow, std::uint64_t outflow) {
    inflow_ = inflow;
    outflow_ = outflow;
  }
  double last_time_step() const { return last_dt_; }
  // Splitting (sph/splitting.hpp) after every step, by these rules; error_when_full: a refused
  // split stops the run (BlowUp) instead of being counted.
  void set_splitting(const SplitParams& rules, bool error_when_full) {
    split_ = rules;
    split_error_when_full_ = error_when_full;
  }
  const SplitCounts& split_totals() const { return split_totals_; }  // since the start of the run
  // Wall time spent splitting (flag, insertion, relaxation, rebuild) and in whole steps since the
  // start of this process's run [s]; measured only with transitions.
  double split_seconds() const { return split_seconds_; }
  // Implicit viscosity, since this process started: the solves (two per step), their
  // conjugate-gradient iterations, the most in one solve, and the solves that stopped at the
  // iteration limit above the tolerance.
  std::uint64_t viscous_solves() const { return viscous_solves_; }
  std::uint64_t viscous_iterations() const { return viscous_iterations_; }
  int viscous_iterations_max() const { return viscous_iterations_max_; }
  std::uint64_t viscous_unconverged() const { return viscous_unconverged_; }
  double step_seconds() const { return step_seconds_; }
  void restore_split_totals(const SplitCounts& c) {
    split_totals_ = c;
    if (c.smallest_h > 0) lower_daughter_h(c.smallest_h);
  }
  // Not owned; must outlive the solver. nullptr: none (the default, nothing is called).
  void set_coupling(StepCoupling* coupling) { coupling_ = coupling; }
  Backend& backend() { return *backend_; }
  const PhysicsParams& params() const { return params_; }

 private:
  void check(const char* phase);
  void split();
  void lower_daughter_h(double h);  // the rules' daughter materials have particles of this h [m]

  ParticleStore& store_;
  FieldIds ids_;
  PhysicsParams params_;
  TimeStepParams time_params_;
  std::unique_ptr<Backend> backend_;
  StepCoupling* coupling_ = nullptr;
  SplitParams split_;
  bool split_error_when_full_ = false;
  SplitCounts split_totals_;
  void solve_viscosity(double dt, bool first_half);
  double split_seconds_ = 0;  // wall time in split() (with transitions only) [s]
  std::uint64_t viscous_solves_ = 0, viscous_iterations_ = 0, viscous_unconverged_ = 0;
  int viscous_iterations_max_ = 0;
  double step_seconds_ = 0;   // wall time of the steps, split included (with transitions only) [s]
  double time_ = 0;
  double last_dt_ = 0;
  std::uint64_t steps_ = 0;
  std::uint64_t removed_ = 0;
  std::uint64_t inflow_ = 0;
  std::uint64_t outflow_ = 0;
  // The statistics of the state check() last saw healthy, for next_time_step(); cleared when a step begins.
  std::optional<StepStats> checked_stats_;
};

}  // namespace turbid::sph
