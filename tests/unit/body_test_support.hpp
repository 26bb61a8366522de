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

// Scene templates shared by the free-body and bullet-body tests (2D, dx = 0.02 m).
// A 0.1 m block of density 500 kg/m^3 falling under gravity far from a small pool of water; `motion`
// is written after 'motion: ' and `lock` after the density (e.g. ", lock: [y]").
inline std::string fall_scene(const std::string& motion, const std::string& lock = "") {
  return std::string(R"(
name: fall
dimensions: 2
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, -9.81]
materials:
  water: {density: 1000, sound_speed: 20}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.1, 0.1]}}
structures:
  - {name: block, box: {size: [0.1, 0.1]}, position: [1.0, 1.0], motion: )") +
         motion + ", density: 500" + lock + R"(}
domain: {min: [-0.5, -3], max: [1.5, 1.5]}
)";
}

// Without gravity, a 0.3 m block of water moving at 1 m/s along +x strikes a 0.1 m box (800 kg/m^3,
// turned 10 degrees); `boundary` is the wall treatment (dbc | mdbc).
inline std::string push_scene(const std::string& motion, const std::string& boundary) {
  return R"(
name: push
dimensions: 2
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, 0]
numerics: {boundary: {type: )" +
         boundary + R"(}}
materials:
  water: {density: 1000, sound_speed: 20}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.3, 0.3]}, initial_velocity: {direction: +x, mean: 1.0}}
structures:
  - {name: box, box: {size: [0.1, 0.1]}, position: [0.35, 0.2], rotation: 10, motion: )" +
         motion + R"(, density: 800}
domain: {min: [-1, -1], max: [2, 2]}
)";
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
