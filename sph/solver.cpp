// Kick-drift-kick time loop; see solver.hpp.
#include "sph/solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace turbid::sph {

double stable_time_step(const PhysicsParams& p, const TimeStepParams& t, double max_speed, double max_acceleration) {
  // Each material with the smallest h among its particles (daughters of a split have half their
  // mother's); max_speed and max_acceleration are the largest over all fluid particles.
  double dt = std::numeric_limits<double>::infinity();
  for (int m = 0; m < p.material_count; ++m) {
    const MaterialParams& M = p.materials[m];
    const double h = M.min_smoothing_length > 0 ? double(M.min_smoothing_length) : double(p.smoothing_length);
    const double nu = double(M.dynamic_viscosity) / double(M.eos.rest_density);
    dt = std::min(dt, t.cfl * h / (double(M.sound_speed) + max_speed));
    if (max_acceleration > 0) dt = std::min(dt, t.cfl * std::sqrt(h / max_acceleration));
    // An implicitly integrated material sets no viscous limit (sph/implicit_viscosity.hpp).
    if (p.viscosity == Viscosity::laminar && nu > 0 && !M.implicit_viscosity)
      dt = std::min(dt, t.viscous_factor * h * h / nu);
  }
  return dt;
}

Solver::Solver(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain,
               const TimeStepParams& time_params, std::unique_ptr<Backend> backend)
    : store_(store), ids_(ids), params_(params), time_params_(time_params), backend_(std::move(backend)) {
  backend_->bind(store_, ids_, params_, domain);
}

void Solver::start() {
  removed_ += backend_->update_neighbours();
  backend_->compute_forces();
  if (coupling_) coupling_->after_forces(*backend_);
  check("the initial state, step");
}

void Solver::resume(double time, std::uint64_t steps, std::uint64_t removed) {
  time_ = time;
  steps_ = steps;
  removed_ = removed;
  checked_stats_.reset();
  backend_->sync_from_host();
  // Rebuild the grid of the restored positions; they were sorted when saved, and the stable sort
  // keeps that order, so the run continues exactly as if it had not stopped.
  backend_->update_neighbours();
  backend_->prepare_resume();
}

double Solver::next_time_step() {
  const StepStats s = checked_stats_ ? *checked_stats_ : backend_->stats();
  return stable_time_step(params_, time_params_, s.max_speed, s.max_acceleration);
}

void Solver::step(double dt) {
  const auto step_start = std::chrono::steady_clock::now();
  if (!(dt >= time_params_.min_time_step)) {
    std::ostringstream os;
    os << "time step collapsed to " << dt << " s (limit " << time_params_.min_time_step << " s) at step " << steps_
       << ", t = " << time_ << " s";
    throw BlowUp(os.str());
  }
  checked_stats_.reset();
  backend_->kick(0.5 * dt);
  if (coupling_) coupling_->after_kick(*backend_, 0.5 * dt);
  // The stiff viscous terms over half a step after each half-kick (K/2 V/2 D F K/2 V/2: a
  // first-order operator splitting, not Strang's symmetric one): the drift moves a plug with the
  // velocity the viscous update left it, and the step ends with velocities the viscous terms have
  // seen (a plug held by its yield stress shows no g dt / 2 of the kick).
  if (params_.implicit_viscosity) solve_viscosity(0.5 * dt, true);
  backend_->compute_density_rate();
  backend_->drift(dt);
  if (coupling_) coupling_->after_drift(*backend_, dt);
  if (params_.zone_count > 0) {
    const OpenBoundaryCounts c = backend_->update_open_boundaries();
    inflow_ += c.inflow;
    outflow_ += c.outflow;
  }
  removed_ += backend_->update_neighbours_in_step();
  backend_->compute_forces();
  if (coupling_) coupling_->after_forces(*backend_);
  backend_->kick(0.5 * dt);
  if (coupling_) coupling_->after_kick(*backend_, 0.5 * dt);
  if (params_.implicit_viscosity) solve_viscosity(0.5 * dt, false);
  time_ += dt;
  last_dt_ = dt;
  ++steps_;
  check("step");
  if (split_.rule_count > 0) {
    // The splitting pass's share of the step (docs/performance.md): wall time of the split, the
    // relaxation and the rebuild after it, against the whole step's.
    const auto t0 = std::chrono::steady_clock::now();
    split();
    const auto t1 = std::chrono::steady_clock::now();
    split_seconds_ += std::chrono::duration<double>(t1 - t0).count();
    step_seconds_ += std::chrono::duration<double>(t1 - step_start).count();
  }
}

void Solver::solve_viscosity(double dt, bool first_half) {
  // dt is half the step: the reaction on structures counts half towards the step's load. With a
  // time step that changes from one step to the next, the second half's share is delivered over
  // the next step: its impulse is off by (dt_next - dt) / (2 dt) of that share (the CFL limit
  // changes dt smoothly; docs/choices.md).
  const ViscousSolve v = backend_->solve_viscosity(dt, 0.5, first_half);
  ++viscous_solves_;
  viscous_iterations_ += std::uint64_t(v.iterations);
  viscous_iterations_max_ = std::max(viscous_iterations_max_, v.iterations);
  if (!v.converged) ++viscous_unconverged_;
}

void Solver::split() {
  const SplitCounts c = backend_->split(split_);
  split_totals_.splits += c.splits;
  split_totals_.daughters += c.daughters;
  split_totals_.refused += c.refused;
  if (c.splits > 0) {
    // Daughters have half their mother's h: their materials' time-step limits follow it.
    split_totals_.smallest_h =
        split_totals_.smallest_h > 0 ? std::min(split_totals_.smallest_h, c.smallest_h) : c.smallest_h;
    lower_daughter_h(split_totals_.smallest_h);
    // The grid and the accelerations are those of the particles before the split; the relaxation
    // needs the daughters in the grid, and moves the particles around them.
    removed_ += backend_->update_neighbours();
    if (split_.relax_iterations > 0 && backend_->relax_split(split_) > 0) removed_ += backend_->update_neighbours();
    backend_->compute_forces();
    // A body's next half-kick takes the fluid's load on the particles as they are now, as the fluid's does.
    if (coupling_) coupling_->after_forces(*backend_);
    check("the split after step");
  }
  if (c.refused > 0 && split_error_when_full_) {
    std::ostringstream os;
    os << "particle capacity exhausted at step " << steps_ << " (t = " << time_ << " s): " << c.refused
       << " splits refused (store full at " << store_.capacity()
       << " particles); raise 'capacity' in the scene, or set on_full: warn to go on without them";
    throw BlowUp(os.str());
  }
}

void Solver::lower_daughter_h(double h) {
  for (int r = 0; r < split_.rule_count; ++r) {
    MaterialParams& M = params_.materials[split_.rules[r].to];
    if (M.min_smoothing_length == Real(0) || Real(h) < M.min_smoothing_length) M.min_smoothing_length = Real(h);
  }
}

void Solver::check(const char* phase) {
  StepCheck c = backend_->check_step(time_params_.density_ratio_limit);
  removed_ += c.removed;
  if (auto& issue = c.issue) {
    checked_stats_.reset();  // stats of a state that failed its check: not for the next step
    std::ostringstream os;
    os << "numerical blow-up after " << phase << " " << steps_ << " (t = " << time_ << " s): particle id " << issue->id
       << " has " << issue->field << " = " << issue->value;
    if (issue->field == "density")
      os << " (outside rest density x (1 +/- " << time_params_.density_ratio_limit << "))";
    throw BlowUp(os.str());
  }
  checked_stats_ = c.stats;
}

}  // namespace turbid::sph
