// The implicit viscous update (sph/implicit_viscosity.hpp) and the full deviatoric stress
// (sph/full_stress.hpp), driven through the CPU backend's solve_viscosity on a scene built by the
// Simulation. References, per test:
//  - Newton's third law: a Bingham block (viscosity at rest 2000 Pa s, implicit) with random
//    velocities beside a fixed structure and no-slip mDBC walls, no gravity: one update over dt
//    changes the fluid's momentum by exactly minus dt times the reaction the structure gets
//    (viscous_load) and the walls' share. With the walls fixed their share is not booked anywhere,
//    so the test puts the block away from the walls and against the structure only: then the fluid's
//    momentum change plus dt x the structure's load is zero up to the float rounding of the update
//    (1e-6 of sum m |dv|, the bound the pair-sum tests use) and of the stored velocities (2^-24 of
//    sum m |v|). For the full stress and the Laplacian form.
//  - The full stress in 2D: div(2 mu D') = mu lap v for the shear v = (k y^2, 0), so one update of a
//    Newtonian block (mu = 1 Pa s) with dt nu / h^2 of 2.5e-4 changes v by dt 2 nu k on the interior
//    (4h from the free edges: the stencil of a divergence of gradients) to 2%, the Laplacian form's
//    bound at h = 2 dx (measured 2.4e-4: the renormalised gradient and the trapezoidal pair residual
//    are exact for a quadratic field on a lattice); for v = (k x^2, 0) (div v != 0) the full stress in
//    2D gives mu lap v too, and the update equals the Laplacian form's to the same 2% (measured 1.5%).
//  - The scene's choice of integrator and stress form per material (fsi::physics_params), and the
//    located error for the full stress with explicit integration.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "fsi/simulation.hpp"
#include "sph/backend.hpp"
#include "sph/vec.hpp"
#include "tests/unit/body_test_support.hpp"

namespace {

using namespace turbid;
using sph::Real;
using sph::Vec;

std::string block_scene(const std::string& stress) {
  return R"(name: implicit_momentum
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, 0]
numerics:
  viscosity: {type: laminar, stress: )" +
         stress + R"(}
  boundary: {type: mdbc, velocity: no_slip}
materials:
  debris: {model: bingham, density: 1800, viscosity: 0.5, yield_stress: 20, papanastasiou_exponent: 100,
           sound_speed: 20}
walls:
  - box: {min: [0, 0], max: [1.0, 1.0]}
structures:
  - {name: block, box: {size: [0.1, 0.3]}, position: [0.55, 0.5]}
fluids:
  - {material: debris, box: {min: [0.3, 0.35], max: [0.5, 0.65]}}
)";
}

struct Totals {
  double p[2] = {0, 0};
  double abs_v = 0;  // sum m |v|
};

Totals fluid_momentum(const fsi::Simulation& sim, std::vector<double>* mv) {
  const auto& s = sim.store();
  const auto& id = sim.fields();
  const auto* m = s.data<float>(id.mass);
  const auto* v = s.data<float>(id.velocity);
  const auto* kind = s.data<std::uint8_t>(id.kind);
  const auto* pid = s.data<std::uint32_t>(id.id);
  Totals t;
  if (mv) mv->assign(2 * s.size() + 2, 0.0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (kind[i] != 0) continue;
    for (int a = 0; a < 2; ++a) {
      t.p[a] += double(m[i]) * double(v[2 * i + a]);
      t.abs_v += double(m[i]) * std::abs(double(v[2 * i + a]));
      if (mv) (*mv)[2 * pid[i] + a] = double(m[i]) * double(v[2 * i + a]);
    }
  }
  return t;
}

class ImplicitMomentum : public ::testing::TestWithParam<const char*> {};

TEST_P(ImplicitMomentum, FluidMomentumChangeIsMinusTheStructuresReaction) {
  fsi::Simulation sim(test::scene_of(block_scene(GetParam())), test::cpu());
  ASSERT_TRUE(sim.params().implicit_viscosity);
  ASSERT_EQ(sim.params().materials[0].full_stress, std::string(GetParam()) == "full");
  sim.start();
  auto& s = sim.store();
  const auto& id = sim.fields();
  ASSERT_GE(id.viscous_load, 0);
  auto* v = s.data<Vec<2>>(id.velocity);
  const auto* kind = s.data<std::uint8_t>(id.kind);
  std::mt19937 rng(2024u);
  auto u = [&] { return double(rng() >> 8) * (1.0 / 16777216.0) - 0.5; };
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] == 0) v[i] = Vec<2>{{Real(0.2 * u()), Real(0.2 * u())}};
  sim.backend().sync_from_host();
  sim.backend().compute_forces();  // the viscosities and the neighbour list of these velocities
  std::vector<double> mv0, mv1;
  const Totals p0 = fluid_momentum(sim, &mv0);
  const double dt = 1e-4;  // dt nu_0 / h^2 = 1e-4 x 1.1 / 4e-4: stiff (the reason for the implicit update)
  const sph::ViscousSolve r = sim.backend().solve_viscosity(dt, 1.0, true);
  EXPECT_TRUE(r.converged) << r.iterations << " iterations, residual " << r.residual;
  sim.backend().sync_to_host();
  const Totals p1 = fluid_momentum(sim, &mv1);
  const auto* load = s.data<Vec<2>>(id.viscous_load);
  double J[2] = {0, 0};
  for (std::size_t i = 0; i < s.size(); ++i)
    if (kind[i] == 2)
      for (int a = 0; a < 2; ++a) J[a] += dt * double(load[i][a]);
  double dv = 0;
  for (std::size_t k = 0; k < mv0.size(); ++k) dv += std::abs(mv1[k] - mv0[k]);
  EXPECT_GT(std::hypot(J[0], J[1]), 1e-3 * dv) << "the structure must take part";
  std::printf("[ measured ] %s: sum m |dv| %.3e, |J| %.3e\n", GetParam(), dv, std::hypot(J[0], J[1]));
  for (int a = 0; a < 2; ++a) {
    const double residual = (p1.p[a] - p0.p[a]) + J[a];
    const double bound = 1e-6 * (dv + std::abs(J[a])) + std::ldexp(1.0, -24) * p1.abs_v;
    EXPECT_LE(std::abs(residual), bound) << "axis " << a;
    std::printf("[ measured ] %s: axis %d: fluid dP %.3e, structure impulse %.3e, residual %.2e (bound %.2e), "
                "%d CG iterations\n",
                GetParam(), a, p1.p[a] - p0.p[a], J[a], residual, bound, r.iterations);
  }
}

INSTANTIATE_TEST_SUITE_P(Stress, ImplicitMomentum, ::testing::Values("full", "laplacian"));

std::string newtonian_block(const std::string& stress) {
  return R"(name: implicit_shear
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 1.0, cfl: 0.2}
gravity: [0, 0]
numerics:
  viscosity: {type: laminar, integration: implicit, stress: )" +
         stress + R"(}
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0, sound_speed: 20}
fluids:
  - {material: water, box: {min: [0, 0], max: [0.3, 0.3]}}
)";
}

// Velocity change of one implicit update over dt of the field v = (k s^2, 0), s = y - c or x - c,
// per particle id; the interior flag marks particles with a full support inside the block.
std::vector<double> update_of_field(const std::string& stress, int field, double dt, std::vector<bool>& interior) {
  fsi::Simulation sim(test::scene_of(newtonian_block(stress)), test::cpu());
  sim.start();
  auto& s = sim.store();
  const auto& id = sim.fields();
  auto* x = s.data<Vec<2>>(id.position);
  auto* v = s.data<Vec<2>>(id.velocity);
  const auto* pid = s.data<std::uint32_t>(id.id);
  const double k = 10.0, c = 0.15, h = sim.params().smoothing_length;
  std::vector<double> v0(s.size() + 1, 0.0), dv(s.size() + 1, 0.0);
  interior.assign(s.size() + 1, false);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double q = double(x[i][field == 0 ? 1 : 0]) - c;
    v[i] = Vec<2>{{Real(k * q * q), Real(0)}};
    v0[pid[i]] = double(v[i][0]);
    bool inside = true;
    // The full stress's stencil reaches 4h (the divergence of neighbours' gradients).
    for (int a = 0; a < 2; ++a) inside = inside && x[i][a] > 4.0 * h && x[i][a] < 0.3 - 4.0 * h;
    interior[pid[i]] = inside;
  }
  sim.backend().sync_from_host();
  sim.backend().compute_forces();
  sim.backend().solve_viscosity(dt, 1.0, true);
  sim.backend().sync_to_host();
  for (std::size_t i = 0; i < s.size(); ++i) dv[pid[i]] = double(v[i][0]) - v0[pid[i]];
  return dv;
}

TEST(ImplicitFullStress, OneUpdateGivesTheDivergenceOfTheDeviatoricStress) {
  const double dt = 1e-4, nu = 1e-3, k = 10.0;  // dt nu / h^2 = 2.5e-4
  const double expected = dt * 2.0 * nu * k;
  for (int field = 0; field < 2; ++field) {
    std::vector<bool> inside, inside_lap;
    const std::vector<double> full = update_of_field("full", field, dt, inside);
    const std::vector<double> lap = update_of_field("laplacian", field, dt, inside_lap);
    double worst = 0, worst_lap = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < full.size(); ++i) {
      if (!inside[i]) continue;
      ++n;
      worst = std::max(worst, std::abs(full[i] - expected) / expected);
      worst_lap = std::max(worst_lap, std::abs(full[i] - lap[i]) / expected);
      EXPECT_NEAR(full[i], expected, 0.02 * expected) << "field " << field << ", particle " << i;
      EXPECT_NEAR(full[i], lap[i], 0.02 * expected) << "field " << field << ", particle " << i;
    }
    EXPECT_GE(n, 100u);
    std::printf("[ measured ] field %d: full stress vs 2 nu k dt: largest relative error %.2e; vs the Laplacian "
                "form %.2e (%zu particles)\n",
                field, worst, worst_lap, n);
  }
}

}  // namespace

namespace {

// Which integrator and stress form each material gets (fsi::physics_params; docs/choices.md): the
// scene's keys against the defaults, and the located error for a combination that cannot run.
sph::PhysicsParams params_of(const std::string& numerics, const std::string& debris_extra = "",
                             const std::string& wall_velocity = "") {
  const std::string boundary =
      wall_velocity.empty() ? std::string() : "\n  boundary: {type: dbc, velocity: " + wall_velocity + "}";
  return fsi::physics_params(test::scene_of(R"(name: choices
dimensions: 2
resolution: {particle_spacing: 0.01, smoothing_ratio: 2.0}
time: {end: 0.1}
numerics:
  viscosity: {type: laminar)" + numerics + "}" + boundary + R"(
materials:
  water: {model: newtonian, density: 1000, viscosity: 1.0e-3, sound_speed: 20}
  debris: {model: bingham, density: 1800, viscosity: 0.5, yield_stress: 20, papanastasiou_exponent: 100,
           sound_speed: 20)" + debris_extra + R"(}
fluids:
  - {material: debris, box: {min: [0, 0], max: [0.1, 0.1]}}
  - {material: water, box: {min: [0.1, 0], max: [0.3, 0.1]}}
)"));
}

TEST(ViscousChoices, IntegratorAndStressFormPerMaterial) {
  // Default (auto): the non-Newtonian debris gets the full stress, and so the implicit update; the
  // Newtonian water stays explicit in the Laplacian form; walls mirror the fluid's velocity (the
  // full stress's gradients need the no-slip profile through the wall, docs/choices.md).
  const sph::PhysicsParams d = params_of("");
  EXPECT_TRUE(d.materials[1].implicit_viscosity);
  EXPECT_TRUE(d.materials[1].full_stress);
  EXPECT_FALSE(d.materials[0].implicit_viscosity || d.materials[0].full_stress);
  EXPECT_TRUE(d.full_stress);
  EXPECT_TRUE(d.wall_no_slip);
  // ... unless the walls' velocity is stated.
  EXPECT_FALSE(params_of(", stress: full", "", "wall").wall_no_slip);
  // A stated cap with `integration: explicit` keeps the debris explicit, in the Laplacian form.
  const sph::PhysicsParams capped = params_of(", integration: explicit", ", max_viscosity: 1");
  EXPECT_FALSE(capped.materials[1].implicit_viscosity || capped.materials[1].full_stress);
  EXPECT_FALSE(capped.wall_no_slip);
  // stress: laplacian keeps the Laplacian form, implicit where the material needs it.
  const sph::PhysicsParams lap = params_of(", stress: laplacian");
  EXPECT_TRUE(lap.materials[1].implicit_viscosity);
  EXPECT_FALSE(lap.materials[1].full_stress || lap.full_stress || lap.wall_no_slip);
  // integration: implicit covers the Newtonian water too (Laplacian form unless stress: full).
  const sph::PhysicsParams all = params_of(", integration: implicit");
  EXPECT_TRUE(all.materials[0].implicit_viscosity);
  EXPECT_FALSE(all.materials[0].full_stress);
  // stress: full gives every material the full stress, and so the implicit update.
  const sph::PhysicsParams full = params_of(", stress: full", ", max_viscosity: 1");
  EXPECT_TRUE(full.materials[0].implicit_viscosity && full.materials[0].full_stress) << "water";
  EXPECT_TRUE(full.materials[1].implicit_viscosity && full.materials[1].full_stress) << "capped debris";
  EXPECT_TRUE(full.full_stress && full.implicit_viscosity);
  // stress: central, explicit where the material allows it.
  const sph::PhysicsParams central = params_of(", stress: central", ", max_viscosity: 1");
  EXPECT_TRUE(central.materials[0].central_stress && central.materials[1].central_stress);
  EXPECT_FALSE(central.materials[1].implicit_viscosity);
}

TEST(ViscousChoices, FullStressWithExplicitIntegrationIsALocatedError) {
  try {
    params_of(", integration: explicit, stress: full", ", max_viscosity: 1");
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("test.yaml:"), std::string::npos) << what;
    EXPECT_NE(what.find("stress: full"), std::string::npos) << what;
  }
}

}  // namespace
