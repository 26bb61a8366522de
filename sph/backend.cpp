// Defaults of the Backend interface for what a backend may not offer yet.
#include "sph/backend.hpp"

#include <stdexcept>

namespace turbid::sph {

SplitCounts Backend::split(const SplitParams&) {
  throw std::logic_error("particle splitting is not implemented on the " + name() + " backend yet");
}

std::size_t Backend::relax_split(const SplitParams&) {
  throw std::logic_error("the relaxation after a split is not implemented on the " + name() + " backend yet");
}

ViscousSolve Backend::solve_viscosity(double, double, bool) {
  throw std::runtime_error("implicit viscosity is not implemented on the " + name() + " backend yet; use --backend cpu");
}

void Backend::place_bodies(const std::vector<BodyPlacement>&, bool) {
  throw std::runtime_error("moving structures (motion: free) are not implemented on the " + name() +
                           " backend yet; use --backend cpu");
}

}  // namespace turbid::sph
