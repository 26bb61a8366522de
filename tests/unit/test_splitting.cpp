// Particle splitting (sph/splitting.hpp, the CPU backend's split): the debris -> turbidity
// transition's insertion step on lattices built here, without a time loop.
//  - geometry: daughters at the sub-cube centres x +- a/4, a = (m/rho)^(1/D) (seed paper eq. 4 as
//    docs/choices.md reads it), mass m/2^D, h/2, the target material;
//  - conservation across the split (conservation laws; double accumulation): mass, linear momentum
//    and kinetic energy to 1e-12 relative (each daughter's m/2^D is exact in binary and velocities
//    are copied: only the order of the double sums differs), the centre of mass to the rounding of
//    the stored float positions (half an ulp of the largest coordinate);
//  - the criterion: exactly the particles whose shear stress passes the threshold split, and with
//    `where: interface` only those with a fluid neighbour of another material (brute force);
//  - a full store refuses the surplus mothers, lowest index first served, and overwrites nothing;
//  - the outcome is bitwise the same for 1 and 2 threads;
//  - summation density sum_j m_j W(r_ij, (h_i + h_j)/2) on a uniform 2D lattice at rest, before and
//    after splitting a square block of it (reference: the mother's summation density): exact deep
//    inside the split block; on its edge, where daughters meet mothers, within 2% after the
//    relaxation that follows a split (the bound), which keeps mass, energy and centre.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <vector>

#include "sph/backend.hpp"
#include "sph/kernels.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/splitting.hpp"
#include "sph/vec.hpp"

namespace {

using namespace turbid::sph;

constexpr double kDx = 0.01;     // lattice spacing [m]
constexpr double kRho0 = 1950.0; // debris and turbidity reference density [kg/m^3]

PhysicsParams params(int d) {
  PhysicsParams p;
  p.dimensions = d;
  p.smoothing_length = Real(2.0 * kDx);
  p.max_smoothing_length = p.smoothing_length;
  p.uniform_h = false;  // a scene with transitions runs the variable-h path from the start
  p.diffusion = Diffusion::none;
  p.viscosity = Viscosity::laminar;
  p.rheology = true;  // registers shear_stress, which the criterion reads
  p.splitting = true; // registers split_fresh, which the relaxation after a split reads
  p.material_count = 3;
  for (int m = 0; m < 3; ++m) {
    p.materials[m].eos = TaitEos::make(m == 0 ? 1000.0 : kRho0, 30.0, 7.0, 0.0);
    p.materials[m].sound_speed = Real(30.0);
    p.materials[m].dynamic_viscosity = Real(1e-3);
  }
  return p;
}

// A block of n^D particles on a lattice of spacing kDx, material `mat`, random velocities and
// slightly perturbed densities, shear stress from `stress(i)`; bound to the CPU backend with the
// given capacity (the store must not move after bind).
template <int D>
struct World {
  PhysicsParams p;
  ParticleStore s;
  FieldIds ids;
  Domain dom;
  std::unique_ptr<Backend> be;

  template <class Material, class Stress>
  World(int n, std::size_t capacity, Material material, Stress stress, int threads = 1) : p(params(D)) {
    ids = register_fields(s, p);
    std::size_t count = 1;
    for (int k = 0; k < D; ++k) {
      dom.min[k] = -0.1;
      dom.max[k] = n * kDx + 0.1;
      count *= std::size_t(n);
    }
    s.reserve(capacity);
    s.resize(count);
    std::mt19937 g(42);
    const auto u = [&] { return double(g() >> 8) * (1.0 / 16777216.0) - 0.5; };  // [-0.5, 0.5)
    for (std::size_t i = 0; i < count; ++i) {
      Vec<D> x;
      std::size_t r = i;
      for (int k = 0; k < D; ++k) {
        x[k] = Real((double(r % std::size_t(n)) + 0.5) * kDx);
        r /= std::size_t(n);
      }
      Vec<D> v;
      for (int k = 0; k < D; ++k) v[k] = Real(u());
      const double rho = kRho0 * (1.0 + 0.01 * u());
      s.data<Vec<D>>(ids.position)[i] = x;
      s.data<Vec<D>>(ids.velocity)[i] = v;
      s.data<Real>(ids.density)[i] = Real(rho);
      s.data<Real>(ids.mass)[i] = Real(rho * std::pow(kDx, D));
      s.data<Real>(ids.smoothing_length)[i] = p.smoothing_length;
      s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(Kind::fluid);
      s.data<std::uint8_t>(ids.material)[i] = std::uint8_t(material(x));
      s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
      s.data<Real>(ids.shear_stress)[i] = Real(stress(i));
    }
    be = make_cpu_backend(threads);
    be->bind(s, ids, p, dom);
    be->update_neighbours();
  }

  std::size_t n() const { return s.size(); }
  const Vec<D>& x(std::size_t i) const { return s.data<Vec<D>>(ids.position)[i]; }
  const Vec<D>& v(std::size_t i) const { return s.data<Vec<D>>(ids.velocity)[i]; }
  double m(std::size_t i) const { return s.data<Real>(ids.mass)[i]; }
  double h(std::size_t i) const { return s.data<Real>(ids.smoothing_length)[i]; }
  int material(std::size_t i) const { return s.data<std::uint8_t>(ids.material)[i]; }
  std::uint32_t id(std::size_t i) const { return s.data<std::uint32_t>(ids.id)[i]; }
  double stress(std::size_t i) const { return s.data<Real>(ids.shear_stress)[i]; }
};

struct Totals {
  double mass = 0, energy = 0;
  double momentum[3] = {0, 0, 0}, moment[3] = {0, 0, 0};  // sum m v, sum m x
  double momentum_scale = 0;                                // sum m |v| (momentum sums near zero)
};

template <int D>
Totals totals(const World<D>& w) {
  Totals t;
  for (std::size_t i = 0; i < w.n(); ++i) {
    const double m = w.m(i);
    t.mass += m;
    for (int k = 0; k < D; ++k) {
      t.momentum[k] += m * double(w.v(i)[k]);
      t.momentum_scale += m * std::abs(double(w.v(i)[k]));
      t.moment[k] += m * double(w.x(i)[k]);
      t.energy += 0.5 * m * double(w.v(i)[k]) * double(w.v(i)[k]);
    }
  }
  return t;
}

SplitParams one_rule(double threshold, bool interface_only) {
  SplitParams sp;
  sp.rule_count = 1;
  sp.rules[0].from = 1;
  sp.rules[0].to = 2;
  sp.rules[0].threshold = Real(threshold);
  sp.rules[0].interface_only = interface_only;
  sp.rules[0].min_smoothing_length = Real(1.5 * kDx);  // one level: daughters (h = kDx) do not split again
  return sp;
}

template <int D>
void check_split_conserves(int n) {
  // Stress 0..199 Pa in a fixed pattern; threshold 150 Pa: a quarter of the particles split.
  World<D> w(n, std::size_t(std::pow(n, D)) * 8, [](const Vec<D>&) { return 1; },
             [](std::size_t i) { return double((i * 37) % 200); });
  std::vector<std::uint32_t> mothers;
  std::vector<Vec<D>> mother_x;
  std::vector<double> mother_m, mother_h;
  for (std::size_t i = 0; i < w.n(); ++i)
    if (w.stress(i) > 150.0) {
      mothers.push_back(w.id(i));
      mother_x.push_back(w.x(i));
      mother_m.push_back(w.m(i));
      mother_h.push_back(w.h(i));
    }
  const std::size_t before = w.n();
  const Totals t0 = totals(w);
  double largest = 0;
  for (std::size_t i = 0; i < w.n(); ++i)
    for (int k = 0; k < D; ++k) largest = std::max(largest, std::abs(double(w.x(i)[k])));

  const SplitCounts c = w.be->split(one_rule(150.0, false));
  constexpr int kD = daughters_per_split<D>();
  ASSERT_EQ(c.splits, mothers.size());
  EXPECT_EQ(c.refused, 0u);
  EXPECT_EQ(c.daughters, mothers.size() * std::size_t(kD - 1));
  ASSERT_EQ(w.n(), before + c.daughters);

  const Totals t1 = totals(w);
  EXPECT_NEAR(t1.mass, t0.mass, 1e-12 * t0.mass) << "mass";
  EXPECT_NEAR(t1.energy, t0.energy, 1e-12 * t0.energy) << "kinetic energy";
  const double half_ulp = largest * std::numeric_limits<float>::epsilon() * 0.5;
  for (int k = 0; k < D; ++k) {
    EXPECT_NEAR(t1.momentum[k], t0.momentum[k], 1e-12 * t0.momentum_scale) << "momentum, axis " << k;
    EXPECT_NEAR(t1.moment[k] / t1.mass, t0.moment[k] / t0.mass, half_ulp) << "centre of mass, axis " << k;
  }

  // Each mother: 2^D particles of material 2 with h/2 and m/2^D at x +- a/4, one of them with her id.
  std::vector<std::vector<std::size_t>> near(mothers.size());
  std::set<std::uint32_t> ids;
  for (std::size_t i = 0; i < w.n(); ++i) {
    ids.insert(w.id(i));
    if (w.material(i) != 2) continue;
    double best = 1e9;
    std::size_t which = 0;
    for (std::size_t q = 0; q < mothers.size(); ++q) {
      double d2 = 0;
      for (int k = 0; k < D; ++k) d2 += std::pow(double(w.x(i)[k]) - double(mother_x[q][k]), 2);
      if (d2 < best) best = d2, which = q;
    }
    near[which].push_back(i);
  }
  EXPECT_EQ(ids.size(), w.n()) << "ids stay unique";
  for (std::size_t q = 0; q < mothers.size(); ++q) {
    ASSERT_EQ(near[q].size(), std::size_t(kD)) << "daughters of mother id " << mothers[q];
    bool has_id = false;
    for (std::size_t i : near[q]) {
      has_id = has_id || w.id(i) == mothers[q];
      EXPECT_EQ(w.m(i), mother_m[q] / kD);
      EXPECT_EQ(w.h(i), 0.5 * mother_h[q]);
      for (int k = 0; k < D; ++k) {
        // a = (m / rho)^(1/D) with rho within 0.5% of kRho0, so |offset| = a/4 is kDx/4 to 0.2%.
        EXPECT_NEAR(std::abs(double(w.x(i)[k]) - double(mother_x[q][k])), 0.25 * kDx, 0.002 * 0.25 * kDx);
      }
    }
    EXPECT_TRUE(has_id) << "daughter 0 keeps the mother's id and slot";
  }
}

TEST(Splitting, ConservesMassMomentumEnergyAndCentre2D) { check_split_conserves<2>(20); }
TEST(Splitting, ConservesMassMomentumEnergyAndCentre3D) { check_split_conserves<3>(8); }

TEST(Splitting, DaughterOffsetsAreSubCubeCentres) {
  // 3D: the 8 sign patterns of (+-a/4)^3, each once, summing to zero (the mother's position).
  std::set<std::vector<int>> seen;
  double sum[3] = {0, 0, 0};
  for (int k = 0; k < 8; ++k) {
    const Vec<3> o = daughter_offset<3>(k, Real(2));
    std::vector<int> sign;
    for (int d = 0; d < 3; ++d) {
      EXPECT_EQ(std::abs(o[d]), Real(0.5)) << "a/4 with a = 2";
      sign.push_back(o[d] > 0 ? 1 : -1);
      sum[d] += o[d];
    }
    seen.insert(sign);
  }
  EXPECT_EQ(seen.size(), 8u);
  for (double s : sum) EXPECT_EQ(s, 0.0);
  EXPECT_FLOAT_EQ(split_edge<3>(Real(8), Real(1)), 2.0f) << "a = (m / rho)^(1/3)";
  EXPECT_FLOAT_EQ(split_edge<2>(Real(9), Real(1)), 3.0f) << "a = (m / rho)^(1/2)";
}

// `where: interface`: debris (material 1) on the left half, water (0) on the right, every debris
// particle above the threshold; exactly those closer than the support 2h to a water particle split
// (brute force over all pairs).
TEST(Splitting, InterfaceOnlySplitsParticlesNextToAnotherMaterial) {
  constexpr int n = 24;
  const auto left = [](const Vec<2>& x) { return x[0] < Real(n * kDx / 2) ? 1 : 0; };
  World<2> w(n, std::size_t(n * n) * 4, left, [](std::size_t) { return 500.0; });
  const double support2 = std::pow(2.0 * 2.0 * kDx, 2);
  std::size_t expected = 0;
  for (std::size_t i = 0; i < w.n(); ++i) {
    if (w.material(i) != 1) continue;
    bool other = false;
    for (std::size_t j = 0; j < w.n(); ++j) {
      const double d2 = std::pow(double(w.x(i)[0] - w.x(j)[0]), 2) + std::pow(double(w.x(i)[1] - w.x(j)[1]), 2);
      other = other || (w.material(j) == 0 && float(d2) < float(support2));
    }
    expected += other ? 1 : 0;
  }
  ASSERT_EQ(expected, std::size_t(3 * n)) << "three columns of debris lie closer than 2h = 4 dx to the water";
  const SplitCounts c = w.be->split(one_rule(150.0, true));
  EXPECT_EQ(c.splits, expected);
  std::size_t turbidity = 0;
  for (std::size_t i = 0; i < w.n(); ++i) turbidity += w.material(i) == 2 ? 1 : 0;
  EXPECT_EQ(turbidity, 4 * expected);
}

// Room for 10 splits (30 new slots in 2D): the 10 lowest-index candidates split, the others are
// refused and counted, and no particle beyond the capacity is written.
TEST(Splitting, FullStoreRefusesTheSurplusLowestIndexFirst) {
  constexpr int n = 10;
  World<2> w(n, std::size_t(n * n) + 31, [](const Vec<2>&) { return 1; },
             [](std::size_t i) { return i % 2 == 0 ? 200.0 : 0.0; });
  const SplitCounts c = w.be->split(one_rule(150.0, false));
  EXPECT_EQ(c.splits, 10u);
  EXPECT_EQ(c.refused, std::size_t(n * n / 2 - 10));
  EXPECT_EQ(w.n(), std::size_t(n * n) + 30);
  EXPECT_LE(w.n(), w.s.capacity());
  for (std::size_t i = 0; i < std::size_t(n * n); ++i) {
    const bool split = i % 2 == 0 && i < 20;
    EXPECT_EQ(w.material(i), split ? 2 : 1) << "particle " << i;
  }
}

// The same split with 1 and 2 threads (4900 particles: above the parallel threshold) writes the
// same bytes in every field.
TEST(Splitting, ThreadCountDoesNotChangeBits) {
  constexpr int n = 70;
  const auto stress = [](std::size_t i) { return double((i * 53) % 300); };
  const auto mat = [](const Vec<2>& x) { return x[1] < Real(0.3) ? 1 : 0; };
  World<2> a(n, std::size_t(n * n) * 4, mat, stress, 1);
  World<2> b(n, std::size_t(n * n) * 4, mat, stress, 2);
  const SplitCounts ca = a.be->split(one_rule(150.0, true));
  const SplitCounts cb = b.be->split(one_rule(150.0, true));
  ASSERT_GT(ca.splits, 100u);
  EXPECT_EQ(ca.splits, cb.splits);
  ASSERT_EQ(a.n(), b.n());
  for (int f = 0; f < a.s.field_count(); ++f)
    EXPECT_EQ(std::memcmp(a.s.raw(f), b.s.raw(f), a.n() * a.s.field_bytes(f)), 0) << a.s.desc(f).name;
}

// Summation density at particle i over all particles, pair h the mean (as the passes use).
template <int D>
double summation_density(const World<D>& w, std::size_t i) {
  double rho = 0;
  for (std::size_t j = 0; j < w.n(); ++j) {
    double r2 = 0;
    for (int k = 0; k < D; ++k) r2 += std::pow(double(w.x(i)[k] - w.x(j)[k]), 2);
    rho += w.m(j) * double(WendlandC2<D>::w(Real(std::sqrt(r2)), Real(0.5 * (w.h(i) + w.h(j)))));
  }
  return rho;
}

// A cubic block of side 2 `half` centred at `centre` on every axis, split on a lattice at rest.
struct Block {
  double centre, half;
  // Distance inside the block's faces (negative outside), by the largest coordinate offset.
  template <int D>
  double depth(const Vec<D>& x) const {
    double d = 0;
    for (int k = 0; k < D; ++k) d = std::max(d, std::abs(double(x[k]) - centre));
    return half - d;
  }
};

// Largest |rho_sum / rho_mother - 1| over the daughters (material 2) more than 2h0 from the split
// block's edge (`deep`), over all daughters, and over the mothers within 2h0 of the block.
struct Blip {
  double deep = 0, daughters = 0, mothers = 0;
};

template <int D>
Blip summation_blip(const World<D>& w, const Block& b, double rho_mother) {
  Blip out;
  const double support = 2.0 * 2.0 * kDx;  // 2 h0
  for (std::size_t i = 0; i < w.n(); ++i) {
    const double depth = b.depth<D>(w.x(i));
    if (depth < -support) continue;
    const double dev = std::abs(summation_density(w, i) / rho_mother - 1.0);
    if (w.material(i) != 2) {
      out.mothers = std::max(out.mothers, dev);
      continue;
    }
    if (depth > support) out.deep = std::max(out.deep, dev);  // beyond the mothers' support
    out.daughters = std::max(out.daughters, dev);
  }
  return out;
}

// Summation density sum_j m_j W(r_ij, (h_i + h_j)/2) on a lattice of n^D particles at rest
// (h = 2 dx) whose middle block of `cells`^D splits; reference: the mother's summation density at
// the block's centre before the split. Then the relaxation after the split.
template <int D>
void check_split_density(int n, int cells) {
  const Block block{n * kDx / 2, cells * kDx / 2};
  std::size_t count = 1, mothers = 1;
  for (int k = 0; k < D; ++k) {
    count *= std::size_t(n);
    mothers *= std::size_t(cells);
  }
  World<D> w(n, count * 4, [](const Vec<D>&) { return 1; }, [](std::size_t) { return 500.0; });
  std::size_t centre = 0;
  for (std::size_t i = 0; i < w.n(); ++i) {
    w.s.template data<Real>(w.ids.density)[i] = Real(kRho0);
    w.s.template data<Real>(w.ids.mass)[i] = Real(kRho0 * std::pow(kDx, D));
    w.s.template data<Real>(w.ids.shear_stress)[i] = Real(block.depth<D>(w.x(i)) > 0 ? 500.0 : 0.0);
    if (block.depth<D>(w.x(i)) > block.depth<D>(w.x(centre))) centre = i;
  }
  const double rho_mother = summation_density(w, centre);
  const SplitParams rules = one_rule(150.0, false);
  const SplitCounts c = w.be->split(rules);
  ASSERT_EQ(c.splits, mothers);
  const Blip raw = summation_blip(w, block, rho_mother);
  // Daughters among daughters form a lattice of dx/2 with h = dx, the mothers' lattice scaled by
  // one half, so their summation density is the mothers' (0.000% measured; bound 0.3%).
  EXPECT_LT(raw.deep, 0.003) << "daughters more than 2h from the block's edge";
  // On the block's edge no symmetric pair kernel serves both sides (2D, the mean h: daughters
  // +15.5%, mothers 5.0%; the mean of both kernels 11% / 7%; docs/choices.md): the relaxation after
  // the split moves the daughters and the particles within a pair support of them.
  const Totals before = totals(w);
  w.be->update_neighbours();  // as the time loop does after a split
  std::vector<Vec<D>> x0(w.n());
  for (std::size_t i = 0; i < w.n(); ++i) x0[w.id(i)] = w.x(i);
  // The zone by brute force: every daughter, and every mother closer than the pair support
  // 2 (h0 + h0/2)/2 = 1.5 h0 to a daughter.
  std::size_t expected_zone = 0;
  for (std::size_t i = 0; i < w.n(); ++i) {
    bool near = w.material(i) == 2;
    for (std::size_t j = 0; j < w.n() && !near; ++j) {
      if (w.material(j) != 2) continue;
      const double support = w.h(i) + w.h(j);
      double r2 = 0;
      for (int k = 0; k < D; ++k) r2 += std::pow(double(w.x(i)[k] - w.x(j)[k]), 2);
      near = r2 < support * support;
    }
    expected_zone += near ? 1 : 0;
  }
  const std::size_t zone = w.be->relax_split(rules);
  const Blip relaxed = summation_blip(w, block, rho_mother);
  const Totals after = totals(w);
  double moved = 0;
  for (std::size_t i = 0; i < w.n(); ++i) {
    double d2 = 0;
    for (int k = 0; k < D; ++k) d2 += std::pow(double(w.x(i)[k] - x0[w.id(i)][k]), 2);
    moved = std::max(moved, std::sqrt(d2));
  }
  std::printf("%dD summation density after the split: daughters within %.2f%% (deep %.3f%%), mothers near the block %.2f%%;\n"
              "   after %d relaxation steps (%zu particles): daughters %.2f%%, mothers %.2f%%, largest shift %.3f dx\n",
              D, 100 * raw.daughters, 100 * raw.deep, 100 * raw.mothers, rules.relax_iterations, zone,
              100 * relaxed.daughters, 100 * relaxed.mothers, moved / kDx);
  EXPECT_GT(raw.daughters, 0.10) << "the blip the relaxation is for";
  EXPECT_LT(relaxed.daughters, 0.02) << "the issue's bound: summation density at the daughters within 2%";
  EXPECT_LT(relaxed.mothers, 0.02) << "and the mothers around them";
  EXPECT_EQ(zone, expected_zone) << "the daughters and the mothers within a pair support of one";
  EXPECT_LT(moved, 0.5 * 2.0 * kDx) << "at most 0.05 h per step for 10 steps";
  // Positions only: each particle keeps its mass and velocity (the sums differ only in their order:
  // the grid update sorted the particles), 1e-12 relative; the zone's mean shift is removed, so the
  // centre of mass stays to the rounding of the stored float positions (half an ulp of the lattice's
  // extent n dx).
  EXPECT_NEAR(after.mass, before.mass, 1e-12 * before.mass);
  EXPECT_NEAR(after.energy, before.energy, 1e-12 * before.energy);
  const float extent = float(n * kDx);
  const double half_ulp = 0.5 * double(std::nextafter(extent, 2 * extent) - extent);
  for (int k = 0; k < D; ++k)
    EXPECT_NEAR(after.moment[k] / after.mass, before.moment[k] / before.mass, half_ulp) << "centre of mass, axis " << k;
}

// 2D: 40 x 40 lattice, the middle 12 x 12 block splits (measured: daughters 15.45% -> 1.08%,
// mothers 4.99% -> 1.06%, 744 particles relaxed, largest shift 0.19 dx).
TEST(Splitting, SummationDensityAfterASplitIsTheMothersWithin2Percent2D) { check_split_density<2>(40, 12); }
// 3D: 20^3 lattice, the middle 6^3 block splits (measured: daughters 20.8% -> 1.98%, mothers 4.9% ->
// 0.56%, 2,888 particles relaxed, largest shift 0.23 dx; close to the bound: docs/choices.md has the
// relaxation's sensitivity to its strength and step count).
TEST(Splitting, SummationDensityAfterASplitIsTheMothersWithin2Percent3D) { check_split_density<3>(20, 6); }

TEST(Splitting, DivideCarryNeedsFloatingPoint) {
  ParticleStore s;
  EXPECT_THROW(s.add_field({"count", "", ScalarType::u32, 1, false, true, true, Carry::divide}), std::invalid_argument);
}

}  // namespace
