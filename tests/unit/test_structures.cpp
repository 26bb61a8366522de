// Structures (fixed boundary bodies) and the forces the fluid puts on them:
//  (a) Newton's third law: the force the fluid puts on every structure (StructureForcePass) is the
//      exact reaction of what the structure does to the fluid, so with no walls and no gravity
//      sum_fluid m_i a_i + sum_structures F = 0 to rounding, for DBC and mDBC, artificial and
//      laminar viscosity, 2D and 3D;
//  (b) torque about the reference point: sum (x_b - x_ref) x F_b, checked against a direct sum;
//  (c) forces.csv columns: names with units, drag/lift and coefficients by their definitions;
//  (d) fluid lattice points inside a structure are left out, and `check`-style summaries report
//      the sampled area and volume of the primitives (within 1% of the analytic values).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "fsi/forces.hpp"
#include "fsi/scene.hpp"
#include "fsi/simulation.hpp"
#include "sph/vec.hpp"

namespace {

using namespace turbid;
using sph::Real;

constexpr double kPi = 3.14159265358979323846;

fsi::Scene block_with_structures(int dims, fsi::BoundaryKind boundary, fsi::ViscosityKind viscosity) {
  fsi::Scene s;
  s.name = "structures";
  s.dimensions = dims;
  s.particle_spacing = dims == 2 ? 0.01 : 0.02;
  s.smoothing_ratio = 2.0;
  s.gravity = {0, 0, 0};
  s.numerics.boundary = boundary;
  s.numerics.viscosity = viscosity;
  s.numerics.artificial_viscosity = 0.1;
  fsi::MaterialSpec water;
  water.name = "water";
  water.density = 1000;
  water.viscosity = 0.5;  // large, so that the laminar term competes with pressure
  water.sound_speed = 20;
  s.materials.push_back(water);
  fsi::FluidBlock block;
  block.material = "water";
  const double side = dims == 2 ? 0.4 : 0.4;
  block.box.min = {0, 0, 0};
  block.box.max = {side, side, dims == 3 ? side : 0.0};
  s.fluids.push_back(block);
  fsi::StructureSpec cyl;
  cyl.name = "cylinder";
  cyl.shape = fsi::StructureSpec::Shape::cylinder;
  cyl.radius = 0.06;
  cyl.length = 0.2;
  cyl.position = {0.13, 0.2, dims == 3 ? 0.2 : 0.0};
  cyl.reference_point = cyl.position;
  s.structures.push_back(cyl);
  fsi::StructureSpec box;
  box.name = "box";
  box.shape = fsi::StructureSpec::Shape::box;
  box.size = {0.08, 0.12, 0.1};
  box.position = {0.29, 0.21, dims == 3 ? 0.2 : 0.0};
  box.rotation_deg = {0, 0, 20};
  box.reference_point = {0.3, 0.0, 0.0};
  s.structures.push_back(box);
  return s;
}

fsi::RunOptions cpu() {
  fsi::RunOptions r;
  r.backend = "cpu";
  r.threads = 1;
  return r;
}

template <int D>
void check_newton(fsi::BoundaryKind boundary, fsi::ViscosityKind viscosity) {
  SCOPED_TRACE(std::to_string(D) + "D boundary " + std::to_string(int(boundary)) + " viscosity " +
               std::to_string(int(viscosity)));
  fsi::Simulation sim(block_with_structures(D, boundary, viscosity), cpu());
  sim.start();
  auto& st = sim.store();
  const auto& id = sim.fields();
  auto* v = st.data<sph::Vec<D>>(id.velocity);
  auto* rho = st.data<Real>(id.density);
  const auto* kind = st.data<std::uint8_t>(id.kind);
  std::mt19937 rng(4242u);
  auto u = [&] { return double(rng() >> 8) * (1.0 / 16777216.0) - 0.5; };
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    for (int k = 0; k < D; ++k) v[i][k] = Real(2.0 * u());
    rho[i] = Real(1000.0 * (1.0 + 0.01 * u()));
  }
  sim.backend().sync_from_host();
  sim.backend().compute_forces();
  const auto loads = sim.structure_loads();
  ASSERT_EQ(loads.size(), 2u);
  const auto* a = st.data<sph::Vec<D>>(id.acceleration);
  const auto* m = st.data<Real>(id.mass);
  double p[3] = {0, 0, 0}, abs_sum = 0;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    double mag = 0;
    for (int k = 0; k < D; ++k) {
      p[k] += double(m[i]) * a[i][k];
      mag += double(a[i][k]) * a[i][k];
    }
    abs_sum += double(m[i]) * std::sqrt(mag);
  }
  double f_abs = 0;
  for (const auto& L : loads) {
    double mag = 0;
    for (int k = 0; k < D; ++k) {
      p[k] += L.force[k];
      mag += L.force[k] * L.force[k];
    }
    f_abs += std::sqrt(mag);
  }
  ASSERT_GT(f_abs, 1e-3 * abs_sum) << "test setup: the structures feel a force";
  // Reference: Newton's third law, pair by pair (the structure-force pass evaluates the momentum
  // pass's own pair function). Residual: float accumulation, rel 1e-6 of sum m |a|.
  const double residual = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  EXPECT_LT(residual, 1e-6 * abs_sum) << "|sum m a + sum F| = " << residual << ", sum m|a| = " << abs_sum;
}

TEST(Structures, FluidForceIsTheReactionOfWhatTheStructureDoes) {
  for (auto b : {fsi::BoundaryKind::dbc, fsi::BoundaryKind::mdbc})
    for (auto vis : {fsi::ViscosityKind::artificial, fsi::ViscosityKind::laminar}) {
      check_newton<2>(b, vis);
    }
  check_newton<3>(fsi::BoundaryKind::mdbc, fsi::ViscosityKind::laminar);
  check_newton<3>(fsi::BoundaryKind::dbc, fsi::ViscosityKind::artificial);
}

TEST(Structures, TorqueIsTheMomentOfTheParticleForcesAboutTheReferencePoint) {
  fsi::Scene scene = block_with_structures(2, fsi::BoundaryKind::dbc, fsi::ViscosityKind::artificial);
  scene.gravity = {0, -9.81, 0};
  fsi::Simulation sim(scene, cpu());
  sim.start();
  const auto loads = sim.structure_loads();
  auto& st = sim.store();
  const auto& id = sim.fields();
  const auto* x = st.data<sph::Vec<2>>(id.position);
  const auto* f = st.data<sph::Vec<2>>(id.structure_force);
  const auto* body = st.data<std::uint8_t>(id.body);
  for (std::size_t b = 0; b < 2; ++b) {
    const auto& ref = scene.structures[b].reference_point;
    double fx = 0, fy = 0, mz = 0;
    for (std::size_t i = 0; i < st.size(); ++i) {
      if (body[i] != b) continue;
      fx += f[i][0];
      fy += f[i][1];
      mz += (double(x[i][0]) - ref[0]) * f[i][1] - (double(x[i][1]) - ref[1]) * f[i][0];
    }
    // Reference: the definition, summed here in the same order (double): equal to rounding.
    EXPECT_NEAR(loads[b].force[0], fx, 1e-9 * (std::abs(fx) + 1));
    EXPECT_NEAR(loads[b].force[1], fy, 1e-9 * (std::abs(fy) + 1));
    EXPECT_NEAR(loads[b].torque[2], mz, 1e-9 * (std::abs(mz) + 1));
    EXPECT_GT(std::abs(fy), 1.0) << "the gravity-loaded fluid pushes on structure " << b;
  }
}

TEST(Structures, ForceColumnsNameUnitsAndCoefficientsFollowTheirDefinition) {
  fsi::Scene s;
  s.dimensions = 2;
  fsi::StructureSpec c;
  c.name = "cyl";
  c.has_coefficients = true;
  c.flow_direction = {1, 0, 0};
  c.lift_direction = {0, 1, 0};
  c.reference_velocity = 0.2;
  c.reference_density = 1.0;
  c.reference_length = 0.1;
  s.structures.push_back(c);
  const auto cols = fsi::force_columns(s);
  const std::vector<std::string> expected = {"cyl.Fx [N/m]",   "cyl.Fy [N/m]",   "cyl.Mz [N m/m]", "cyl.drag [N/m]",
                                             "cyl.lift [N/m]", "cyl.C_D [-]",    "cyl.C_L [-]"};
  EXPECT_EQ(cols, expected);
  sph::BodyLoad L;
  L.force = {0.01115, -0.0004, 0};
  L.torque = {0, 0, 0.5};
  const auto row = fsi::force_row(s, {L});
  ASSERT_EQ(row.size(), cols.size());
  // C_D = 2 F_D / (rho U^2 D): 2 * 0.01115 / (1 * 0.04 * 0.1) = 5.575 (Schaefer & Turek's scale).
  EXPECT_NEAR(row[5], 5.575, 1e-12);
  EXPECT_NEAR(row[6], -0.2, 1e-12);
  EXPECT_DOUBLE_EQ(row[2], 0.5);
}

TEST(Structures, FluidInsideStructuresIsLeftOutAndSummariesGiveAreaAndVolume) {
  fsi::Scene scene = block_with_structures(2, fsi::BoundaryKind::mdbc, fsi::ViscosityKind::artificial);
  fsi::Simulation sim(scene, cpu());
  const auto& sum = sim.summary();
  ASSERT_EQ(sum.structures.size(), 2u);
  // Reference: analytic area and perimeter of the circle r = 0.06 m and the box 0.08 x 0.12 m.
  EXPECT_NEAR(sum.structures[0].volume, kPi * 0.06 * 0.06, 0.01 * kPi * 0.06 * 0.06);
  EXPECT_NEAR(sum.structures[0].surface_area, 2 * kPi * 0.06, 0.01 * 2 * kPi * 0.06);
  EXPECT_NEAR(sum.structures[1].volume, 0.08 * 0.12, 0.01 * 0.08 * 0.12);
  EXPECT_NEAR(sum.structures[1].surface_area, 0.4, 0.01 * 0.4);
  // No fluid particle lies inside a structure: lattice points within dx/2 of the surface are left out,
  // and a particle next to the surface moves towards it only to the centroid of its cell and the part
  // of the gap it took over (simulation.cpp, restore_carved_volume), which for a circle of r = 6 dx
  // keeps it at least dx/4 from the surface: |x - c| >= r + dx/4.
  const auto& st = sim.store();
  const auto& id = sim.fields();
  const auto* x = st.data<sph::Vec<2>>(id.position);
  const auto* kind = st.data<std::uint8_t>(id.kind);
  double closest = 1e9;
  for (std::size_t i = 0; i < st.size(); ++i) {
    if (kind[i] != 0) continue;
    closest = std::min(closest, std::hypot(double(x[i][0]) - 0.13, double(x[i][1]) - 0.2));
  }
  EXPECT_GE(closest, 0.06 + 0.25 * scene.particle_spacing);
  EXPECT_LT(closest, 0.06 + 1.5 * scene.particle_spacing) << "and no wider gap than one spacing";
  // Lattice points left out: about (circle area + box area) / dx^2 plus the dx/2 margin.
  const double inside = (kPi * 0.06 * 0.06 + 0.08 * 0.12) / (0.01 * 0.01);
  EXPECT_GT(double(sum.fluid_removed_by_structures), inside);
  EXPECT_LT(double(sum.fluid_removed_by_structures), 1.6 * inside);
}

}  // namespace
