// Kernel sums on lattices whose particles carry different smoothing lengths, pairs through the
// kernel of the mean h (sph/passes.hpp pair_h), as the transition issue asks: "a mixed-h lattice
// still integrates the kernel to one and its gradient to zero within the foundation's tolerances".
// The foundation's tolerances are those of test_kernels.cpp (uniform lattice, interior particle):
// partition of unity |sum_j V_j W_ij - 1| within the lattice quadrature error of h/dx (1.2e-2 at
// 1.3, 3.5e-3 at 1.7, 1.5e-3 at 2.0) and |sum_j V_j grad_i W_ij| < 1e-5 / h (round-off: the lattice
// is symmetric under x -> -x); and that of test_physics_passes.cpp for the engine's momentum pass at
// uniform pressure (interior acceleration below 1e-4 of the one-sided pressure sum).
//
// What holds and what does not (2D, 40 x 40 lattice, interior particles; the numbers are printed):
//  - h patterns symmetric under x -> -x about every particle (checkerboard or row stripes of h0 and
//    1.25 h0): the gradient sum vanishes to round-off, brute force and through the engine's
//    momentum pass (asserted, foundation tolerances). The partition of unity there is printed, not
//    asserted: the pattern adds an aliasing error of the same order as the lattice's own, which
//    passes the foundation's bound for the cubic spline on the checkerboard but not for Wendland
//    (e.g. 1.8e-3 at h0/dx = 2.0 against 1.5e-3) nor for stripes (up to 4.9e-2 at 1.3).
//  - h without that symmetry (random in [h0, 1.25 h0], or a step): the mean-h kernel is
//    not first-order consistent where h varies, so the gradient sum is of order (dh/dx) / h, not
//    round-off (random: 0.07-0.10 / h0, unity off by 3-6%; a step h0 | 1.25 h0: 0.05-0.06 / h0 and
//    3-4%; printed, not asserted against the foundation).
//  - a refined block (daughters at dx/2 with h/2 inside a lattice of dx, h): the foundation's values
//    deep inside either region (asserted), the blip on the block's edge printed and bounded by the
//    known figure of the mean-h kernel (open in the transition issue: a remedy is being worked on).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "sph/backend.hpp"
#include "sph/fields.hpp"
#include "sph/kernels.hpp"
#include "sph/particle_store.hpp"
#include "sph/passes.hpp"
#include "sph/split_params.hpp"
#include "sph/vec.hpp"

namespace {

using namespace turbid::sph;

constexpr double kDx = 0.01;  // lattice spacing [m]
constexpr int kN = 40;        // kN x kN lattice
constexpr double kRho0 = 1000.0;

// test_kernels.cpp's kLatticeTolerances: partition of unity per h/dx.
double unity_tolerance(double ratio) {
  if (ratio == 1.3) return 1.2e-2;
  if (ratio == 1.7) return 3.5e-3;
  if (ratio == 2.0) return 1.5e-3;
  ADD_FAILURE() << "no foundation tolerance for h/dx = " << ratio;
  return 0;
}

enum class Pattern { uniform, checkerboard, stripes, random, step };
const char* name(Pattern p) {
  switch (p) {
    case Pattern::uniform: return "uniform";
    case Pattern::checkerboard: return "checkerboard";
    case Pattern::stripes: return "stripes";
    case Pattern::random: return "random";
    case Pattern::step: return "step";
  }
  return "";
}

// h of lattice site (a, b): h0 or 1.25 h0 by the pattern (random: uniform in [h0, 1.25 h0]).
std::vector<Real> h_pattern(Pattern p, double h0) {
  std::vector<Real> h(std::size_t(kN) * kN);
  std::mt19937 g(2024);
  for (int b = 0; b < kN; ++b)
    for (int a = 0; a < kN; ++a) {
      double f = 1.0;
      if (p == Pattern::checkerboard) f = (a + b) % 2 ? 1.25 : 1.0;
      if (p == Pattern::stripes) f = b % 2 ? 1.25 : 1.0;
      if (p == Pattern::random) f = 1.0 + 0.25 * double(g() >> 8) / 16777216.0;
      if (p == Pattern::step) f = a < kN / 2 ? 1.0 : 1.25;
      h[std::size_t(b) * kN + std::size_t(a)] = Real(f * h0);
    }
  return h;
}

// A fluid lattice at rest (v = 0, rho = rho0, m = rho0 dx^2) with the given h, bound to the CPU
// backend on the variable-h path; the EOS has a background pressure p_b, so every particle has
// p = p_b exactly and the momentum pass gives a_i = -(2 p_b / rho0) sum_j V_j grad_i W_ij.
template <class K>
struct Lattice {
  static constexpr double kBackground = 1000.0;  // p_b [Pa]
  PhysicsParams p;
  ParticleStore s;
  FieldIds ids;
  std::unique_ptr<Backend> be;

  // split_block: the 12 x 12 block in the middle splits (the engine's split: daughters at x +- a/4
  // with h/2, m/4) before the force pass.
  Lattice(const std::vector<Real>& h, double h0, bool split_block = false) {
    p.dimensions = 2;
    p.kernel = std::is_same_v<K, WendlandC2<2>> ? KernelKind::wendland_c2 : KernelKind::cubic_spline;
    p.smoothing_length = Real(h0);
    p.max_smoothing_length = *std::max_element(h.begin(), h.end());
    p.uniform_h = false;
    p.diffusion = Diffusion::none;
    p.viscosity = Viscosity::artificial;
    p.rheology = split_block;  // registers the shear stress the split reads
    p.material_count = 2;
    for (int m = 0; m < 2; ++m) {
      p.materials[m].eos = TaitEos::make(kRho0, 20.0, 7.0, kBackground);
      p.materials[m].sound_speed = Real(20.0);
      p.materials[m].dynamic_viscosity = Real(1e-3);
    }
    ids = register_fields(s, p);
    s.reserve(4 * h.size());
    s.resize(h.size());
    for (int b = 0; b < kN; ++b)
      for (int a = 0; a < kN; ++a) {
        const std::size_t i = std::size_t(b) * kN + std::size_t(a);
        s.data<Vec<2>>(ids.position)[i] = Vec<2>{{Real((a + 0.5) * kDx), Real((b + 0.5) * kDx)}};
        s.data<Vec<2>>(ids.velocity)[i] = Vec<2>::zero();
        s.data<Real>(ids.density)[i] = Real(kRho0);
        s.data<Real>(ids.mass)[i] = Real(kRho0 * kDx * kDx);
        s.data<Real>(ids.smoothing_length)[i] = h[i];
        s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(Kind::fluid);
        s.data<std::uint8_t>(ids.material)[i] = 0;
        s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
      }
    Domain dom;
    for (int k = 0; k < 2; ++k) {
      dom.min[k] = -0.05;
      dom.max[k] = kN * kDx + 0.05;
    }
    be = make_cpu_backend(1);
    be->bind(s, ids, p, dom);
    be->update_neighbours();
    if (split_block) {
      for (std::size_t i = 0; i < s.size(); ++i)
        s.data<Real>(ids.shear_stress)[i] = Real(in_block(s.data<Vec<2>>(ids.position)[i]) ? 500.0 : 0.0);
      SplitParams sp;
      sp.rule_count = 1;
      sp.rules[0].from = 0;
      sp.rules[0].to = 1;
      sp.rules[0].threshold = Real(150.0);
      sp.rules[0].interface_only = false;
      sp.rules[0].min_smoothing_length = Real(0.75 * h0);
      const SplitCounts c = be->split(sp);
      EXPECT_EQ(c.splits, 144u) << "the 12 x 12 block";
      be->update_neighbours();
    }
    be->compute_forces();
  }

  static bool in_block(const Vec<2>& x) {
    return std::abs(double(x[0]) - 0.2) < 0.06 && std::abs(double(x[1]) - 0.2) < 0.06;
  }

  ParticleView<2> view() {
    ParticleView<2> v;
    v.position = s.data<Vec<2>>(ids.position);
    v.mass = s.data<Real>(ids.mass);
    v.density = s.data<Real>(ids.density);
    v.smoothing_length = s.data<Real>(ids.smoothing_length);
    v.kind = s.data<std::uint8_t>(ids.kind);  // pair_h tells fluid from walls by it
    v.count = std::uint32_t(s.size());
    return v;
  }
};

struct Sums {
  double unity = 0;        // sum_j V_j W(r_ij, h_ij)
  double grad[2] = {0, 0}; // sum_j V_j grad_i W(r_ij, h_ij)
  double abs_grad = 0;     // sum_j V_j |grad_i W| r: the one-sided size of the gradient sum [1/m]
};

// Brute force over all particles, in double over the float kernel values, pair h from pair_h.
template <class K>
Sums sums(const ParticleView<2>& P, const PhysicsParams& prm, std::uint32_t i) {
  Sums out;
  for (std::uint32_t j = 0; j < P.count; ++j) {
    const double rx = double(P.position[i][0]) - double(P.position[j][0]);
    const double ry = double(P.position[i][1]) - double(P.position[j][1]);
    const double r = std::hypot(rx, ry);
    const Real h = pair_h<2, K>(P, prm, false, P.smoothing_length[i], j);
    const double V = double(P.mass[j]) / double(P.density[j]);
    out.unity += V * double(K::w(Real(r), h));
    if (r == 0) continue;
    const double F = K::f(Real(r), h);
    out.grad[0] += V * F * rx;
    out.grad[1] += V * F * ry;
    out.abs_grad += V * std::abs(F) * r;
  }
  return out;
}

// Interior: the full support of the largest pair (2 x 1.25 h0) inside the lattice.
bool interior(const Vec<2>& x, double h0) {
  const double m = 2.5 * h0;
  for (int k = 0; k < 2; ++k)
    if (double(x[k]) < m || double(x[k]) > kN * kDx - m) return false;
  return true;
}

struct Worst {
  double unity = 0, grad = 0, engine = 0, engine_vs_brute = 0;
};

template <class K>
Worst measure(Pattern pattern, double ratio) {
  const double h0 = ratio * kDx;
  Lattice<K> L(h_pattern(pattern, h0), h0);
  const ParticleView<2> P = L.view();
  const Vec<2>* acc = L.s.template data<Vec<2>>(L.ids.acceleration);
  Worst w;
  std::size_t inner = 0;
  for (std::uint32_t i = 0; i < P.count; ++i) {
    if (!interior(P.position[i], h0)) continue;
    ++inner;
    const Sums S = sums<K>(P, L.p, i);
    w.unity = std::max(w.unity, std::abs(S.unity - 1.0));
    w.grad = std::max(w.grad, std::hypot(S.grad[0], S.grad[1]) * h0);
    // The engine: a_i = -(2 p_b / rho0) sum_j V_j grad_i W_ij; its size relative to the one-sided
    // sum, and its difference from the brute-force sum (every pair found, each with pair_h).
    const double scale = 2.0 * Lattice<K>::kBackground / kRho0;
    const double e0 = -double(acc[i][0]) / scale, e1 = -double(acc[i][1]) / scale;
    w.engine = std::max(w.engine, std::hypot(e0, e1) / S.abs_grad);
    w.engine_vs_brute = std::max(w.engine_vs_brute, std::hypot(e0 - S.grad[0], e1 - S.grad[1]) / S.abs_grad);
  }
  EXPECT_GE(inner, std::size_t(100)) << "test setup: interior particles";
  std::printf("mixed h %-12s %s h0/dx=%.1f: |sum V W - 1| %.2e, |sum V grad W| h0 %.2e; engine |a| / one-sided %.2e,"
              " engine vs brute force %.2e\n",
              name(pattern), std::is_same_v<K, WendlandC2<2>> ? "wendland" : "cubic   ", ratio, w.unity, w.grad,
              w.engine, w.engine_vs_brute);
  return w;
}

// Symmetric patterns: the gradient sum and the engine's acceleration at uniform pressure vanish to
// round-off, with the foundation's tolerances; and the engine finds every pair of the mixed
// lattice (pair h up to 1.25 h0, beyond the initial h: the grid must cover 2 h_max).
template <class K>
void check_symmetric(Pattern pattern) {
  for (double ratio : {1.3, 1.7, 2.0}) {
    SCOPED_TRACE(std::string(name(pattern)) + " h0/dx = " + std::to_string(ratio));
    const Worst w = measure<K>(pattern, ratio);
    // Reference: the pattern and the lattice are symmetric under x -> -x about every site, so the
    // pairs' gradients cancel two by two; test_kernels.cpp's round-off bound 1e-5 / h.
    EXPECT_LT(w.grad, 1e-5) << "|sum_j V_j grad_i W(r_ij, (h_i + h_j)/2)| h0";
    // Reference: the same symmetry in the engine's float sum; test_physics_passes.cpp's bound for
    // the interior acceleration under a background pressure, 1e-4 of the one-sided sum.
    EXPECT_LT(w.engine, 1e-4) << "momentum pass at uniform pressure";
    // Reference: the brute-force double sum over all pairs; float accumulation of ~30 terms of
    // one sign each side (rel 1e-6 of the one-sided sum). A pair the grid misses (r up to 2.5 h0)
    // would leave a term of order 1e-3 of the one-sided sum.
    EXPECT_LT(w.engine_vs_brute, 1e-5) << "every pair within the pair support found";
  }
}

TEST(MixedH, CheckerboardGradientVanishesWendland) { check_symmetric<WendlandC2<2>>(Pattern::checkerboard); }
TEST(MixedH, CheckerboardGradientVanishesCubic) { check_symmetric<CubicSpline<2>>(Pattern::checkerboard); }
TEST(MixedH, StripesGradientVanishesWendland) { check_symmetric<WendlandC2<2>>(Pattern::stripes); }
TEST(MixedH, StripesGradientVanishesCubic) { check_symmetric<CubicSpline<2>>(Pattern::stripes); }

// The uniform lattice through the same code (h_i = h0 for all, variable-h path): the foundation's
// partition of unity, a check that the sums above are set up as test_kernels.cpp's are.
TEST(MixedH, UniformLatticeOnTheVariableHPathMeetsTheFoundation) {
  for (double ratio : {1.3, 1.7, 2.0}) {
    SCOPED_TRACE("h0/dx = " + std::to_string(ratio));
    const Worst wa = measure<WendlandC2<2>>(Pattern::uniform, ratio);
    const Worst wb = measure<CubicSpline<2>>(Pattern::uniform, ratio);
    EXPECT_LT(wa.unity, unity_tolerance(ratio));
    EXPECT_LT(wb.unity, unity_tolerance(ratio));
    EXPECT_LT(wa.grad, 1e-5);
    EXPECT_LT(wb.grad, 1e-5);
  }
}

// Patterns without the symmetry: printed. The engine still sums every pair with the brute force's
// pair h (asserted); the sums themselves show the mean-h kernel's inconsistency where h varies.
TEST(MixedH, AsymmetricPatternsAreMeasured) {
  for (Pattern pattern : {Pattern::random, Pattern::step})
    for (double ratio : {1.3, 1.7, 2.0}) {
      SCOPED_TRACE(std::string(name(pattern)) + " h0/dx = " + std::to_string(ratio));
      const Worst wa = measure<WendlandC2<2>>(pattern, ratio);
      const Worst wb = measure<CubicSpline<2>>(pattern, ratio);
      EXPECT_LT(wa.engine_vs_brute, 1e-5);
      EXPECT_LT(wb.engine_vs_brute, 1e-5);
    }
}

// A refined block: the 12 x 12 block in the middle of the 40 x 40 lattice split by the engine
// (Wendland, h0/dx = 2.0, as in test_splitting.cpp's density test). Deep inside either region (more
// than 2 h0 + dx/2 from the block's edge) the lattice is uniform with h/dx = 2 (the daughters' at
// dx/2 with h0/2): the foundation's tolerances (asserted). On the edge the sums are printed and
// bounded by the known state of the mean-h kernel: the partition of unity is off by up to 15.6% at
// daughters (test_splitting.cpp measured 15.5% for the summation density, which equals it here:
// m = rho0 V); bound 16%. The gradient sum there is up to 0.22 / h_i (measured); bound 0.25 / h_i.
// Both bounds are regression guards of an open defect, to tighten when its remedy lands.
TEST(MixedH, RefinedBlockMeetsTheFoundationAwayFromItsEdge) {
  using K = WendlandC2<2>;
  const double h0 = 2.0 * kDx;
  Lattice<K> L(h_pattern(Pattern::uniform, h0), h0, true);
  const ParticleView<2> P = L.view();
  const Vec<2>* acc = L.s.template data<Vec<2>>(L.ids.acceleration);
  ASSERT_EQ(P.count, std::size_t(kN * kN) + 3u * 144u);
  double deep_unity = 0, deep_grad = 0, edge_unity[2] = {0, 0}, edge_grad[2] = {0, 0}, engine_vs_brute = 0;
  std::size_t deep[2] = {0, 0}, edge[2] = {0, 0};
  for (std::uint32_t i = 0; i < P.count; ++i) {
    if (!interior(P.position[i], h0)) continue;
    const Sums S = sums<K>(P, L.p, i);
    const double hi = P.smoothing_length[i];
    const int daughter = hi < 0.75 * h0 ? 1 : 0;
    const double unity = std::abs(S.unity - 1.0), grad = std::hypot(S.grad[0], S.grad[1]) * hi;
    const double m = std::max(std::abs(double(P.position[i][0]) - 0.2), std::abs(double(P.position[i][1]) - 0.2));
    if (std::abs(m - 0.06) > 2 * h0 + 0.5 * kDx) {
      ++deep[daughter];
      deep_unity = std::max(deep_unity, unity);
      deep_grad = std::max(deep_grad, grad);
    } else {
      ++edge[daughter];
      edge_unity[daughter] = std::max(edge_unity[daughter], unity);
      edge_grad[daughter] = std::max(edge_grad[daughter], grad);
    }
    const double scale = 2.0 * Lattice<K>::kBackground / kRho0;
    const double e0 = -double(acc[i][0]) / scale, e1 = -double(acc[i][1]) / scale;
    engine_vs_brute = std::max(engine_vs_brute, std::hypot(e0 - S.grad[0], e1 - S.grad[1]) / S.abs_grad);
  }
  std::printf("refined block (wendland, h/dx = 2): deep (%zu mothers, %zu daughters) |sum V W - 1| %.2e, |sum V grad W| h"
              " %.2e; edge daughters (%zu) %.2f%% and %.3f; edge mothers (%zu) %.2f%% and %.3f; engine vs brute force"
              " %.1e\n",
              deep[0], deep[1], deep_unity, deep_grad, edge[1], 100 * edge_unity[1], edge_grad[1], edge[0],
              100 * edge_unity[0], edge_grad[0], engine_vs_brute);
  ASSERT_GT(deep[0], 100u);
  ASSERT_GT(deep[1], 10u);
  EXPECT_LT(deep_unity, unity_tolerance(2.0)) << "test_kernels.cpp, h/dx = 2.0";
  EXPECT_LT(deep_grad, 1e-5) << "test_kernels.cpp round-off bound";
  EXPECT_LT(engine_vs_brute, 1e-5) << "the momentum pass sums every pair with the pair h";
  for (int d = 0; d < 2; ++d) {
    EXPECT_LT(edge_unity[d], 0.16) << (d ? "daughters" : "mothers") << ": known blip of the mean-h kernel";
    EXPECT_LT(edge_grad[d], 0.25) << (d ? "daughters" : "mothers") << ": known blip of the mean-h kernel";
  }
}

}  // namespace
