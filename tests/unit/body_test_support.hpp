// Helpers shared by the moving-body tests (test_body_coupling, test_body_contacts,
// test_bullet_coupling): a one-thread CPU run, a scene from YAML text, a text substitution for scene
// templates, and the particles' positions by id.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "tools/scene_reader.hpp"

namespace turbid::test {

inline fsi::RunOptions cpu() {
  fsi::RunOptions r;
  r.backend = "cpu";
  r.threads = 1;
  return r;
}

inline fsi::Scene scene_of(const std::string& yaml) { return tools::read_scene_string(yaml, "test.yaml"); }

// `s` with the first `what` replaced by `with` (scene templates with placeholders).
inline std::string replace(std::string s, const std::string& what, const std::string& with) {
  return s.replace(s.find(what), what.size(), with);
}

// Every particle's 2D position, indexed 2 id + axis.
inline std::vector<double> positions_by_id_2d(const fsi::Simulation& sim) {
  const auto& s = sim.store();
  const auto& ids = sim.fields();
  std::vector<double> out(2 * s.size());
  const auto* x = s.data<float>(ids.position);
  const auto* id = s.data<std::uint32_t>(ids.id);
  for (std::size_t i = 0; i < s.size(); ++i)
    for (int a = 0; a < 2; ++a) out[2 * id[i] + a] = x[2 * i + a];
  return out;
}

}  // namespace turbid::test
