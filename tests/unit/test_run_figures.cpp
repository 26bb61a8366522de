// The run's throughput figures count what they say (issue #24 item 3): particle-steps count every
// particle, fluid particle-steps only the fluid (walls are most of a small tank's particles).
// Reference: the particle counts of the world as built, times the steps taken.
#include <gtest/gtest.h>

#include <string>

#include "fsi/simulation.hpp"
#include "tests/unit/body_test_support.hpp"

namespace {

using namespace turbid;

TEST(RunFigures, FluidParticleStepsCountTheFluidOnly) {
  const std::string yaml = R"(name: tank
dimensions: 2
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
time: {end: 1.0}
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [0.6, 0.4]}
structures:
  - {name: post, box: {size: [0.06, 0.1]}, position: [0.4, 0.05]}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.3, 0.2]}}
)";
  fsi::Simulation sim(test::scene_of(yaml), test::cpu());
  sim.start();
  const auto& s = sim.summary();
  ASSERT_GT(s.wall_particles, 0u);
  ASSERT_GT(s.structure_particles, 0u);
  for (int k = 0; k < 10; ++k) sim.step();
  EXPECT_EQ(sim.particle_steps(), 10u * (s.fluid_particles + s.wall_particles + s.structure_particles));
  EXPECT_EQ(sim.fluid_particle_steps(), 10u * s.fluid_particles);
}

}  // namespace
