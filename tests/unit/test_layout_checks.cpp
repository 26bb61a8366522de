// Layouts that cannot be meant are refused with the scene line, those that may be are warned about
// (issue #27 item 2; fsi::Simulation's check_layout on the particles as built): a structure outside
// the domain, structures inside each other or inside a wall, a wall drawn through fluid (errors or
// warnings as each test says), fluid with nothing beneath it (a warning: a falling jet may be
// meant). Reference: the geometry as stated in each scene below (the expected counts follow from
// the lattice); every shipped scene passes with no warning (`turbid check scenes/*.yaml`).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "fsi/simulation.hpp"
#include "tests/unit/body_test_support.hpp"

namespace {

using namespace turbid;
using test::cpu;
using test::scene_of;

// A 2D scene's head: spacing dx [m], water of sound speed c0 [m/s]; fluids, walls and the rest follow.
std::string head(const std::string& name, const std::string& dx, const std::string& c0) {
  return "name: " + name + "\ndimensions: 2\nresolution: {particle_spacing: " + dx +
         ", smoothing_ratio: 1.3}\ntime: {end: 0.01}\nmaterials:\n  water: {density: 1000, sound_speed: " + c0 + "}\n";
}

// A 1 x 0.6 m tank with 0.4 x 0.3 m of water at dx = 0.02 m; `extra` is appended (walls, structures).
std::string tank(const std::string& walls_extra, const std::string& rest, const std::string& domain = "") {
  return head("layout", "0.02", "20") + R"(fluids:
  - {material: water, box: {min: [0, 0], max: [0.4, 0.3]}}
walls:
  - box: {min: [0, 0], max: [1.0, 0.6]}
)" + walls_extra + rest + domain;
}

// The message of the std::invalid_argument that building the scene throws ("" if none).
std::string refusal(const std::string& yaml) {
  try {
    fsi::Simulation sim(scene_of(yaml), cpu());
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// 1-based line of the first occurrence of `text` in the scene.
int line_of(const std::string& yaml, const std::string& text) {
  return 1 + int(std::count(yaml.begin(), yaml.begin() + long(yaml.find(text)), '\n'));
}

void expect_at(const std::string& message, const std::string& yaml, const std::string& text, const char* kind) {
  const std::string at = "test.yaml:" + std::to_string(line_of(yaml, text)) + ":";
  EXPECT_EQ(message.rfind(at, 0), 0u) << "'" << at << "' at the start of: " << message;
  EXPECT_NE(message.find(std::string(": ") + kind + ": "), std::string::npos) << message;
}

// The one warning building the scene gives ("" and a failure if it gives none or several).
std::string only_warning(const std::string& yaml) {
  const fsi::Simulation sim(scene_of(yaml), cpu());
  const auto& w = sim.summary().warnings;
  if (w.size() != 1) {
    ADD_FAILURE() << w.size() << " warnings, expected 1";
    return "";
  }
  std::printf("[ measured ] %s\n", w[0].c_str());
  return w[0];
}

TEST(LayoutChecks, AStructureReachingOutOfTheDomainIsRefused) {
  const std::string yaml = tank("", "structures:\n  - {name: post, box: {size: [0.1, 0.2]}, position: [0.7, 0.55]}\n",
                                "domain: {min: [-0.1, -0.1], max: [1.1, 0.62]}\n");
  const std::string m = refusal(yaml);
  std::printf("[ measured ] %s\n", m.c_str());
  expect_at(m, yaml, "  - {name: post", "error");
  EXPECT_NE(m.find("structure 'post' reaches outside 'domain' along y"), std::string::npos) << m;
}

TEST(LayoutChecks, AMovingStructureInsideAnotherIsRefusedFixedOnesAreWarnedAbout) {
  const std::string two = "structures:\n  - {name: a, box: {size: [0.2, 0.2]}, position: [0.7, 0.3]}\n"
                          "  - {name: b, sphere: {radius: 0.08}, position: [0.75, 0.3]MOTION}\n";
  const std::string fixed = tank("", test::replace(two, "MOTION", ""));
  const fsi::Simulation sim(scene_of(fixed), cpu());
  const auto& w = sim.summary().warnings;
  for (const auto& s : w) std::printf("[ measured ] %s\n", s.c_str());
  // a's shell reaches into b (b sticks out of a's side): one warning for the pair, at the line of
  // the first of them whose particles lie inside the other, naming both.
  ASSERT_EQ(w.size(), 1u);
  expect_at(w[0], fixed, "  - {name: a", "warning");
  EXPECT_NE(w[0].find("structure 'a' overlaps structure 'b' (line " + std::to_string(line_of(fixed, "  - {name: b")) + ")"),
            std::string::npos)
      << w[0];
  const std::string moving = tank("", test::replace(two, "MOTION", ", motion: free, density: 500"));
  const std::string m = refusal(moving);
  std::printf("[ measured ] %s\n", m.c_str());
  expect_at(m, moving, "  - {name: a", "error");
  EXPECT_NE(m.find("a moving structure must start clear of the others"), std::string::npos) << m;
}

TEST(LayoutChecks, AStructureInAWallIsRefusedWhenItMoves) {
  // The pipe's centre 0.02 m below the floor: half of it in the floor's wall layers.
  const std::string s = "structures:\n  - {name: pipe, cylinder: {radius: 0.05}, position: [0.7, -0.02]MOTION}\n";
  const std::string fixed = tank("", test::replace(s, "MOTION", ""));
  const std::string w = only_warning(fixed);
  expect_at(w, fixed, "  - {name: pipe", "warning");
  EXPECT_NE(w.find("overlaps wall 1 of 'walls'"), std::string::npos) << w;
  const std::string moving = tank("", test::replace(s, "MOTION", ", motion: free, density: 2000"));
  const std::string m = refusal(moving);
  expect_at(m, moving, "  - {name: pipe", "error");
  EXPECT_NE(m.find("a moving structure must start clear of the walls"), std::string::npos) << m;
  // Resting on the floor (its surface on the floor's): no overlap.
  const std::string resting = tank("", test::replace(s, "-0.02]MOTION", "0.05], motion: free, density: 2000"));
  EXPECT_EQ(refusal(resting), "");
}

TEST(LayoutChecks, AWallDrawnThroughTheFluidIsRefused) {
  const std::string yaml = tank("  - polyline: {points: [[0.2, -0.1], [0.2, 0.5]]}\n", "");
  const std::string m = refusal(yaml);
  std::printf("[ measured ] %s\n", m.c_str());
  expect_at(m, yaml, "  - polyline", "error");
  EXPECT_NE(m.find("wall 2 of 'walls'"), std::string::npos) << m;
  EXPECT_NE(m.find("passes through the fluid of line " + std::to_string(line_of(yaml, "  - {material: water"))),
            std::string::npos)
      << m;
}

TEST(LayoutChecks, FluidWithNothingBeneathItIsWarnedAbout) {
  const std::string top = head("falling", "0.02", "20");
  // Beside the tank: nothing below any of it.
  const std::string beside = top + R"(fluids:
  - {material: water, box: {min: [0, 0], max: [0.4, 0.3]}}
  - {material: water, box: {min: [1.2, 0.1], max: [1.4, 0.3]}}
walls:
  - box: {min: [0, 0], max: [1.0, 0.6]}
)";
  const std::string m = only_warning(beside);
  expect_at(m, beside, "  - {material: water, box: {min: [1.2", "warning");
  EXPECT_NE(m.find("has nothing beneath it: 100 of its 100 particles"), std::string::npos) << m;
  // On a 0.2 m wide obstacle, 0.4 m of water: the overhang falls (a warning: it may be meant).
  const std::string ledge = top + R"(fluids:
  - {material: water, box: {min: [0.4, 0.2], max: [0.8, 0.3]}}
walls:
  - solid_box: {min: [0.5, 0.0], max: [0.7, 0.2]}
)";
  const std::string w = only_warning(ledge);
  expect_at(w, ledge, "  - {material: water", "warning");
  // 20 x 5 particles; a column is held where an obstacle particle (x = 0.51 ... 0.69) lies in its
  // cell of side dx or the next one: fluid x = 0.49 ... 0.71, 12 of the 20 columns, so 8 x 5 fall.
  EXPECT_NE(w.find("in part nothing beneath it: 40 of its 100 particles"), std::string::npos) << w;
}

}  // namespace

namespace {

// Geometry as stated (issue #27 item 8): at dx = 0.03 m a 3.22 m tank is built to 3.21 m (107
// whole cells from its min corner); a water block stated from x = 1.0 up to the far wall takes the
// tank's lattice, clipped to its cells, so no fluid particle reaches into the wall's layers and
// every fluid particle next to the wall stands exactly dx from it; `turbid check` lists both
// extents and volumes.
TEST(LayoutChecks, ABlockStatedUpToAWallStopsAtTheWallAsBuilt) {
  const std::string yaml = head("stated", "0.03", "40") + R"(fluids:
  - {material: water, box: {min: [1.0, 0], max: [3.22, 0.55]}}
walls:
  - box: {min: [0, 0], max: [3.22, 1.0]}
)";
  const fsi::Simulation sim(scene_of(yaml), cpu());
  const auto& sum = sim.summary();
  EXPECT_TRUE(sum.warnings.empty()) << sum.warnings.front();
  ASSERT_EQ(sum.extents.size(), 2u);
  const auto& fluid = sum.extents[0];
  const auto& tank = sum.extents[1];
  EXPECT_EQ(tank.what, "container");
  EXPECT_NEAR(tank.built.max[0], 3.21, 1e-12);   // 107 cells of 0.03 m
  EXPECT_NEAR(tank.built.max[1], 0.99, 1e-12);   // 33 cells
  EXPECT_NEAR(fluid.built.max[0], 3.21, 1e-9);   // the tank's last cell, not 3.22
  EXPECT_NEAR(fluid.built.min[0], 0.99, 1e-9);   // cell 33 of the tank's lattice (1.0 / 0.03 = 33.3)
  EXPECT_NEAR(fluid.built.max[1], 0.54, 1e-9);   // 18 rows (0.55 / 0.03 = 18.3)
  EXPECT_NEAR(fluid.built_volume, 74 * 18 * 0.03 * 0.03, 1e-9);
  EXPECT_NEAR(fluid.stated_volume, 2.22 * 0.55, 1e-12);
  // Nearest wall particle of every fluid particle: never closer than dx (lattice-aligned).
  const auto& st = sim.store();
  const auto* x = st.data<sph::Real>(sim.fields().position);
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  double closest = 1e9;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != std::uint8_t(sph::Kind::fluid)) continue;
    for (std::size_t j = 0; j < st.size(); ++j) {
      if (kind[j] != std::uint8_t(sph::Kind::wall)) continue;
      closest = std::min(closest, std::hypot(double(x[2 * i] - x[2 * j]), double(x[2 * i + 1] - x[2 * j + 1])));
    }
  }
  std::printf("[ measured ] closest fluid-wall pair %.6f m (dx 0.03); fluid built x %.4f to %.4f, volume %.5f "
              "against %.5f stated\n",
              closest, fluid.built.min[0], fluid.built.max[0], fluid.built_volume, fluid.stated_volume);
  EXPECT_NEAR(closest, 0.03, 1e-6);
}

// An obstacle whose built cells reach past its stated face: fluid lattice points whose cells lie
// mostly in them are left out with a warning at the block's line.
TEST(LayoutChecks, FluidInAnObstaclesCellsIsLeftOutWithAWarning) {
  // solid_box 0.5 to 0.612 at dx 0.02: 5.6 -> 6 cells from 0.5, built to 0.62. Water from 0.612
  // (its own lattice outside any tank: centres 0.622, 0.642, ...): the column at 0.622 lies within
  // dx/4 of the obstacle's built cells and is left out, one per row (5 rows).
  const std::string yaml = head("obstacle", "0.02", "20") + R"(fluids:
  - {material: water, box: {min: [0.612, 0], max: [0.812, 0.1]}}
walls:
  - solid_box: {min: [0.5, -0.06], max: [0.612, 0.1]}
  - polyline: {points: [[0.4, 0], [1.0, 0]]}
)";
  const fsi::Simulation sim(scene_of(yaml), cpu());
  const auto& sum = sim.summary();
  ASSERT_EQ(sum.warnings.size(), 1u);
  std::printf("[ measured ] %s\n", sum.warnings[0].c_str());
  expect_at(sum.warnings[0], yaml, "  - {material: water", "warning");
  EXPECT_NE(sum.warnings[0].find("5 lattice points of this fluid block lie in the cells of a wall"), std::string::npos);
  EXPECT_EQ(sum.fluid_removed_by_walls, 5u);
}

}  // namespace
