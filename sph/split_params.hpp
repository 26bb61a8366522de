// What a scene's transitions ask of the splitting pass (sph/splitting.hpp), and what a split step
// reports; plain values that backends and the time loop pass around.
#pragma once
#include <cstddef>
#include <cstdint>

#include "sph/config.hpp"

namespace turbid::sph {

constexpr int kMaxSplitRules = 4;

struct SplitRule {
  std::uint8_t from = 0;            // material whose particles split
  std::uint8_t to = 0;              // material of the daughters (same reference density)
  Real threshold = 0;               // effective shear stress sqrt(J2(tau)) above which a particle splits [Pa]
  bool interface_only = true;       // only particles with a fluid neighbour of a third material (not from, not to)
  Real min_smoothing_length = 0;    // only particles with h above this split (bounds the levels) [m]
};

struct SplitParams {
  int rule_count = 0;
  SplitRule rules[kMaxSplitRules];
  int relax_iterations = 10;  // Jacobi steps of the relaxation after a split (0: none; sph/splitting.hpp)
  Real relax_strength = Real(0.2);  // beta of the relaxation's displacement -beta h^2 grad(sum V W)
};

struct SplitCounts {
  std::size_t splits = 0;     // mothers split
  std::size_t daughters = 0;  // particles created, beyond the mothers' own slots
  std::size_t refused = 0;    // mothers that met the criterion but found no room in the store
  double smallest_h = 0;      // smallest smoothing length among the daughters [m]; 0: no split
};

}  // namespace turbid::sph
