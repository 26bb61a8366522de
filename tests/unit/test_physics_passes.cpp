// Physics passes (sph/passes.hpp) run by the CPU backend on a small 2D lattice (30 x 30) built by
// the Simulation from a Scene made in code (no walls; no gravity unless stated):
//  (a) a fluid at rest with uniform density: zero continuity rate (exact) and zero acceleration
//      (exact without background pressure; round-off with one, by lattice symmetry);
//  (b) momentum conservation sum_i m_i a_i = 0 for random velocities and densities, artificial and
//      laminar viscosity (pairwise antisymmetric forces, physics.md C3/C10);
//  (c) continuity under uniform compression v = -k x: D rho/Dt = -rho div v = rho k D;
//  (d) hydrostatic balance, (e) density diffusion in a hydrostatic column, (f) laminar viscosity
//      of a parabolic profile, (g) bitwise independence of the thread count, (h) particle shifting;
//  (f') the central viscous pair form: mu (lap v + 2 grad div v) for a constant mu, and the
//      conservation of angular momentum (central pair forces);
//  (b') momentum conservation with mixed h (random h in [h0/2, h0]), two materials and a structure
//      whose force is the fluid's reaction, built on the CPU backend directly.
// Lattice sums in double over the same float kernel values serve as brute-force references; the
// analytic references hold within the lattice quadrature error measured in test_kernels.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fsi/scene.hpp"
#include "fsi/simulation.hpp"
#include "sph/backend.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/kernels.hpp"
#include "sph/vec.hpp"

namespace {

using namespace turbid;
using sph::Real;
using sph::Vec;

constexpr double kDx = 0.01;   // particle spacing [m]
constexpr double kSide = 0.3;  // square block of 30 x 30 particles
constexpr double kRho0 = 1000.0;

struct SceneOptions {
  double smoothing_ratio = 1.3;
  sph::KernelKind kernel = sph::KernelKind::wendland_c2;
  fsi::DiffusionKind diffusion = fsi::DiffusionKind::fourtakas;
  fsi::ViscosityKind viscosity = fsi::ViscosityKind::artificial;
  double artificial_viscosity = 0.05;
  double dynamic_viscosity = 1e-3;
  double background_pressure = 0.0;
  double gravity = 0.0;  // [m/s^2] along -y
  double shifting = 0.0;  // particle shifting coefficient A (0: off)
  double shifting_surface_threshold = -1.0;  // < 0: the engine's default
  fsi::ViscousStress viscous_stress = fsi::ViscousStress::laplacian;
};

fsi::Scene make_scene(const SceneOptions& o) {
  fsi::Scene s;
  s.name = "unit_block";
  s.dimensions = 2;
  s.particle_spacing = kDx;
  s.smoothing_ratio = o.smoothing_ratio;
  s.gravity = {0, -o.gravity, 0};
  s.numerics.kernel = o.kernel;
  s.numerics.diffusion = o.diffusion;
  s.numerics.viscosity = o.viscosity;
  s.numerics.artificial_viscosity = o.artificial_viscosity;
  s.numerics.viscous_stress = o.viscous_stress;
  s.numerics.shifting_coefficient = o.shifting;
  s.numerics.shifting_surface_threshold = o.shifting_surface_threshold;
  fsi::MaterialSpec water;
  water.name = "water";
  water.density = kRho0;
  water.viscosity = o.dynamic_viscosity;
  water.sound_speed = 20.0;
  water.gamma = 7.0;
  water.background_pressure = o.background_pressure;
  s.materials.push_back(water);
  fsi::FluidBlock block;
  block.material = "water";
  block.box.min = {0, 0, 0};
  block.box.max = {kSide, kSide, 0};
  s.fluids.push_back(block);
  return s;
}

// One thread: the passes are gathers, so results do not depend on the thread count (checked by
// ThreadCountDoesNotChangeBits); one thread keeps each test fast on a loaded machine.
fsi::RunOptions cpu(int threads = 1) {
  fsi::RunOptions r;
  r.backend = "cpu";
  r.threads = threads;
  return r;
}

struct Fields {
  Vec<2>* x;
  Vec<2>* v;
  Vec<2>* a;
  Real* rho;
  Real* drho;
  Real* m;
  std::size_t n;
};

Fields fields(fsi::Simulation& sim) {
  auto& s = sim.store();
  const auto& id = sim.fields();
  return {s.data<Vec<2>>(id.position), s.data<Vec<2>>(id.velocity), s.data<Vec<2>>(id.acceleration),
          s.data<Real>(id.density),    s.data<Real>(id.density_rate), s.data<Real>(id.mass),
          s.size()};
}

// Full kernel support inside the block: every lattice point within 2h exists.
bool interior(const Vec<2>& x, double h) {
  for (int k = 0; k < 2; ++k)
    if (double(x[k]) - 2.0 * h < 0.0 || double(x[k]) + 2.0 * h > kSide) return false;
  return true;
}

// (1/r) dW/dr of the scene's 2D kernel, evaluated in float like the engine.
double kernel_f(sph::KernelKind kind, double r, double h) {
  return kind == sph::KernelKind::wendland_c2 ? sph::WendlandC2<2>::f(Real(r), Real(h))
                                              : sph::CubicSpline<2>::f(Real(r), Real(h));
}

// sum_j V_j |F_ij| r_ij over a full lattice support [1/m]: the size of one side of the
// pressure sum per unit of 2 p / rho, the scale against which round-off is judged.
double lattice_abs_gradient(double h, sph::KernelKind kind) {
  const int n = int(std::ceil(2.0 * h / kDx)) + 1;
  double s = 0;
  for (int a = -n; a <= n; ++a)
    for (int b = -n; b <= n; ++b) {
      const double r = std::hypot(a * kDx, b * kDx);
      if (r == 0) continue;
      const double F = kernel_f(kind, r, h);
      s += kDx * kDx * std::abs(F) * r;
    }
  return s;
}

// tr(sum_j (x_j - x_i) (x) grad_i W_ij V_j) = sum_j -F r^2 V_j over a full lattice support: the
// discrete divergence operator's factor, D up to the lattice quadrature error.
double lattice_trace(double h, sph::KernelKind kind) {
  const int n = int(std::ceil(2.0 * h / kDx)) + 1;
  double s = 0;
  for (int a = -n; a <= n; ++a)
    for (int b = -n; b <= n; ++b) {
      const double r = std::hypot(a * kDx, b * kDx);
      if (r == 0) continue;
      const double F = kernel_f(kind, r, h);
      s += -F * r * r * kDx * kDx;
    }
  return s;
}

std::string label(const SceneOptions& o) {
  return std::string(o.kernel == sph::KernelKind::wendland_c2 ? "wendland" : "cubic") +
         " h/dx=" + std::to_string(o.smoothing_ratio) + " diffusion=" + std::to_string(int(o.diffusion)) +
         " viscosity=" + std::to_string(int(o.viscosity)) + " p_b=" + std::to_string(o.background_pressure);
}

// ---------------------------------------------------------------------------------------------
// (a) Fluid at rest

TEST(PhysicsPasses, RestStateHasZeroRatesForEveryDiffusion) {
  for (auto diff : {fsi::DiffusionKind::none, fsi::DiffusionKind::molteni, fsi::DiffusionKind::antuono,
                    fsi::DiffusionKind::fourtakas}) {
    SceneOptions o;
    o.diffusion = diff;
    SCOPED_TRACE(label(o));
    fsi::Simulation sim(make_scene(o), cpu());
    sim.start();
    sim.backend().compute_density_rate();
    const Fields f = fields(sim);
    ASSERT_EQ(f.n, 900u);
    std::size_t inner = 0;
    for (std::size_t i = 0; i < f.n; ++i) {
      ASSERT_EQ(f.rho[i], Real(kRho0)) << "uniform initial density without gravity";
      // Exact: v_ij = 0 and rho_j - rho_i = 0 make every continuity and diffusion term exactly 0
      // (at interior and at free-surface particles alike).
      EXPECT_EQ(f.drho[i], Real(0)) << "continuity rate at rest, particle " << i;
      // Exact: p = B((rho0/rho0)^7 - 1) + 0 = 0 for every particle, so no force at all.
      EXPECT_EQ(f.a[i][0], Real(0)) << i;
      EXPECT_EQ(f.a[i][1], Real(0)) << i;
      inner += interior(f.x[i], sim.params().smoothing_length);
    }
    EXPECT_GE(inner, 500u) << "test setup: interior particles present";
  }
}

TEST(PhysicsPasses, RestStateWithBackgroundPressureIsBalancedInside) {
  for (auto kernel : {sph::KernelKind::wendland_c2, sph::KernelKind::cubic_spline}) {
    SceneOptions o;
    o.kernel = kernel;
    o.background_pressure = 1000.0;  // every particle has p = p_b > 0
    SCOPED_TRACE(label(o));
    fsi::Simulation sim(make_scene(o), cpu());
    sim.start();
    sim.backend().compute_density_rate();
    const Fields f = fields(sim);
    const double h = sim.params().smoothing_length;
    // Scale of one side of the pressure sum: (2 p_b / rho0) sum_j V_j |F| r (~300 m/s^2 here).
    const double scale = 2.0 * o.background_pressure / kRho0 * lattice_abs_gradient(h, kernel);
    double px = 0, py = 0, abs_sum = 0, worst = 0;
    for (std::size_t i = 0; i < f.n; ++i) {
      EXPECT_EQ(f.drho[i], Real(0)) << "continuity rate at rest is exactly zero, particle " << i;
      px += double(f.m[i]) * f.a[i][0];
      py += double(f.m[i]) * f.a[i][1];
      abs_sum += double(f.m[i]) * std::hypot(double(f.a[i][0]), double(f.a[i][1]));
      if (interior(f.x[i], h)) worst = std::max(worst, std::hypot(double(f.a[i][0]), double(f.a[i][1])));
    }
    // Reference: lattice symmetry, the interior pressure forces cancel pair by pair. What is left
    // is the rounding of float positions (|x| <= 0.3 m, eps |x| / r <= 2e-6 per pair), summed
    // over ~20 pairs: below 1e-4 of the one-sided sum.
    EXPECT_LT(worst, 1e-4 * scale) << "largest interior acceleration vs one-sided pressure sum " << scale;
    // Free-surface particles are pushed outwards by p_b, but the total momentum change is zero
    // (antisymmetric pair forces; float accumulation, rel 1e-6).
    ASSERT_GT(abs_sum, 0.0);
    EXPECT_LT(std::hypot(px, py), 1e-6 * abs_sum) << "sum m a vs sum m |a|";
  }
}

// ---------------------------------------------------------------------------------------------
// (b) Momentum conservation with random velocities (and densities)

void check_momentum(const SceneOptions& o, bool random_density) {
  SCOPED_TRACE(label(o) + (random_density ? " random density" : " uniform density"));
  fsi::Simulation sim(make_scene(o), cpu());
  sim.start();
  Fields f = fields(sim);
  std::mt19937 rng(31337u);
  auto u = [&] { return double(rng() >> 8) * (1.0 / 16777216.0) - 0.5; };  // [-0.5, 0.5)
  for (std::size_t i = 0; i < f.n; ++i) {
    f.v[i][0] = Real(2.0 * u());  // |v| ~ 1 m/s (a tenth of c0 = 20 m/s)
    f.v[i][1] = Real(2.0 * u());
    // Masses stay rho0 dx^2; a density change of +-0.5% gives pressures of +-0.035 B.
    if (random_density) f.rho[i] = Real(kRho0 * (1.0 + 0.01 * u()));
  }
  sim.backend().sync_from_host();
  sim.backend().compute_forces();
  f = fields(sim);
  double px = 0, py = 0, abs_sum = 0;
  for (std::size_t i = 0; i < f.n; ++i) {
    px += double(f.m[i]) * f.a[i][0];
    py += double(f.m[i]) * f.a[i][1];
    abs_sum += double(f.m[i]) * std::hypot(double(f.a[i][0]), double(f.a[i][1]));
  }
  ASSERT_GT(abs_sum, 0.0) << "test setup: forces act";
  // Reference: Newton's third law. Every pair term (pressure, artificial or laminar viscosity)
  // is antisymmetric in i, j, so sum_i m_i a_i = 0; the residual is float accumulation of each
  // particle's sum (rel ~1e-7 per particle, partly cancelling): rel 1e-6 of sum m |a|.
  EXPECT_LT(std::hypot(px, py), 1e-6 * abs_sum) << "|sum m a| = " << std::hypot(px, py) << ", sum m|a| = " << abs_sum;
}

TEST(PhysicsPasses, MomentumConservedArtificialViscosity) {
  SceneOptions o;
  o.viscosity = fsi::ViscosityKind::artificial;
  o.artificial_viscosity = 0.1;
  check_momentum(o, false);  // viscosity alone (p = 0)
  check_momentum(o, true);   // pressure and viscosity
  o.kernel = sph::KernelKind::cubic_spline;
  check_momentum(o, true);
}

TEST(PhysicsPasses, MomentumConservedLaminarViscosity) {
  SceneOptions o;
  o.viscosity = fsi::ViscosityKind::laminar;
  o.dynamic_viscosity = 1.0;  // large enough that viscosity competes with pressure
  check_momentum(o, false);
  check_momentum(o, true);
  o.smoothing_ratio = 2.0;
  o.kernel = sph::KernelKind::cubic_spline;
  check_momentum(o, true);
}

// Mixed h (transition issue: "pairwise forces stay antisymmetric, so momentum is conserved to
// rounding"): a random cloud (jittered lattice, h random in [h0/2, h0] as after splitting, masses
// rho V with V following h^2) of two materials (water; Bingham debris with its own density, sound
// speed and per-particle effective viscosity), beside a structure along two sides (its particles
// with random h too). Built on the CPU backend directly (the Simulation starts with uniform h).
// Reference: Newton's third law. Every fluid-fluid pair term uses the kernel of the mean h and
// symmetric means of the pair's properties, so it is antisymmetric; the structure force pass
// evaluates the fluid's pair function for the same pairs, so the force on the structure is the
// exact reaction. Hence sum_fluid m a + sum_structure F = 0, with the residual of float
// accumulation: rel 1e-6 of sum m |a| + sum |F|, the bound of the uniform-h tests above.
void check_momentum_mixed_h(sph::Viscosity viscosity, sph::Boundary boundary) {
  using namespace turbid::sph;
  SCOPED_TRACE(std::string(viscosity == Viscosity::laminar ? "laminar + Bingham" : "artificial") +
               (boundary == Boundary::mdbc ? ", mDBC no-slip" : ", DBC"));
  const double h0 = 2.0 * kDx;
  PhysicsParams p;
  p.dimensions = 2;
  p.smoothing_length = Real(h0);
  p.max_smoothing_length = Real(h0);
  p.uniform_h = false;
  p.diffusion = Diffusion::fourtakas;
  p.viscosity = viscosity;
  p.artificial_viscosity = Real(0.05);
  p.boundary = boundary;
  p.wall_no_slip = boundary == Boundary::mdbc;
  p.rheology = viscosity == Viscosity::laminar;
  p.body_count = 1;
  p.material_count = 2;
  p.materials[0].eos = TaitEos::make(1000.0, 20.0, 7.0, 0.0);
  p.materials[0].sound_speed = Real(20.0);
  p.materials[0].dynamic_viscosity = Real(1e-2);
  p.materials[0].rheology.consistency = Real(1e-2);
  p.materials[1].eos = TaitEos::make(1950.0, 30.0, 7.0, 0.0);
  p.materials[1].sound_speed = Real(30.0);
  p.materials[1].non_newtonian = true;
  p.materials[1].dynamic_viscosity = Real(50.0);  // cap
  p.materials[1].rheology.yield_stress = Real(20.0);
  p.materials[1].rheology.consistency = Real(0.1);
  p.materials[1].rheology.regularisation = Real(100.0);
  p.materials[1].rheology.max_viscosity = Real(50.0);
  ParticleStore s;
  const FieldIds ids = register_fields(s, p, true);
  std::mt19937 rng(4242u);
  auto u = [&] { return double(rng() >> 8) * (1.0 / 16777216.0) - 0.5; };  // [-0.5, 0.5)
  const int n = 30, layers = 3;
  for (int b = -layers; b < n; ++b)
    for (int a = -layers; a < n; ++a) {
      const bool wall = a < 0 || b < 0;
      const std::size_t i = s.size();
      s.resize(i + 1);
      const double hf = 0.5 + 0.5 * (u() + 0.5);  // h / h0 in [0.5, 1)
      const int mat = a + b < n ? 1 : 0;           // debris in the lower-left triangle
      const double rho0 = mat == 1 ? 1950.0 : 1000.0;
      double x = (a + 0.5) * kDx, y = (b + 0.5) * kDx;
      if (!wall) {
        x += 0.4 * kDx * u();
        y += 0.4 * kDx * u();
      }
      s.data<Vec<2>>(ids.position)[i] = Vec<2>{{Real(x), Real(y)}};
      s.data<Vec<2>>(ids.velocity)[i] = wall ? Vec<2>::zero() : Vec<2>{{Real(2.0 * u()), Real(2.0 * u())}};
      s.data<Real>(ids.density)[i] = Real(rho0 * (1.0 + 0.01 * u()));
      s.data<Real>(ids.mass)[i] = Real(rho0 * std::pow(hf * kDx, 2));
      s.data<Real>(ids.smoothing_length)[i] = Real(hf * h0);
      s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(wall ? Kind::structure : Kind::fluid);
      s.data<std::uint8_t>(ids.material)[i] = std::uint8_t(wall ? 0 : mat);
      s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
      s.data<std::uint8_t>(ids.body)[i] = wall ? 0 : kNoBody;
      if (ids.boundary_normal >= 0)  // ghost node mirrored across the faces x = 0 and y = 0
        s.data<Vec<2>>(ids.boundary_normal)[i] =
            wall ? Vec<2>{{Real(a < 0 ? -2.0 * x : 0.0), Real(b < 0 ? -2.0 * y : 0.0)}} : Vec<2>::zero();
    }
  Domain dom;
  for (int k = 0; k < 2; ++k) {
    dom.min[k] = -0.1;
    dom.max[k] = 0.4;
  }
  auto be = make_cpu_backend(1);
  be->bind(s, ids, p, dom);
  ASSERT_EQ(be->update_neighbours(), 0u);
  be->compute_forces();
  const Vec<2>* a = s.data<Vec<2>>(ids.acceleration);
  const Vec<2>* f = s.data<Vec<2>>(ids.structure_force);
  const Real* m = s.data<Real>(ids.mass);
  const std::uint8_t* kind = s.data<std::uint8_t>(ids.kind);
  const Real* h = s.data<Real>(ids.smoothing_length);
  double px = 0, py = 0, scale = 0, wall_x = 0, wall_y = 0;
  std::size_t fluid = 0;
  Real h_min = Real(h0), h_max = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    h_min = std::min(h_min, h[i]);
    h_max = std::max(h_max, h[i]);
    if (kind[i] == std::uint8_t(Kind::fluid)) {
      ++fluid;
      px += double(m[i]) * a[i][0];
      py += double(m[i]) * a[i][1];
      scale += double(m[i]) * std::hypot(double(a[i][0]), double(a[i][1]));
    } else {
      wall_x += f[i][0];
      wall_y += f[i][1];
      scale += std::hypot(double(f[i][0]), double(f[i][1]));
    }
  }
  ASSERT_EQ(fluid, std::size_t(n * n));
  ASSERT_LT(h_min, Real(0.55 * h0)) << "test setup: h spans [h0/2, h0]";
  ASSERT_GT(h_max, Real(0.95 * h0));
  ASSERT_GT(std::hypot(wall_x, wall_y), 1e-3 * scale) << "test setup: the structure takes a share of the momentum";
  const double residual = std::hypot(px + wall_x, py + wall_y);
  std::printf("mixed-h momentum: |sum m a + F_structure| = %.3e, sum m|a| + |F| = %.3e (rel %.1e); F_structure = (%.3e, %.3e)\n",
              residual, scale, residual / scale, wall_x, wall_y);
  EXPECT_LT(residual, 1e-6 * scale);
}

TEST(PhysicsPasses, MomentumConservedMixedHArtificialViscosityDbc) {
  check_momentum_mixed_h(sph::Viscosity::artificial, sph::Boundary::dbc);
}
TEST(PhysicsPasses, MomentumConservedMixedHLaminarBinghamMdbc) {
  check_momentum_mixed_h(sph::Viscosity::laminar, sph::Boundary::mdbc);
}

// ---------------------------------------------------------------------------------------------
// (c) Uniform compression

void check_compression(const SceneOptions& o, double analytic_tolerance) {
  SCOPED_TRACE(label(o));
  fsi::Simulation sim(make_scene(o), cpu());
  sim.start();
  Fields f = fields(sim);
  const double k = 2.0;  // compression rate [1/s]
  const double c = 0.5 * kSide;
  for (std::size_t i = 0; i < f.n; ++i)
    for (int d = 0; d < 2; ++d) f.v[i][d] = Real(-k * (double(f.x[i][d]) - c));  // v = -k (x - x_c)
  sim.backend().sync_from_host();
  sim.backend().compute_density_rate();
  f = fields(sim);
  const double h = sim.params().smoothing_length;
  const double expected = kRho0 * k * 2.0;  // -rho div v = rho k D, D = 2
  const double discrete = kRho0 * k * lattice_trace(h, o.kernel);
  std::size_t inner = 0;
  for (std::size_t i = 0; i < f.n; ++i) {
    if (!interior(f.x[i], h)) continue;
    ++inner;
    // Reference 1 (brute force): the SPH sum rho k sum_j -F r^2 V_j over the lattice in double;
    // the pass must reproduce it up to float rounding of positions and velocities (~2e-6), rel 1e-4.
    // Diffusion vanishes for a uniform density.
    EXPECT_NEAR(f.drho[i], discrete, 1e-4 * discrete) << "particle at (" << f.x[i][0] << ", " << f.x[i][1] << ")";
    // Reference 2 (analytic): -rho div v = rho k D, within the lattice consistency error of the
    // kernel (test_kernels.cpp: 1% for h/dx = 1.7 and 2.0; 2.6% for Wendland at h/dx = 1.3).
    EXPECT_NEAR(f.drho[i], expected, analytic_tolerance * expected)
        << "particle at (" << f.x[i][0] << ", " << f.x[i][1] << ")";
  }
  EXPECT_GE(inner, 400u) << "test setup: interior particles present";
}

TEST(PhysicsPasses, ContinuityUnderUniformCompression) {
  for (auto kernel : {sph::KernelKind::wendland_c2, sph::KernelKind::cubic_spline})
    for (double ratio : {1.3, 1.7, 2.0})
      for (auto diff : {fsi::DiffusionKind::none, fsi::DiffusionKind::fourtakas}) {
        SceneOptions o;
        o.kernel = kernel;
        o.smoothing_ratio = ratio;
        o.diffusion = diff;
        // 1% as asked where the lattice allows it; at h/dx = 1.3 the discrete divergence of the
        // lattice itself is off by -2.6% (Wendland) / +1.05% (cubic spline), hence 3%.
        check_compression(o, ratio < 1.5 ? 0.03 : 0.01);
      }
}

// ---------------------------------------------------------------------------------------------
// Beyond the required checks: signs and sizes of gravity, diffusion and laminar viscosity.

// (d) A column at rest with the hydrostatic initial density (physics.md D8): the pressure gradient
// balances gravity at interior particles. Reference: analytic balance -grad p / rho + g = 0. Two
// known discrepancies bound the residual: the lattice consistency error of the discrete gradient
// |1 - M_yy| (test_kernels.cpp: 2.6% at h/dx = 1.3, 0.09% at 2.0) and the initial state
// p = rho0 g d (D8) against the balance dp/dd = rho g, off by rho/rho0 - 1 <= g H / c0^2 = 0.74%.
TEST(PhysicsPasses, HydrostaticPressureBalancesGravity) {
  const double g = 9.81;
  for (auto kernel : {sph::KernelKind::wendland_c2, sph::KernelKind::cubic_spline})
    for (double ratio : {1.3, 2.0}) {
      SceneOptions o;
      o.kernel = kernel;
      o.smoothing_ratio = ratio;
      o.gravity = g;
      SCOPED_TRACE(label(o));
      fsi::Simulation sim(make_scene(o), cpu());
      sim.start();
      const Fields f = fields(sim);
      const double h = sim.params().smoothing_length;
      const double tolerance = ratio < 1.5 ? 0.04 : 0.01;  // (2.6% or 0.09%) + 0.74%, rounded up
      std::size_t inner = 0;
      for (std::size_t i = 0; i < f.n; ++i) {
        if (!interior(f.x[i], h)) continue;
        ++inner;
        EXPECT_LT(std::hypot(double(f.a[i][0]), double(f.a[i][1])), tolerance * g)
            << "net acceleration at (" << f.x[i][0] << ", " << f.x[i][1] << ")";
      }
      EXPECT_GE(inner, 400u);
    }
}

// (e) Density diffusion in the same hydrostatic column at rest (v = 0, so the density rate is the
// diffusion term alone). References (physics.md C3, C4):
//  - Molteni & Colagrossi is not zero in hydrostatics: at the free surface, where the support is
//    cut, it diffuses density upwards (positive rate: the particles below are denser);
//  - Antuono's renormalised term vanishes for a linear density profile; the Tait profile's
//    curvature (rho'' r^2 / 2 vs rho' r: 1e-3) and float rounding of rho leave < 2e-3 of Molteni's;
//  - Fourtakas subtracts the hydrostatic difference computed with rho0 and B, which differs from
//    the local one by (gamma - 1) g d / c0^2 (4.4% at the bottom, d = 0.3 m, 0.07% in the top row);
//    its prefactor delta 2h is twice Molteni's delta h: < 8.8% of Molteni's maximum everywhere and
//    < 2e-3 of it in the top row. A wrong sign of rho^H would instead double the Molteni value.
TEST(PhysicsPasses, DiffusionInHydrostaticColumn) {
  double max_rate[4] = {}, top_rate[4] = {};
  const double g = 9.81, c0 = 20.0, gamma = 7.0;
  for (auto diff : {fsi::DiffusionKind::molteni, fsi::DiffusionKind::antuono, fsi::DiffusionKind::fourtakas}) {
    SceneOptions o;
    o.diffusion = diff;
    o.gravity = g;
    fsi::Simulation sim(make_scene(o), cpu());
    sim.start();
    sim.backend().compute_density_rate();
    const Fields f = fields(sim);
    const int d = int(diff);
    for (std::size_t i = 0; i < f.n; ++i) {
      max_rate[d] = std::max(max_rate[d], std::abs(double(f.drho[i])));
      // the top row, away from the side edges
      if (f.x[i][1] > kSide - kDx && f.x[i][0] > 0.1 && f.x[i][0] < 0.2 && std::abs(f.drho[i]) > std::abs(top_rate[d]))
        top_rate[d] = f.drho[i];  // signed value of largest magnitude
    }
  }
  const int mol = int(fsi::DiffusionKind::molteni), ant = int(fsi::DiffusionKind::antuono),
            fou = int(fsi::DiffusionKind::fourtakas);
  EXPECT_GT(top_rate[mol], 1.0) << "Molteni diffuses density upwards at the free surface [kg/m^3/s]";
  EXPECT_LT(max_rate[ant], 2e-3 * max_rate[mol]) << "Antuono vanishes for the hydrostatic profile";
  EXPECT_LT(max_rate[fou], 2.0 * (gamma - 1.0) * g * kSide / (c0 * c0) * max_rate[mol])
      << "Fourtakas removes the hydrostatic part";
  EXPECT_LT(std::abs(top_rate[fou]), 2e-3 * max_rate[mol]) << "Fourtakas in the top row";
}

// (f) Morris laminar viscosity of a parabolic shear flow v = (k (y - y_c)^2, 0) at interior
// particles. References: (1) brute force: on the lattice the odd part of v_ij cancels and the sum
// is 2 nu k sum_j V_j (-F) dy^2 r^2 / (r^2 + eta^2), evaluated here in double (rel 1e-3: float
// rounding of v amplified by the cancellation of the odd part, ~1e-4); (2) analytic nu d2v/dy2 =
// 2 nu k, within the lattice consistency error plus the eta^2 = 0.01 h^2 regularisation (~1.5%):
// 4% at h/dx = 1.3, 2% at 2.0. a_y must vanish exactly (v_y = 0, no pressure).
TEST(PhysicsPasses, LaminarViscosityGivesNuLaplacian) {
  for (auto kernel : {sph::KernelKind::wendland_c2, sph::KernelKind::cubic_spline})
    for (double ratio : {1.3, 2.0}) {
      SceneOptions o;
      o.kernel = kernel;
      o.smoothing_ratio = ratio;
      o.viscosity = fsi::ViscosityKind::laminar;
      o.dynamic_viscosity = 1.0;
      SCOPED_TRACE(label(o));
      fsi::Simulation sim(make_scene(o), cpu());
      sim.start();
      Fields f = fields(sim);
      const double k = 10.0, c = 0.5 * kSide;  // [1/(m s)], centre line [m]
      for (std::size_t i = 0; i < f.n; ++i) {
        const double y = double(f.x[i][1]) - c;
        f.v[i][0] = Real(k * y * y);
        f.v[i][1] = 0;
      }
      sim.backend().sync_from_host();
      sim.backend().compute_forces();
      f = fields(sim);
      const double h = sim.params().smoothing_length;
      const double nu = o.dynamic_viscosity / kRho0;
      const double analytic = 2.0 * nu * k;
      double lattice = 0;
      const int n = int(std::ceil(2.0 * h / kDx)) + 1;
      for (int a = -n; a <= n; ++a)
        for (int b = -n; b <= n; ++b) {
          const double r = std::hypot(a * kDx, b * kDx);
          if (r == 0) continue;
          const double F = kernel_f(kernel, r, h);
          const double dy = b * kDx;
          lattice += kDx * kDx * (-F) * dy * dy * r * r / (r * r + 0.01 * h * h);
        }
      const double discrete = 2.0 * nu * k * lattice;
      const double tolerance = ratio < 1.5 ? 0.04 : 0.02;
      std::size_t inner = 0;
      for (std::size_t i = 0; i < f.n; ++i) {
        if (!interior(f.x[i], h)) continue;
        ++inner;
        EXPECT_NEAR(f.a[i][0], discrete, 1e-3 * discrete) << "brute-force lattice sum, y = " << f.x[i][1];
        EXPECT_NEAR(f.a[i][0], analytic, tolerance * analytic) << "nu d2v/dy2, y = " << f.x[i][1];
        EXPECT_EQ(f.a[i][1], Real(0)) << "no force across the flow";
      }
      EXPECT_GE(inner, 400u);
    }
}

// (f') The central pair form (pair::ViscousPair, numerics: viscosity: stress: central): its
// continuum limit is the divergence of mu (grad v + grad v^T) + mu (div v) I, i.e.
// mu (lap v + 2 grad div v) for a constant mu, through the kernel's fourth moment, which a square
// lattice samples anisotropically. Two quadratic fields on the interior of the block:
//   v = (k x^2, 0): div v = 2 k x, a_x = nu (2 k + 4 k) = 6 nu k (the Laplacian form gives 2 nu k:
//                   it drops grad div v = div (grad v)^T); reference: analytic, within 5% at
//                   h/dx 1.3 and 1% at 2.0 (measured 1.6% / 4.5% and 0.3% / 0.6%, Wendland / cubic);
//   v = (k y^2, 0): a shear along a lattice axis, a_x = 2 nu k in the continuum; reference: the
//                   brute-force lattice sum of the same pair term in double (1e-3), which is below
//                   2 nu k by the lattice's anisotropy: 20% / 14% at h/dx 1.3, 5% / 4% at 2.0.
// That anisotropy is why the central form is not the default (docs/choices.md).
TEST(PhysicsPasses, CentralFormGivesTheDivergenceOfGradVPlusItsTranspose) {
  for (auto kernel : {sph::KernelKind::wendland_c2, sph::KernelKind::cubic_spline})
    for (double ratio : {1.3, 2.0})
      for (int field = 0; field < 2; ++field) {
        SceneOptions o;
        o.kernel = kernel;
        o.smoothing_ratio = ratio;
        o.viscosity = fsi::ViscosityKind::laminar;
        o.dynamic_viscosity = 1.0;
        o.viscous_stress = fsi::ViscousStress::central;
        SCOPED_TRACE(label(o) + (field ? " v = (k x^2, 0)" : " v = (k y^2, 0)"));
        fsi::Simulation sim(make_scene(o), cpu());
        ASSERT_TRUE(sim.params().materials[0].central_stress);
        sim.start();
        Fields f = fields(sim);
        const double k = 10.0, c = 0.5 * kSide;  // [1/(m s)], centre [m]
        for (std::size_t i = 0; i < f.n; ++i) {
          const double s = double(f.x[i][field == 0 ? 1 : 0]) - c;
          f.v[i][0] = Real(k * s * s);
          f.v[i][1] = 0;
        }
        sim.backend().sync_from_host();
        sim.backend().compute_forces();
        f = fields(sim);
        const double h = sim.params().smoothing_length;
        const double nu = o.dynamic_viscosity / kRho0;
        // Brute-force lattice sum: a_x = sum_j V_j (D + 2) 2 nu F (r . v_ij) r_x / (r^2 + eta^2), with
        // v_ij = -k (2 s_i ds + ds^2) along x; the part odd in ds cancels on the interior.
        double lattice = 0;
        const int n = int(std::ceil(2.0 * h / kDx)) + 1;
        for (int a = -n; a <= n; ++a)
          for (int b = -n; b <= n; ++b) {
            const double rx = a * kDx, ry = b * kDx, r = std::hypot(rx, ry);
            if (r == 0) continue;
            const double ds = field == 0 ? ry : rx;
            lattice += kDx * kDx * 4.0 * 2.0 * nu * kernel_f(kernel, r, h) * rx * rx * (-k * ds * ds) / (r * r + 0.01 * h * h);
          }
        const double analytic = (field == 1 ? 6.0 : 2.0) * nu * k;
        std::size_t inner = 0;
        for (std::size_t i = 0; i < f.n; ++i) {
          if (!interior(f.x[i], h)) continue;
          ++inner;
          EXPECT_NEAR(f.a[i][0], lattice, 1e-3 * lattice) << "brute-force lattice sum, x = " << f.x[i][0];
          if (field == 1) EXPECT_NEAR(f.a[i][0], analytic, (ratio < 1.5 ? 0.05 : 0.01) * analytic) << "6 nu k";
          EXPECT_NEAR(f.a[i][1], 0.0, 1e-4 * analytic) << "no force across the flow";
        }
        EXPECT_GE(inner, 400u);
        std::printf("[ measured ] %s: lattice sum / continuum %.4f\n", label(o).c_str(), lattice / analytic);
      }
}

// Angular momentum (the central form's pair force lies along r_ij, as the pressure force does):
// for random velocities and densities, sum_i m_i (x_i - c) x a_i = 0 to the float accumulation of
// the pair sums (rel 1e-6 of sum_i m_i |x_i - c| |a_i|, the bound of the momentum tests). The
// Laplacian form's pair force is along v_ij, not r_ij: its torque here is 8e-5 of the same scale,
// which the test checks is above 1e-5 so that the bound is shown to bite.
TEST(PhysicsPasses, CentralFormConservesAngularMomentum) {
  for (auto stress : {fsi::ViscousStress::central, fsi::ViscousStress::laplacian}) {
    SceneOptions o;
    o.viscosity = fsi::ViscosityKind::laminar;
    o.dynamic_viscosity = 1.0;
    o.viscous_stress = stress;
    fsi::Simulation sim(make_scene(o), cpu());
    sim.start();
    Fields f = fields(sim);
    std::mt19937 rng(4242u);
    auto u = [&] { return double(rng() >> 8) * (1.0 / 16777216.0) - 0.5; };
    for (std::size_t i = 0; i < f.n; ++i) {
      f.v[i][0] = Real(2.0 * u());
      f.v[i][1] = Real(2.0 * u());
      f.rho[i] = Real(kRho0 * (1.0 + 0.01 * u()));
    }
    sim.backend().sync_from_host();
    sim.backend().compute_forces();
    f = fields(sim);
    const double c = 0.5 * kSide;
    double torque = 0, scale = 0;
    for (std::size_t i = 0; i < f.n; ++i) {
      const double rx = double(f.x[i][0]) - c, ry = double(f.x[i][1]) - c;
      const double ax = f.a[i][0], ay = f.a[i][1];
      torque += double(f.m[i]) * (rx * ay - ry * ax);
      scale += double(f.m[i]) * std::hypot(rx, ry) * std::hypot(ax, ay);
    }
    ASSERT_GT(scale, 0.0);
    const bool central = stress == fsi::ViscousStress::central;
    std::printf("[ measured ] %s: |torque| / scale %.2e\n", central ? "central form" : "Laplacian form",
                std::abs(torque) / scale);
    if (central) EXPECT_LT(std::abs(torque), 1e-6 * scale);
    else EXPECT_GT(std::abs(torque), 1e-5 * scale);
  }
}

TEST(PhysicsPasses, MomentumConservedCentralForm) {
  SceneOptions o;
  o.viscosity = fsi::ViscosityKind::laminar;
  o.dynamic_viscosity = 1.0;
  o.viscous_stress = fsi::ViscousStress::central;
  check_momentum(o, false);
  check_momentum(o, true);
}

// (g) Determinism (design.md: gather, not scatter): the same scene on 1 and 2 threads gives the
// same bits for accelerations, density rates, positions and densities after a step with
// gravity, random velocities, diffusion and viscosity. Reference: bitwise equality (memcmp).
TEST(PhysicsPasses, ThreadCountDoesNotChangeBits) {
  SceneOptions o;
  o.gravity = 9.81;
  o.diffusion = fsi::DiffusionKind::antuono;
  o.viscosity = fsi::ViscosityKind::laminar;
  o.dynamic_viscosity = 0.1;
  auto run = [&](int threads) {
    auto sim = std::make_unique<fsi::Simulation>(make_scene(o), cpu(threads));
    sim->start();
    Fields f = fields(*sim);
    std::mt19937 rng(4242u);
    for (std::size_t i = 0; i < f.n; ++i)
      for (int d = 0; d < 2; ++d) f.v[i][d] = Real(0.2 * (double(rng() >> 8) / 16777216.0 - 0.5));
    sim->backend().sync_from_host();
    sim->backend().compute_forces();
    sim->step();  // one full kick-drift-sort-kick step (few parallel regions: fast on a loaded machine)
    sim->backend().compute_density_rate();
    sim->sync_to_host();
    return sim;
  };
  auto one = run(1), two = run(2);
  ASSERT_EQ(one->store().size(), two->store().size());
  const auto& ids = one->fields();
  for (auto field : {ids.position, ids.velocity, ids.acceleration, ids.density, ids.density_rate, ids.pressure, ids.id}) {
    const std::size_t bytes = one->store().size() * one->store().field_bytes(field);
    EXPECT_EQ(std::memcmp(one->store().raw(field), two->store().raw(field), bytes), 0)
        << "field " << one->store().desc(field).name << " differs between 1 and 2 threads";
  }
  EXPECT_EQ(one->time(), two->time());
}

// ---------------------------------------------------------------------------------------------
// (h) Particle shifting, u_s = -A h |v| grad C with grad C_i = sum_j V_j grad_i W_ij (Lind et al.
// 2012; Skillen et al. 2013), in a block moving at v = (1, 0.5) m/s.

struct ShiftedBlock {
  std::unique_ptr<fsi::Simulation> sim;
  Vec<2>* shift = nullptr;
  Fields f{};
};

Vec<2> uniform_flow(const Vec<2>&) {
  Vec<2> v;
  v[0] = Real(1.0);
  v[1] = Real(0.5);
  return v;
}

// `displaced`: index (in the lattice order of the block) of a particle moved by `offset` first;
// then every particle gets the velocity `flow` gives at its position.
ShiftedBlock shifted_block(const SceneOptions& o, std::size_t displaced, const Vec<2>& offset,
                           Vec<2> (*flow)(const Vec<2>&) = uniform_flow) {
  ShiftedBlock b;
  b.sim = std::make_unique<fsi::Simulation>(make_scene(o), cpu());
  b.sim->start();
  Fields f = fields(*b.sim);
  if (displaced < f.n) f.x[displaced] += offset;
  for (std::size_t i = 0; i < f.n; ++i) f.v[i] = flow(f.x[i]);
  b.sim->backend().sync_from_host();
  b.sim->backend().update_neighbours();
  b.sim->backend().compute_forces();
  b.f = fields(*b.sim);
  const auto id = b.sim->fields().shifting_velocity;
  b.shift = id >= 0 ? b.sim->store().data<Vec<2>>(id) : nullptr;
  return b;
}

TEST(PhysicsPasses, ShiftingVanishesOnAUniformLatticeAndAtTheFreeSurface) {
  {
    SceneOptions o;  // shifting off: no field, nothing to pay
    EXPECT_LT(shifted_block(o, ~std::size_t(0), Vec<2>::zero()).sim->fields().shifting_velocity, 0);
  }
  SceneOptions o;
  o.shifting = 2.0;
  o.smoothing_ratio = 2.0;
  ShiftedBlock b = shifted_block(o, ~std::size_t(0), Vec<2>::zero());
  ASSERT_NE(b.shift, nullptr);
  const double h = b.sim->params().smoothing_length;
  EXPECT_DOUBLE_EQ(double(b.sim->params().shifting_surface_threshold), 1.5) << "default D - 1/2 in 2D";
  // Scale: A h |v| times one side of the gradient sum, sum_j V_j |F| r.
  const double scale = 2.0 * h * std::hypot(1.0, 0.5) * lattice_abs_gradient(h, o.kernel);
  std::size_t inner = 0, edge = 0;
  for (std::size_t i = 0; i < b.f.n; ++i) {
    const Vec<2>& x = b.f.x[i];
    const double u = std::hypot(double(b.shift[i][0]), double(b.shift[i][1]));
    if (interior(x, h)) {
      // Reference: lattice symmetry, grad C = 0 up to float rounding of positions (rel ~1e-6).
      EXPECT_LT(u, 1e-4 * scale) << "interior particle at (" << x[0] << ", " << x[1] << ")";
      ++inner;
    }
    const bool on_edge = x[0] < 0.5 * kDx || x[1] < 0.5 * kDx || x[0] > kSide - kDx || x[1] > kSide - kDx;
    if (on_edge) {
      // div r of a particle on the block's edge is about 1 (half its support is empty) < 1.5:
      // a free surface is not shifted (it would be pulled into the fluid).
      EXPECT_EQ(u, 0.0) << "edge particle at (" << x[0] << ", " << x[1] << ")";
      ++edge;
    }
  }
  EXPECT_GE(inner, 300u);
  EXPECT_EQ(edge, 4u * 29u);

  // Without free-surface detection an edge particle is shifted outwards, down the concentration
  // gradient (Fick's law): here the bottom-left corner, towards (-1, -1).
  o.shifting_surface_threshold = 0.0;
  ShiftedBlock all = shifted_block(o, ~std::size_t(0), Vec<2>::zero());
  for (std::size_t i = 0; i < all.f.n; ++i)
    if (all.f.x[i][0] < 0.5 * kDx && all.f.x[i][1] < 0.5 * kDx) {
      EXPECT_LT(all.shift[i][0], 0) << "corner particle moves out of the block";
      EXPECT_LT(all.shift[i][1], 0);
    }
}

// The particle nearest the block's centre, moved by 0.2 dx along (1, 0.5) / |(1, 0.5)|, in the flow
// `flow`; grad C at its new place from the undisturbed lattice in double (the brute-force
// reference of u_s = -A h |v| grad C).
struct DisplacedCentre {
  ShiftedBlock b;
  std::size_t k = 0;  // its index after the sort
  Vec<2> offset;
  double grad_c[2] = {0, 0};
  double h = 0;
};

DisplacedCentre displaced_centre(const SceneOptions& o, Vec<2> (*flow)(const Vec<2>&)) {
  fsi::Simulation probe(make_scene(o), cpu());
  probe.start();
  const Fields p = fields(probe);
  std::size_t centre = 0;
  for (std::size_t i = 0; i < p.n; ++i)
    if (std::hypot(p.x[i][0] - 0.5 * kSide, p.x[i][1] - 0.5 * kSide) <
        std::hypot(p.x[centre][0] - 0.5 * kSide, p.x[centre][1] - 0.5 * kSide))
      centre = i;
  DisplacedCentre c;
  const Vec<2> site = p.x[centre];
  const double d = 0.2 * kDx / std::hypot(1.0, 0.5);
  c.offset[0] = Real(d);
  c.offset[1] = Real(0.5 * d);
  c.b = shifted_block(o, centre, c.offset, flow);
  c.h = c.b.sim->params().smoothing_length;
  // Find it again (the sort moved it) by its position.
  c.k = c.b.f.n;
  for (std::size_t i = 0; i < c.b.f.n; ++i)
    if (std::hypot(double(c.b.f.x[i][0] - site[0]) - c.offset[0], double(c.b.f.x[i][1] - site[1]) - c.offset[1]) < 1e-7)
      c.k = i;
  const double xi = double(site[0]) + double(c.offset[0]), yi = double(site[1]) + double(c.offset[1]);
  for (std::size_t j = 0; j < p.n; ++j) {
    if (j == centre) continue;
    const double rx = xi - double(p.x[j][0]), ry = yi - double(p.x[j][1]);
    const double r = std::hypot(rx, ry);
    if (r >= 2.0 * c.h) continue;
    const double F = kernel_f(o.kernel, r, c.h);
    c.grad_c[0] += kDx * kDx * F * rx;
    c.grad_c[1] += kDx * kDx * F * ry;
  }
  return c;
}

TEST(PhysicsPasses, ShiftingMovesADisplacedParticleBackToItsSite) {
  SceneOptions o;
  o.shifting = 2.0;
  o.smoothing_ratio = 2.0;
  const DisplacedCentre c = displaced_centre(o, uniform_flow);
  ASSERT_LT(c.k, c.b.f.n);
  // Reference (brute force, rel 1e-3: float positions and kernel values): u_s = -A h |v| grad C.
  const double speed = std::hypot(1.0, 0.5);
  const double ux = -2.0 * c.h * speed * c.grad_c[0], uy = -2.0 * c.h * speed * c.grad_c[1];
  const double u = std::hypot(ux, uy);
  ASSERT_GT(u, 0.0);
  EXPECT_NEAR(c.b.shift[c.k][0], ux, 1e-3 * u);
  EXPECT_NEAR(c.b.shift[c.k][1], uy, 1e-3 * u);
  // The shift points back to the lattice site: the particle sits on a slope of its neighbours'
  // concentration, whose minimum is the site (cosine with the offset within 1 degree of -1).
  const double cosine =
      (ux * c.offset[0] + uy * c.offset[1]) / (u * std::hypot(double(c.offset[0]), double(c.offset[1])));
  EXPECT_LT(cosine, -std::cos(M_PI / 180.0)) << "u_s = (" << ux << ", " << uy << ")";
  // A uniform flow has no velocity gradient: no Taylor correction, and no other force (p = 0,
  // artificial viscosity of equal velocities is 0).
  EXPECT_EQ(c.b.f.a[c.k][0], Real(0));
  EXPECT_EQ(c.b.f.a[c.k][1], Real(0));
}

// Shear flow v = (1 + k (y - y_c), 0.5) with k = 2 1/s: the shifted particle takes the velocity of
// the place it moves to, a = (u_s . grad) v = (k u_s,y, 0) (first-order Taylor correction).
Vec<2> shear_flow(const Vec<2>& x) {
  Vec<2> v;
  v[0] = Real(1.0 + 2.0 * (double(x[1]) - 0.5 * kSide));
  v[1] = Real(0.5);
  return v;
}

TEST(PhysicsPasses, ShiftingCarriesTheVelocityOfTheNewPlace) {
  SceneOptions o;
  o.shifting = 2.0;
  o.smoothing_ratio = 2.0;
  o.artificial_viscosity = 0.0;  // only the correction acts (p = 0 at rest density)
  const DisplacedCentre c = displaced_centre(o, shear_flow);
  ASSERT_LT(c.k, c.b.f.n);
  const Vec<2> v = shear_flow(c.b.f.x[c.k]);
  const double speed = std::hypot(double(v[0]), double(v[1]));
  const double uy = -2.0 * c.h * speed * c.grad_c[1];
  const double expected = 2.0 * uy;  // k u_s,y
  ASSERT_GT(std::abs(expected), 0.0);
  // Reference: the analytic gradient k e_x (x) e_y; the SPH gradient sum_j V_j (v_j - v_i) (x) grad W
  // reproduces it within the lattice consistency error at h/dx = 2 (1%, test_kernels.cpp) plus
  // the displacement's share (cross term k sum V F r_x r_y, a few per cent of k): 5%.
  EXPECT_NEAR(c.b.f.a[c.k][0], expected, 0.05 * std::abs(expected));
  EXPECT_NEAR(c.b.f.a[c.k][1], 0.0, 1e-3 * std::abs(expected)) << "v_y is uniform";
}

}  // namespace
