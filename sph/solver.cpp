// Kick-drift-kick time loop; see solver.hpp.
#include "sph/solver.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace turbid::sph {

double stable_time_step(const PhysicsParams& p, const TimeStepParams& t, double max_speed, double max_acceleration) {
  const double h = p.smoothing_length;
  double c_max = 0, nu_max = 0;
  for (int m = 0; m < p.material_count; ++m) {
    c_max = std::max(c_max, double(p.materials[m].sound_speed));
    nu_max = std::max(nu_max, double(p.materials[m].dynamic_viscosity) / double(p.materials[m].eos.rest_density));
  }
  double dt = t.cfl * h / (c_max + max_speed);
  if (max_acceleration > 0) dt = std::min(dt, t.cfl * std::sqrt(h / max_acceleration));
  if (p.viscosity == Viscosity::laminar && nu_max > 0) dt = std::min(dt, t.viscous_factor * h * h / nu_max);
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
  check("the initial state, step");
}

void Solver::resume(double time, std::uint64_t steps, std::uint64_t removed) {
  time_ = time;
  steps_ = steps;
  removed_ = removed;
  backend_->sync_from_host();
  // Rebuild the grid of the restored positions; they were sorted when saved, and the stable sort
  // keeps that order, so the run continues exactly as if it had not stopped.
  backend_->update_neighbours();
  backend_->prepare_resume();
}

double Solver::next_time_step() {
  const StepStats s = backend_->stats();
  return stable_time_step(params_, time_params_, s.max_speed, s.max_acceleration);
}

void Solver::step(double dt) {
  if (!(dt >= time_params_.min_time_step)) {
    std::ostringstream os;
    os << "time step collapsed to " << dt << " s (limit " << time_params_.min_time_step << " s) at step " << steps_
       << ", t = " << time_ << " s";
    throw BlowUp(os.str());
  }
  backend_->kick(0.5 * dt);
  backend_->compute_density_rate();
  backend_->drift(dt);
  if (params_.zone_count > 0) {
    const OpenBoundaryCounts c = backend_->update_open_boundaries();
    inflow_ += c.inflow;
    outflow_ += c.outflow;
  }
  removed_ += backend_->update_neighbours();
  backend_->compute_forces();
  backend_->kick(0.5 * dt);
  time_ += dt;
  last_dt_ = dt;
  ++steps_;
  check("step");
}

void Solver::check(const char* phase) {
  if (auto issue = backend_->check_health(time_params_.density_ratio_limit)) {
    std::ostringstream os;
    os << "numerical blow-up after " << phase << " " << steps_ << " (t = " << time_ << " s): particle id " << issue->id
       << " has " << issue->field << " = " << issue->value;
    if (issue->field == "density")
      os << " (outside rest density x (1 +/- " << time_params_.density_ratio_limit << "))";
    throw BlowUp(os.str());
  }
}

}  // namespace turbid::sph
