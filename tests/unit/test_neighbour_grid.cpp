// Neighbour grid of the CPU backend (sph/neighbour_grid.hpp, sph/backend/cpu/cpu_backend.cpp):
// the cell-sorted layout must find exactly the pairs an O(N^2) brute force finds (r < 2h, same
// float arithmetic, so counts are compared exactly), drop particles outside the domain or with a
// non-finite position and count them, and sort stably (particles of one cell keep their order).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <vector>

#include "sph/backend.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/passes.hpp"
#include "sph/vec.hpp"

namespace {

using namespace turbid::sph;

// Deterministic on every standard library: raw mt19937 words, not std::*_distribution.
struct Rng {
  std::mt19937 g;
  explicit Rng(std::uint32_t seed) : g(seed) {}
  double u01() { return double(g() >> 8) * (1.0 / 16777216.0); }  // [0, 1)
};

PhysicsParams params(int d, double h) {
  PhysicsParams p;
  p.dimensions = d;
  p.smoothing_length = Real(h);
  p.diffusion = Diffusion::none;
  p.material_count = 1;
  p.materials[0].eos = TaitEos::make(1000.0, 30.0, 7.0, 0.0);
  p.materials[0].sound_speed = Real(30.0);
  p.materials[0].dynamic_viscosity = Real(1e-3);
  return p;
}

// A fluid world bound to the CPU backend; the store must not move after bind.
template <int D>
struct World {
  PhysicsParams p;
  ParticleStore s;
  FieldIds ids;
  Domain dom;
  std::unique_ptr<Backend> be;

  World(double h, const double* lo, const double* hi, const std::vector<Vec<D>>& x, int threads = 1)
      : p(params(D, h)) {
    ids = register_fields(s, p);
    for (int k = 0; k < D; ++k) {
      dom.min[k] = lo[k];
      dom.max[k] = hi[k];
    }
    s.resize(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      s.data<Vec<D>>(ids.position)[i] = x[i];
      s.data<Real>(ids.density)[i] = Real(1000);
      s.data<Real>(ids.mass)[i] = Real(1);
      s.data<Real>(ids.smoothing_length)[i] = p.smoothing_length;
      s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(Kind::fluid);
      s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
    }
    be = make_cpu_backend(threads);
    be->bind(s, ids, p, dom);
  }
  const Vec<D>* x() const { return s.data<Vec<D>>(ids.position); }
  const std::uint32_t* id() const { return s.data<std::uint32_t>(ids.id); }

  // Ordered pairs (i, j), i != j, with |x_i - x_j|^2 < (2h)^2 in float, as the backend tests them.
  std::size_t brute_force_pairs() const {
    const Real h = p.smoothing_length;
    const Real lim = Real(4) * h * h;
    std::size_t n = 0;
    for (std::size_t i = 0; i < s.size(); ++i)
      for (std::size_t j = i + 1; j < s.size(); ++j)
        if (norm2(x()[i] - x()[j]) < lim) n += 2;
    return n;
  }

  // The documented layout: cells of size 2h from the domain's lower corner, x fastest.
  std::uint64_t cell_key(const Vec<D>& xi) const {
    const double cell = 2.0 * double(p.smoothing_length);
    const Real inv = Real(1.0 / cell);
    std::uint64_t key = 0, stride = 1;
    for (int k = 0; k < D; ++k) {
      const int n = std::max(1, int(std::ceil((dom.max[k] - dom.min[k]) / cell)));
      const int c = int((xi[k] - Real(dom.min[k])) * inv);
      key += std::uint64_t(c) * stride;
      stride *= std::uint64_t(n);
    }
    return key;
  }
};

template <int D>
std::vector<Vec<D>> random_points(std::size_t n, const double* lo, const double* hi, std::uint32_t seed) {
  Rng rng(seed);
  std::vector<Vec<D>> x(n);
  for (auto& xi : x)
    for (int k = 0; k < D; ++k) xi[k] = Real(lo[k] + (hi[k] - lo[k]) * rng.u01());
  return x;
}

template <int D>
void check_pairs(double h, const double* lo, const double* hi, std::size_t n, std::uint32_t seed) {
  // Two threads: the parallel key computation, permutation and pair loop are exercised too.
  World<D> w(h, lo, hi, random_points<D>(n, lo, hi, seed), 2);
  const std::size_t removed = w.be->update_neighbours();
  EXPECT_EQ(removed, 0u) << "all points lie inside the domain";
  ASSERT_EQ(w.s.size(), n);
  // The sort is a permutation: every id once.
  std::vector<std::uint32_t> ids(w.id(), w.id() + n);
  std::sort(ids.begin(), ids.end());
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(ids[i], i) << "ids after sort are a permutation";
  const std::size_t brute = w.brute_force_pairs();
  EXPECT_GT(brute, 5 * n) << "test setup: enough pairs to be meaningful";
  // Reference: O(N^2) brute force with the same float distance test -> exact equality.
  EXPECT_EQ(w.be->pair_count(), brute) << "cell grid pairs vs brute force, D=" << D;
}

TEST(NeighbourGrid, PairCountMatchesBruteForce2D) {
  // Non-square domain with a negative origin: catches axis strides and origin mix-ups.
  const double lo[2] = {-0.3, -1.0}, hi[2] = {0.7, 0.5};
  check_pairs<2>(0.02, lo, hi, 4000, 12345u);
}

TEST(NeighbourGrid, PairCountMatchesBruteForce3D) {
  const double lo[3] = {0.0, -0.5, 0.2}, hi[3] = {1.0, 0.3, 0.8};
  check_pairs<3>(0.04, lo, hi, 4000, 54321u);
}

TEST(NeighbourGrid, PairCountMatchesBruteForceFewCells) {
  // One or two cells per axis: the neighbour ranges are clipped at both grid ends.
  const double lo2[2] = {0.0, 0.0}, hi2[2] = {0.15, 0.05};
  check_pairs<2>(0.04, lo2, hi2, 500, 7u);
  const double lo3[3] = {0.0, 0.0, 0.0}, hi3[3] = {0.1, 0.05, 0.2};
  check_pairs<3>(0.03, lo3, hi3, 800, 8u);
}

template <int D>
void check_removal() {
  double lo[3] = {0.0, -0.2, 0.1}, hi[3] = {0.5, 0.4, 0.3};
  std::vector<Vec<D>> x = random_points<D>(600, lo, hi, 99u);
  const std::size_t inside = x.size();
  const Real nan = std::numeric_limits<Real>::quiet_NaN(), inf = std::numeric_limits<Real>::infinity();
  // One point beyond each face, then non-finite coordinates on each axis.
  std::size_t outside = 0;
  for (int k = 0; k < D; ++k) {
    Vec<D> a = x[std::size_t(k)], b = x[std::size_t(k) + 10], c = x[std::size_t(k) + 20], e = x[std::size_t(k) + 30];
    a[k] = Real(lo[k] - 1e-3);
    b[k] = Real(hi[k] + 0.25);
    c[k] = nan;
    e[k] = k % 2 ? -inf : inf;
    // interleave with inside points so that removal must pick them out of the middle
    x.insert(x.begin() + std::ptrdiff_t(50 * (k + 1)), {a, b, c, e});
    outside += 4;
  }
  // id = position in the input; remember which ids are the outside points
  std::set<std::uint32_t> expected_kept;
  for (std::size_t i = 0; i < x.size(); ++i) {
    bool in = true;
    for (int k = 0; k < D; ++k) in = in && x[i][k] >= Real(lo[k]) && x[i][k] < Real(hi[k]);
    if (in) expected_kept.insert(std::uint32_t(i));
  }
  ASSERT_EQ(expected_kept.size(), inside) << "test setup";
  World<D> w(0.02, lo, hi, x);
  EXPECT_EQ(w.be->update_neighbours(), outside) << "removed count, D=" << D;
  ASSERT_EQ(w.s.size(), inside);
  const std::set<std::uint32_t> kept(w.id(), w.id() + w.s.size());
  EXPECT_EQ(kept, expected_kept) << "exactly the points inside the domain remain";
  for (std::size_t i = 0; i < w.s.size(); ++i)
    for (int k = 0; k < D; ++k) ASSERT_TRUE(std::isfinite(w.x()[i][k]));
  // The grid built after removal still finds every pair.
  EXPECT_EQ(w.be->pair_count(), w.brute_force_pairs());
  // Nothing left to remove.
  EXPECT_EQ(w.be->update_neighbours(), 0u);
}

TEST(NeighbourGrid, RemovesOutsideAndNonFinite2D) { check_removal<2>(); }
TEST(NeighbourGrid, RemovesOutsideAndNonFinite3D) { check_removal<3>(); }

// The domain's extent is not a whole number of cells (0.5 / 0.04 = 12.5, 0.3 / 0.04 = 7.5,
// 0.1 / 0.04 = 2.5), so the grid's last cell reaches past the max face. A point a quarter cell
// beyond the max face is outside the domain and must be removed all the same (backend.hpp:
// "Particles outside this box are removed at the next neighbour update"), as one just below the
// min face is.
template <int D>
void check_removal_near_max_face() {
  const double lo[3] = {0.0, 0.0, 0.0}, hi[3] = {0.5, 0.3, 0.1};
  std::vector<Vec<D>> x = random_points<D>(300, lo, hi, 5u);
  const std::size_t inside = x.size();
  for (int k = 0; k < D; ++k) {
    Vec<D> beyond = x[std::size_t(k)];
    beyond[k] = Real(hi[k] + 0.01);  // 0.25 cell past the face, inside the grid's last cell
    x.push_back(beyond);
    Vec<D> below = x[std::size_t(k) + 5];
    below[k] = Real(lo[k] - 0.01);
    x.push_back(below);
  }
  World<D> w(0.02, lo, hi, x);
  EXPECT_EQ(w.be->update_neighbours(), std::size_t(2 * D))
      << "removed count: one point beyond each max face and one below each min face, D=" << D;
  EXPECT_EQ(w.s.size(), inside);
  for (std::size_t i = 0; i < w.s.size(); ++i)
    for (int k = 0; k < D; ++k)
      EXPECT_TRUE(w.x()[i][k] >= Real(lo[k]) && w.x()[i][k] <= Real(hi[k]))
          << "particle id " << w.id()[i] << " kept at coordinate " << k << " = " << w.x()[i][k]
          << ", outside the domain [" << lo[k] << ", " << hi[k] << "]";
}

TEST(NeighbourGrid, RemovesJustBeyondMaxFace2D) { check_removal_near_max_face<2>(); }
TEST(NeighbourGrid, RemovesJustBeyondMaxFace3D) { check_removal_near_max_face<3>(); }

template <int D>
void check_stable() {
  // Big cells (h = 0.1 -> 5 cells per axis): dozens of particles share each cell.
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  World<D> w(0.1, lo, hi, random_points<D>(D == 2 ? 2000 : 3000, lo, hi, 2024u));
  ASSERT_EQ(w.be->update_neighbours(), 0u);
  const std::size_t n = w.s.size();
  std::size_t shared = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const std::uint64_t a = w.cell_key(w.x()[i]), b = w.cell_key(w.x()[i + 1]);
    ASSERT_LE(a, b) << "particles sorted by cell index (x fastest), position " << i;
    if (a == b) {
      ++shared;
      ASSERT_LT(w.id()[i], w.id()[i + 1]) << "stable sort: input order kept inside cell " << a;
    }
  }
  EXPECT_GT(shared, n / 2) << "test setup: most particles share a cell with the next";
  // Sorting a sorted store changes nothing (deterministic restart).
  const std::vector<std::uint32_t> before(w.id(), w.id() + n);
  ASSERT_EQ(w.be->update_neighbours(), 0u);
  EXPECT_EQ(std::vector<std::uint32_t>(w.id(), w.id() + n), before);
}

TEST(NeighbourGrid, StableSortByCell2D) { check_stable<2>(); }
TEST(NeighbourGrid, StableSortByCell3D) { check_stable<3>(); }

// Periodic axes: the grid's wrapped ranges find exactly the pairs of a brute force over nearest
// images (x_i - x_j shifted by one period where it exceeds half a period), in float as the grid
// tests them. The domains are not whole numbers of supports, so the cells are stretched to tile
// the period (neighbour_grid.hpp).
template <int D>
void check_periodic_pairs(double h, const double* lo, const double* hi, const bool* periodic, std::size_t n,
                          std::uint32_t seed) {
  World<D> w(h, lo, hi, random_points<D>(n, lo, hi, seed), 2);
  for (int k = 0; k < D; ++k) w.dom.periodic[k] = periodic[k];
  w.be->bind(w.s, w.ids, w.p, w.dom);
  ASSERT_EQ(w.be->update_neighbours(), 0u);
  Real period[D];
  for (int k = 0; k < D; ++k) period[k] = periodic[k] ? Real(hi[k] - lo[k]) : Real(0);
  const Real lim = Real(4) * w.p.smoothing_length * w.p.smoothing_length;
  std::size_t brute = 0, across = 0;
  for (std::size_t i = 0; i < w.s.size(); ++i)
    for (std::size_t j = i + 1; j < w.s.size(); ++j) {
      Vec<D> r = w.x()[i] - w.x()[j];
      bool wrapped = false;
      for (int k = 0; k < D; ++k) {
        if (period[k] == Real(0)) continue;
        if (r[k] > Real(0.5) * period[k]) r[k] -= period[k], wrapped = true;
        else if (r[k] < Real(-0.5) * period[k]) r[k] += period[k], wrapped = true;
      }
      if (norm2(r) < lim) {
        brute += 2;
        if (wrapped) across += 2;
      }
    }
  EXPECT_GT(across, n / 10) << "test setup: many pairs reach across a periodic face";
  EXPECT_EQ(w.be->pair_count(), brute) << "periodic cell grid pairs vs nearest-image brute force, D=" << D;
}

TEST(NeighbourGrid, PeriodicPairsMatchNearestImageBruteForce) {
  const double lo2[2] = {-0.1, 0.0}, hi2[2] = {0.23, 0.31};
  const bool px[2] = {true, false}, pxy[2] = {true, true};
  check_periodic_pairs<2>(0.02, lo2, hi2, px, 3000, 7u);
  check_periodic_pairs<2>(0.02, lo2, hi2, pxy, 3000, 8u);
  const double lo3[3] = {0.0, 0.0, -0.2}, hi3[3] = {0.29, 0.4, 0.13};
  const bool pxz[3] = {true, false, true};
  check_periodic_pairs<3>(0.04, lo3, hi3, pxz, 3000, 9u);
}

// A periodic axis shorter than three supports cannot be tiled without a cell seeing itself twice.
TEST(NeighbourGrid, PeriodicAxisShorterThanThreeSupportsIsRefused) {
  Domain d;
  d.max[0] = 0.1;
  d.max[1] = 1.0;
  d.periodic[0] = true;
  EXPECT_THROW(GridLayout::make(d, 2, 0.04), std::runtime_error) << "0.1 m < 3 x 0.04 m";
  d.max[0] = 0.12;
  EXPECT_EQ(GridLayout::make(d, 2, 0.04).cells[0], 3);
}

// The drift's wrap must land every coordinate in [min, max) of the domain as the sort tests it,
// for any float domain (x - period can round below min, min + period above max): 2000 random
// domains, coordinates just across either face. Reference: the sort keeps exactly [min, max].
TEST(NeighbourGrid, PeriodicWrapLandsInsideTheSortedDomain) {
  Rng rng(99u);
  PhysicsParams p;
  p.dimensions = 2;
  p.periodic = true;
  for (int trial = 0; trial < 2000; ++trial) {
    const Real lo = Real(-1 + 2 * rng.u01()), hi = lo + Real(0.1 + rng.u01());
    p.period[0] = hi - lo;
    p.periodic_origin[0] = lo;
    p.periodic_end[0] = hi;
    DriftPass<2> drift(ParticleView<2>{}, Real(0), Real(0), p);
    for (Real d : {Real(0), Real(1e-7), Real(1e-5), Real(1e-3)}) {
      for (Real x : {lo - d, hi + d, std::nextafter(lo, Real(-10)), hi, std::nextafter(hi, Real(10))}) {
        const Real w = drift.wrap(Vec<2>{x, Real(0)})[0];
        ASSERT_TRUE(w >= lo && w < hi) << "x = " << x << " wrapped to " << w << " outside [" << lo << ", " << hi << ")";
      }
    }
  }
}

}  // namespace
