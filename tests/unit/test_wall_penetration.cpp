// Fluid behind walls (issue #27 item 9; fsi/wall_penetration.hpp): a fluid particle counts when its
// signed distance to the surface of its nearest wall or structure particle is negative. Reference:
// the geometry of each case (a floor whose surface is z = 0 with its particles dx/2 and 3dx/2 below,
// a structure particle turned by a stated rotation); a tank at rest has none behind its walls.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "fsi/wall_penetration.hpp"
#include "sph/physics_params.hpp"
#include "tests/unit/body_test_support.hpp"

namespace {

using namespace turbid;
using sph::Kind;

struct Layout {
  std::vector<float> x;
  std::vector<std::uint8_t> kind, body;
  std::vector<std::uint32_t> id;
  std::vector<std::array<float, 3>> ghost0;
  void boundary(float px, float py, std::array<float, 3> g, Kind k = Kind::wall, std::uint8_t b = 0) {
    x.push_back(px), x.push_back(py);
    kind.push_back(std::uint8_t(k)), body.push_back(b);
    id.push_back(std::uint32_t(100 + ghost0.size()));
    ghost0.push_back(g);
  }
  void fluid(float px, float py) {
    x.push_back(px), x.push_back(py);
    kind.push_back(std::uint8_t(Kind::fluid)), body.push_back(255);
    id.push_back(std::uint32_t(1000 + kind.size()));
  }
  fsi::PenetrationInput input(double radius) const {
    fsi::PenetrationInput in;
    in.dimensions = 2;
    in.size = kind.size();
    in.position = x.data();
    in.kind = kind.data();
    in.id = id.data();
    in.body = body.data();
    in.ghost0 = &ghost0;
    in.first_id = 100;
    in.radius = radius;
    return in;
  }
};

TEST(FluidBehindWalls, CountsWhatIsBeyondTheFloorSurfaceAndHowDeep) {
  const float dx = 0.01f;
  Layout L;
  // A floor with its surface at y = 0: two layers, ghosts 2 x depth along +y.
  for (int i = -5; i <= 15; ++i) {
    L.boundary(i * dx, -0.5f * dx, {0, dx, 0});
    L.boundary(i * dx, -1.5f * dx, {0, 3 * dx, 0});
  }
  for (int i = 0; i < 10; ++i) L.fluid(i * dx, 0.5f * dx);  // the lattice's first row: dx/2 in front
  L.fluid(0.03f, 0.05f * dx);                              // in front, close: not behind
  L.fluid(0.04f, -0.2f * dx);                              // 0.2 dx behind: within a tolerance of dx/4
  L.fluid(0.05f, -0.3f * dx);                              // 0.3 dx behind
  L.fluid(0.07f, -1.2f * dx);                              // 1.2 dx behind, among the layers
  auto in = L.input(2 * dx);
  auto b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 3u);
  EXPECT_EQ(b.below_walls, 3u);
  EXPECT_EQ(b.inside_structures, 0u);
  EXPECT_NEAR(b.deepest, 1.2 * dx, 1e-6);
  in.tolerance = 0.25 * dx;
  b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 2u);
}

TEST(FluidBehindWalls, AStructuresSurfaceTurnsWithItsBody) {
  const float dx = 0.01f;
  Layout L;
  // One structure particle at the origin whose ghost at t = 0 pointed along +x; its body has since
  // turned by +90 degrees about z, so its surface normal is +y and its surface is y = dx/2.
  L.boundary(0, 0, {dx, 0, 0}, Kind::structure, 0);
  L.fluid(0.4f * dx, 0.3f * dx);   // behind the turned surface (0.2 dx), though in front of the old one
  auto in = L.input(2 * dx);
  in.rotation = {{0, -1, 0, 1, 0, 0, 0, 0, 1}};
  auto b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 1u);
  EXPECT_EQ(b.inside_structures, 1u);
  EXPECT_NEAR(b.deepest, 0.2 * dx, 1e-6);
  in.rotation = {{1, 0, 0, 0, 1, 0, 0, 0, 1}};  // not turned: x = 0.4 dx is 0.1 dx behind x = dx/2
  b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 1u);
  EXPECT_NEAR(b.deepest, 0.1 * dx, 1e-6);
}

// The corner of a 2D solid box (x < 0, y < 0; 4 x 4 particles, each ghost along the normal of its
// nearest face, the corner particle's along +y): fluid beside its right face, below the top
// surface's height, is in front of the box; fluid inside near the corner is behind both faces, by
// its distance to the nearer one.
TEST(FluidBehindWalls, BesideABoxsEdgeIsNotBehindItsTopFace) {
  const float dx = 0.01f;
  Layout L;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const float x = -(i + 0.5f) * dx, y = -(j + 0.5f) * dx;
      const bool top = j <= i;  // the top face (y = 0) is nearest, or ties on the diagonal
      L.boundary(x, y, top ? std::array<float, 3>{0, 2 * -y, 0} : std::array<float, 3>{2 * -x, 0, 0});
    }
  L.fluid(0.3f * dx, -1.0f * dx);   // beside the right face (x = 0), 0.3 dx in front of it
  L.fluid(-0.2f * dx, -0.8f * dx);  // inside: 0.2 dx behind the right face, 0.8 dx below the top
  auto in = L.input(2 * dx);
  in.band = 0.5 * dx;
  const auto b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 1u);
  EXPECT_NEAR(b.deepest, 0.2 * dx, 1e-6);
}

// A concave junction: a box standing on the floor (its bottom face rests on the floor's surface
// y = 0 and is no surface). Fluid inside the box near its left face (x = 0) and above the floor's
// surface is behind the box's face, though in front of the floor: counted, by its distance to the
// face it is least behind. Fluid beside the box above the floor is in front of both.
TEST(FluidBehindWalls, InsideABoxOnTheFloorIsBehindItsFace) {
  const float dx = 0.01f;
  Layout L;
  for (int i = -4; i < 6; ++i)
    for (int j = 0; j < 2; ++j) L.boundary((i + 0.5f) * dx, -(j + 0.5f) * dx, {0, (2 * j + 1) * dx, 0});  // floor
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {  // the box [0, 0.04] x [0, 0.04]: left face x = 0, top y = 0.04
      const float x = (i + 0.5f) * dx, y = (j + 0.5f) * dx;
      const bool left = i <= 3 - j;  // nearer the left face than the top
      L.boundary(x, y, left ? std::array<float, 3>{-2 * x, 0, 0} : std::array<float, 3>{0, 2 * (4 * dx - y), 0});
    }
  L.fluid(0.3f * dx, 0.2f * dx);    // inside the box, 0.3 dx behind its left face, 0.2 dx above the floor
  L.fluid(-0.5f * dx, 0.5f * dx);   // beside the box on the floor: in front of both
  auto in = L.input(2 * dx);
  in.band = 0.5 * dx;
  const auto b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 1u);
  EXPECT_NEAR(b.deepest, 0.3 * dx, 1e-6);
}

TEST(FluidBehindWalls, NothingBeyondTheSearchRadiusCounts) {
  const float dx = 0.01f;
  Layout L;
  L.boundary(0, 0, {0, dx, 0});
  L.fluid(0, -3 * dx);  // behind the plane, but no boundary particle within 2 dx
  EXPECT_EQ(fsi::count_fluid_behind_walls(L.input(2 * dx)).count, 0u);
  EXPECT_EQ(fsi::count_fluid_behind_walls(L.input(4 * dx)).count, 1u);
}

// A fluid particle beside a box's corner, 4 dx off, sees only the top row's particle within the
// search radius and stands below its plane: it is inside no wall, for it is farther than dx
// (`inside`) from every boundary particle (a point behind a surface built on the lattice is within
// sqrt(d)/2 dx of one). Seen in the 3D dam break with a box (docs/validation.md W).
TEST(FluidBehindWalls, FarFromEveryWallParticleIsInsideNone) {
  const float dx = 0.01f;
  Layout L;
  L.boundary(0, 0, {0, dx, 0});     // the top row's corner particle; surface y = dx/2
  L.fluid(-3.9f * dx, -0.5f * dx);  // 1 dx below that plane, 3.93 dx from the particle
  auto in = L.input(4 * dx);
  EXPECT_EQ(fsi::count_fluid_behind_walls(in).count, 1u) << "no bound: behind the plane";
  in.inside = dx;
  EXPECT_EQ(fsi::count_fluid_behind_walls(in).count, 0u);
  L.fluid(0.3f * dx, -0.4f * dx);  // 0.5 dx from it and behind its surface: inside
  in = L.input(4 * dx);
  in.inside = dx;
  EXPECT_EQ(fsi::count_fluid_behind_walls(in).count, 1u);
}

// In a tank's floor-wall edge the edge particle's ghost offset is diagonal; its plane passes through
// the floor particle next to it. A fluid particle in front of that plane but below the floor's
// surface is in a concave corner, not beside a convex edge: it is behind the floor. Reference: the
// geometry (end wall x < 0, floor y < 0, surfaces x = 0 and y = 0); seen in the 3D box case.
TEST(FluidBehindWalls, ATanksDiagonalEdgePlaneIsNoConvexEdge) {
  const float dx = 0.01f;
  Layout L;
  L.boundary(-0.5f * dx, -0.5f * dx, {dx, dx, 0});  // the edge particle: ghost across the corner
  for (int i = 0; i < 6; ++i) {
    L.boundary((i + 0.5f) * dx, -0.5f * dx, {0, dx, 0});       // floor, first layer
    L.boundary((i + 0.5f) * dx, -1.5f * dx, {0, 3 * dx, 0});   // second layer
    L.boundary(-0.5f * dx, (i + 0.5f) * dx, {dx, 0, 0});       // end wall
    L.boundary(-1.5f * dx, (i + 0.5f) * dx, {3 * dx, 0, 0});
  }
  L.fluid(0.25f * dx, -0.2f * dx);  // 0.2 dx below the floor's surface, in front of the diagonal plane
  auto in = L.input(2 * dx);
  in.band = 0.5 * dx;
  const auto b = fsi::count_fluid_behind_walls(in);
  EXPECT_EQ(b.count, 1u);
  EXPECT_NEAR(b.deepest, 0.2 * dx, 1e-6);
}

// A 2D tank 1 x 0.6 m at dx = 0.02 m, water 0.3 m deep; `numerics` (YAML lines) and `rest` follow.
std::string tank(const std::string& numerics, const std::string& rest) {
  return R"(name: tank
dimensions: 2
resolution: {particle_spacing: 0.02, smoothing_ratio: 2.0}
numerics:
)" + numerics + R"(
materials:
  water: {density: 1000, sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [1.0, 0.6]}
fluids:
  - {material: water, box: {min: [0, 0], max: [1.0, 0.3]}}
)" + rest;
}

// A 2D tank at rest, built by fsi::Simulation with DBC and with mDBC walls: the lattice leaves every
// fluid particle dx/2 in front of the walls' surfaces, so none is behind.
TEST(FluidBehindWalls, ATankAtRestHasNoneBehindItsWalls) {
  for (const char* boundary : {"dbc", "mdbc"}) {
    const std::string yaml = tank(std::string("  boundary: {type: ") + boundary + "}", "time: {end: 0.01}\n");
    fsi::Simulation sim(test::scene_of(yaml), test::cpu());
    const auto b = sim.measure_fluid_behind_walls();
    EXPECT_EQ(b.count, 0u) << boundary;
  }
}

// The scene's limit stops the run at the output that finds more behind walls than it allows, with
// the key's line and the count; within the limit the run goes on.
TEST(FluidBehindWalls, MoreThanTheScenesLimitStopsTheRunAtItsLine) {
  for (int limit : {0, 1}) {
    // Walls left to their pressure alone (impermeable walls would put the particle back).
    const std::string yaml = tank("  max_fluid_behind_walls: " + std::to_string(limit) +
                                      "\n  boundary: {type: dbc, impermeable: false}",
                                  "time: {end: 0.002}\noutput: {every: 0.001, vtk: false}\n");
    fsi::Simulation sim(test::scene_of(yaml), test::cpu());
    sim.start();
    // Put one fluid particle of the bottom row 0.3 dx below the floor's surface (y = 0), past the
    // count's tolerance of dx/4.
    auto& st = sim.store();
    auto* x = static_cast<float*>(st.raw(sim.fields().position));
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    for (std::size_t i = 0; i < st.size(); ++i)
      if (kind[i] == std::uint8_t(Kind::fluid) && x[2 * i + 1] < 0.011f && x[2 * i] > 0.4f) {
        x[2 * i + 1] = -0.006f;
        break;
      }
    fsi::Observer quiet;
    if (limit == 0) {
      try {
        sim.run(quiet);
        ADD_FAILURE() << "the run went on with fluid behind the floor";
      } catch (const std::runtime_error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.rfind("test.yaml:5:", 0), 0u) << m;  // the key's line in tank()
        EXPECT_NE(m.find("1 fluid particles are behind"), std::string::npos) << m;
        EXPECT_NE(m.find("max_fluid_behind_walls"), std::string::npos) << m;
      }
    } else {
      EXPECT_NO_THROW(sim.run(quiet));
      EXPECT_LE(sim.fluid_behind_walls().count, 1u);
    }
  }
}

// Impermeable walls (sph::WallConstraintPass, issue #27 item 9). Reference: the pass's definition:
// a fluid particle behind the surface of the boundary particles near it is put on that surface
// (signed distance 0, to float rounding of positions of O(1) m: 1e-6 m) and its velocity into the
// wall removed; its tangential velocity is the kick's alone; fluid in front of every surface moves
// exactly as without the pass (bit for bit).
// A still 2D tank (no gravity) with walls of `boundary` (a numerics line), started; then the first
// fluid particle of the bottom row with x in [x_lo, x_hi] is moved to `at` with velocity `vel`.
// Returns its id.
std::uint32_t move_one(fsi::Simulation& sim, float x_lo, float x_hi, std::array<float, 2> at,
                       std::array<float, 2> vel) {
  sim.start();
  auto& st = sim.store();
  auto* x = static_cast<float*>(st.raw(sim.fields().position));
  auto* v = static_cast<float*>(st.raw(sim.fields().velocity));
  const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
  const auto* id = st.data<std::uint32_t>(sim.fields().id);
  for (std::size_t i = 0; i < st.size(); ++i)
    if (kind[i] == std::uint8_t(Kind::fluid) && x[2 * i + 1] < 0.011f && x[2 * i] >= x_lo && x[2 * i] <= x_hi) {
      x[2 * i] = at[0], x[2 * i + 1] = at[1];
      v[2 * i] = vel[0], v[2 * i + 1] = vel[1];
      return id[i];
    }
  ADD_FAILURE() << "no bottom-row fluid particle with x in [" << x_lo << ", " << x_hi << "]";
  return std::uint32_t(-1);
}

std::string still_tank(const std::string& boundary) {
  return tank("  boundary: " + boundary, "time: {end: 0.001}\ngravity: [0, 0]\noutput: {every: 0, vtk: false}\n");
}

TEST(ImpermeableWalls, FluidPastTheFloorIsPutBackOnItsSurface) {
  struct Result {
    float y_moved, v_moved, u_moved;  // the particle pushed below the floor
    std::vector<float> others;        // every other fluid particle's position after the steps
    std::uint64_t put_backs;          // the run's count of particles put back on a surface
  };
  auto run = [](bool impermeable) {
    fsi::Simulation sim(test::scene_of(still_tank(std::string("{type: dbc, impermeable: ") +
                                                  (impermeable ? "true" : "false") + "}")),
                        test::cpu());
    // 0.3 dx below the floor's surface (y = 0), heading down and along.
    const std::uint32_t moved = move_one(sim, 0.4f, 1.0f, {0.41f, -0.006f}, {0.5f, -1.0f});
    sim.step(1e-4);
    const auto& st = sim.store();
    const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
    const auto* v = static_cast<const float*>(st.raw(sim.fields().velocity));
    const auto* kind = st.data<std::uint8_t>(sim.fields().kind);
    const auto* id = st.data<std::uint32_t>(sim.fields().id);
    Result r{};
    r.put_backs = sim.wall_put_backs();
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (kind[i] != std::uint8_t(Kind::fluid)) continue;
      if (id[i] == moved) {
        r.y_moved = x[2 * i + 1];
        r.u_moved = v[2 * i];
        r.v_moved = v[2 * i + 1];
      } else if (x[2 * i + 1] > 0.1f) {  // away from the moved particle's neighbourhood
        r.others.push_back(x[2 * i]);
        r.others.push_back(x[2 * i + 1]);
      }
    }
    return r;
  };
  const Result on = run(true), off = run(false);
  EXPECT_NEAR(on.y_moved, 0.0f, 1e-6f) << "put back on the floor's surface";
  EXPECT_GE(on.v_moved, 0.0f) << "no velocity into the floor after the pass";
  EXPECT_LT(off.y_moved, -0.006f) << "without the pass it goes on down: " << off.y_moved;
  EXPECT_LT(off.v_moved, 0.0f);
  EXPECT_EQ(on.others, off.others) << "fluid in front of the walls is not touched";
  EXPECT_EQ(on.put_backs, 1u) << "the one particle, counted once";
  EXPECT_EQ(off.put_backs, 0u);
}

// In a concave corner (the floor meeting the tank's end wall) a particle behind both surfaces is
// put in front of both: pushed out of the one it is least behind alone it would stay below the
// floor. Reference: the surfaces x = 0 and y = 0 of the tank's walls; "on the surface" to the
// pass's on-surface margin (1e-3 of its band, dx/2: 1e-5 m) and float rounding.
TEST(ImpermeableWalls, FluidInACornerIsPutInFrontOfBothWalls) {
  fsi::Simulation sim(test::scene_of(still_tank("{type: dbc}")), test::cpu());
  // 0.1 dx behind the end wall's surface (x = 0) and 0.3 dx below the floor's (y = 0), heading
  // into the corner.
  const std::uint32_t who = move_one(sim, 0.0f, 0.011f, {-0.002f, -0.006f}, {-0.5f, -1.0f});
  sim.step(1e-4);
  EXPECT_EQ(sim.wall_put_backs(), 1u) << "one particle in one drift, however many pushes";
  const auto& st = sim.store();
  const auto* x = static_cast<const float*>(st.raw(sim.fields().position));
  const auto* v = static_cast<const float*>(st.raw(sim.fields().velocity));
  const auto* id = st.data<std::uint32_t>(sim.fields().id);
  for (std::size_t i = 0; i < st.size(); ++i)
    if (id[i] == who) {
      EXPECT_GE(x[2 * i], -1.1e-5f) << "in front of the end wall: " << x[2 * i] << ", " << x[2 * i + 1];
      EXPECT_GE(x[2 * i + 1], -1.1e-5f) << "in front of the floor";
      EXPECT_LT(x[2 * i] + x[2 * i + 1], 0.005f) << "put on the surfaces, not thrown into the fluid";
      EXPECT_GE(v[2 * i], 0.0f) << "no velocity into the end wall";
      EXPECT_GE(v[2 * i + 1], 0.0f) << "no velocity into the floor";
    }
}

}  // namespace
