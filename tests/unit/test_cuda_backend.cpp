// The CUDA backend (sph/backend/cuda/). Without a usable GPU (or in a CPU-only build) the backend
// must say why and refuse cleanly: cuda_device_count() == 0 with a reason, make_cuda_backend()
// throws std::runtime_error. With a GPU, the parity tests run the same hand-built particle blocks
// (shuffled, with particles outside the domain) through the CPU and CUDA backends and compare:
// the sorted order and removed count exactly (same keys, both sorts stable), pair counts exactly,
// density rates and accelerations within 1e-5 of the largest magnitude in the block (float32
// sums in a different association and with fused multiply-adds on the GPU), and a first step.
// Splitting (sph/splitting.hpp) on the same lattices on both backends: the same counts and the
// same bytes in every field (flag, scan, capacity rule and writes are integer work or correctly
// rounded float operations on both), the full-store refusal, and conservation on the GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "sph/backend.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"
#include "sph/split_params.hpp"
#include "sph/vec.hpp"
#include "tests/device_backends.hpp"

namespace {

using namespace turbid::sph;

TEST(CudaBackend, ReportsAvailabilityAndRefusesWithoutDevice) {
#ifdef TURBID_HAVE_CUDA
  EXPECT_TRUE(cuda_backend_compiled());
#else
  EXPECT_FALSE(cuda_backend_compiled());
#endif
  std::string reason;
  const int devices = cuda_device_count(&reason);
  EXPECT_GE(devices, 0);
  EXPECT_FALSE(reason.empty());
  EXPECT_EQ(cuda_device_count(nullptr), devices);  // a null reason is allowed
  if (devices == 0) {
    try {
      (void)make_cuda_backend();
      ADD_FAILURE() << "make_cuda_backend() returned a backend without a usable device";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_FALSE(what.empty());
#ifdef TURBID_HAVE_CUDA
      // The message carries the reason, e.g. "cudaGetDeviceCount: CUDA driver version is insufficient ...".
      EXPECT_NE(what.find(reason), std::string::npos) << what;
#endif
    }
  } else {
    auto backend = make_cuda_backend();
    ASSERT_NE(backend, nullptr);
    EXPECT_EQ(backend->name(), "cuda");
  }
}

// ---- CPU/GPU parity (GPU only) -----------------------------------------------------------------

struct Case {
  const char* name;
  int dimensions;
  KernelKind kernel;
  Diffusion diffusion;
  Viscosity viscosity;
  // Water beside a Herschel-Bulkley-Papanastasiou debris of 1950 kg/m^3 (the materials issue):
  // rheology pass, harmonic-mean viscosity, per-material EOS and the ghost-density correction.
  bool two_materials = false;
};

// Names the case in test output (instead of its bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

constexpr double kDx = 0.01;    // particle spacing [m]
constexpr double kRho0 = 1000;  // [kg/m^3]
constexpr double kSlideRho = 1950.0;  // debris (and turbidity) reference density [kg/m^3]

PhysicsParams make_params(const Case& c) {
  PhysicsParams p;
  p.dimensions = c.dimensions;
  p.kernel = c.kernel;
  p.diffusion = c.diffusion;
  p.viscosity = c.viscosity;
  p.artificial_viscosity = Real(0.05);
  p.smoothing_length = Real(1.3 * kDx);
  p.uniform_h = true;
  p.max_smoothing_length = p.smoothing_length;
  p.gravity[c.dimensions - 1] = Real(-9.81);
  p.hydrostatic_gravity[c.dimensions - 1] = Real(-9.81);
  p.material_count = 1;
  p.wall_material = 0;
  p.materials[0].eos = TaitEos::make(kRho0, 20.0, 7.0, 0.0);
  p.materials[0].sound_speed = Real(20);
  p.materials[0].dynamic_viscosity = Real(1e-3);
  p.materials[0].rheology.consistency = Real(1e-3);
  if (c.two_materials) {
    p.material_count = 2;
    p.rheology = true;
    p.interface_correction = true;
    MaterialParams& debris = p.materials[1];
    debris.eos = TaitEos::make(kSlideRho, 20.0, 7.0, 0.0);
    debris.sound_speed = Real(20);
    debris.rheology = Rheology{Real(50), Real(0.5), Real(0.8), Real(100), Real(5)};  // tau_y, K, n, m, cap
    debris.dynamic_viscosity = debris.rheology.max_viscosity;
    debris.non_newtonian = true;
  }
  return p;
}

// A fluid block over three wall layers, jittered, with varied density and velocity, stored in a
// shuffled order, plus one particle outside the domain, one with a NaN position and one just past
// the domain's upper x face (inside the whole-cell grid, still removed). With two materials the
// fluid beyond x = nx dx / 2 is debris (material 1, its rest density and mass).
template <int D>
FieldIds build_block(ParticleStore& s, const PhysicsParams& p, Domain& domain) {
  const FieldIds ids = register_fields(s, p);
  const int nx = D == 2 ? 24 : 10, ny = D == 2 ? 12 : 8, nz = D == 2 ? 1 : 6;
  struct Particle {
    Vec<D> x, v;
    Real rho;
    std::uint8_t kind;
  };
  std::vector<Particle> parts;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int vertical = D - 1;
  for (int k = 0; k < nz; ++k)
    for (int j = -3; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        Particle q{};
        const int idx[3] = {i, D == 2 ? j : k, j};
        for (int a = 0; a < D; ++a) q.x[a] = Real((idx[a] + 0.5) * kDx);
        const bool wall = j < 0;
        q.kind = std::uint8_t(wall ? Kind::wall : Kind::fluid);
        if (!wall)
          for (int a = 0; a < D; ++a) {
            q.x[a] += Real(0.1 * kDx * u(rng));
            q.v[a] = Real(0.2 * u(rng));
          }
        q.rho = Real(kRho0 * (1.0 + (wall ? 0.0 : 0.01 * u(rng))));
        parts.push_back(q);
      }
  std::shuffle(parts.begin(), parts.end(), rng);
  Particle outside{};
  for (int a = 0; a < D; ++a) outside.x[a] = Real(10.0);
  outside.rho = Real(kRho0);
  Particle nan_particle = outside;
  nan_particle.x[0] = std::numeric_limits<Real>::quiet_NaN();
  parts.insert(parts.begin() + std::ptrdiff_t(parts.size() / 3), outside);
  parts.insert(parts.begin() + std::ptrdiff_t(parts.size() / 2), nan_particle);
  Particle past_upper = parts.back();
  past_upper.x[0] = Real(nx * kDx + 0.05 + 1e-3);  // domain.max[0] below
  parts.insert(parts.begin() + std::ptrdiff_t(parts.size() / 4), past_upper);

  s.reserve(parts.size() + parts.size() / 4);
  s.resize(parts.size());
  const Real vol = Real(std::pow(kDx, D));
  for (std::size_t n = 0; n < parts.size(); ++n) {
    s.data<Vec<D>>(ids.position)[n] = parts[n].x;
    s.data<Vec<D>>(ids.velocity)[n] = parts[n].v;
    const bool debris = p.material_count > 1 && parts[n].kind == std::uint8_t(Kind::fluid) && parts[n].x[0] > Real(nx * kDx / 2);
    const Real ratio = debris ? Real(kSlideRho / kRho0) : Real(1);
    s.data<Real>(ids.density)[n] = parts[n].rho * ratio;
    s.data<Real>(ids.mass)[n] = Real(kRho0) * vol * ratio;
    s.data<Real>(ids.smoothing_length)[n] = p.smoothing_length;
    s.data<std::uint8_t>(ids.material)[n] = debris ? 1 : 0;
    s.data<std::uint8_t>(ids.kind)[n] = parts[n].kind;
    s.data<std::uint32_t>(ids.id)[n] = std::uint32_t(n);
  }
  for (int a = 0; a < D; ++a) {
    domain.min[a] = -4 * kDx;
    domain.max[a] = (a == vertical ? ny : (a == 0 ? nx : nz)) * kDx + 0.05;
  }
  return ids;
}

// Largest |difference| over the largest |value| of the reference (per component).
double relative_difference(const float* ref, const float* got, std::size_t count) {
  double diff = 0, scale = 0;
  for (std::size_t k = 0; k < count; ++k) {
    diff = std::max(diff, std::abs(double(ref[k]) - double(got[k])));
    scale = std::max(scale, std::abs(double(ref[k])));
  }
  return scale > 0 ? diff / scale : diff;
}

// The rows of `got` reordered to `ref`'s ids, so a comparison does not depend on the sort order.
std::vector<float> by_id(const ParticleStore& ref, const ParticleStore& got, const FieldIds& ids, FieldId field) {
  const std::size_t n = ref.size();
  const std::size_t comps = std::size_t(ref.desc(field).components);
  const std::uint32_t* gid = got.data<std::uint32_t>(ids.id);
  std::vector<std::size_t> row_of(*std::max_element(gid, gid + got.size()) + 1, SIZE_MAX);
  for (std::size_t r = 0; r < got.size(); ++r) row_of[gid[r]] = r;
  std::vector<float> out(n * comps, std::numeric_limits<float>::quiet_NaN());
  const std::uint32_t* rid = ref.data<std::uint32_t>(ids.id);
  const float* g = got.data<float>(field);
  for (std::size_t r = 0; r < n; ++r) {
    if (rid[r] >= row_of.size() || row_of[rid[r]] == SIZE_MAX) continue;
    for (std::size_t c = 0; c < comps; ++c) out[r * comps + c] = g[row_of[rid[r]] * comps + c];
  }
  return out;
}

template <int D>
void run_parity(const Case& c, const std::string& device) {
  const PhysicsParams params = make_params(c);
  ParticleStore cpu_store, gpu_store;
  Domain domain;
  const FieldIds ids = build_block<D>(cpu_store, params, domain);
  build_block<D>(gpu_store, params, domain);
  auto cpu = make_cpu_backend(2);
  auto gpu = turbid::testing::make_device_backend(device);
  cpu->bind(cpu_store, ids, params, domain);
  gpu->bind(gpu_store, ids, params, domain);

  const std::size_t removed_cpu = cpu->update_neighbours();
  const std::size_t removed_gpu = gpu->update_neighbours();
  EXPECT_EQ(removed_cpu, 3u);
  EXPECT_EQ(removed_gpu, removed_cpu);
  EXPECT_EQ(gpu_store.size(), cpu_store.size());  // the host count follows the device

  for (auto* b : {cpu.get(), gpu.get()}) {
    b->compute_density_rate();
    b->compute_forces();
  }
  // The block is not trivial: pressure forces well above gravity, so the sums are compared.
  ASSERT_GT(cpu->stats().max_acceleration, 10 * 9.81);
  EXPECT_EQ(gpu->pair_count(), cpu->pair_count());
  gpu->sync_to_host();
  const std::size_t n = cpu_store.size();
  ASSERT_EQ(gpu_store.size(), n);

  // Same keys and stable sorts: the same order, particle by particle.
  const std::uint32_t* id_cpu = cpu_store.data<std::uint32_t>(ids.id);
  const std::uint32_t* id_gpu = gpu_store.data<std::uint32_t>(ids.id);
  EXPECT_TRUE(std::equal(id_cpu, id_cpu + n, id_gpu)) << "sorted order differs";

  const auto rate = by_id(cpu_store, gpu_store, ids, ids.density_rate);
  const auto acc = by_id(cpu_store, gpu_store, ids, ids.acceleration);
  EXPECT_LT(relative_difference(cpu_store.data<float>(ids.density_rate), rate.data(), n), 1e-5);
  EXPECT_LT(relative_difference(cpu_store.data<float>(ids.acceleration), acc.data(), n * D), 1e-5);
  if (ids.effective_viscosity >= 0) {
    const auto mu = by_id(cpu_store, gpu_store, ids, ids.effective_viscosity);
    EXPECT_LT(relative_difference(cpu_store.data<float>(ids.effective_viscosity), mu.data(), n), 1e-5);
  }

  const StepStats s_cpu = cpu->stats(), s_gpu = gpu->stats();
  EXPECT_NEAR(s_gpu.max_speed, s_cpu.max_speed, 1e-6 * s_cpu.max_speed);  // same velocities, exact max
  EXPECT_NEAR(s_gpu.max_acceleration, s_cpu.max_acceleration, 1e-5 * s_cpu.max_acceleration);
  EXPECT_FALSE(cpu->check_health(0.5).has_value());
  EXPECT_FALSE(gpu->check_health(0.5).has_value());

  // One kick-drift-kick step on both.
  const double dt = 1e-4;
  for (auto* b : {cpu.get(), gpu.get()}) {
    b->kick(0.5 * dt);
    b->compute_density_rate();
    b->drift(dt);
    b->update_neighbours();
    b->compute_forces();
    b->kick(0.5 * dt);
  }
  gpu->sync_to_host();
  ASSERT_EQ(gpu_store.size(), cpu_store.size());
  const auto x = by_id(cpu_store, gpu_store, ids, ids.position);
  const auto v = by_id(cpu_store, gpu_store, ids, ids.velocity);
  const auto rho = by_id(cpu_store, gpu_store, ids, ids.density);
  EXPECT_LT(relative_difference(cpu_store.data<float>(ids.position), x.data(), n * D), 1e-6);
  EXPECT_LT(relative_difference(cpu_store.data<float>(ids.velocity), v.data(), n * D), 1e-5);
  EXPECT_LT(relative_difference(cpu_store.data<float>(ids.density), rho.data(), n), 1e-6);

  // A NaN planted on the host is found at the same particle by both backends.
  const std::uint32_t bad_id = cpu_store.data<std::uint32_t>(ids.id)[n / 2];
  for (ParticleStore* s : {&cpu_store, &gpu_store}) {
    const std::uint32_t* id = s->data<std::uint32_t>(ids.id);
    const std::size_t row = std::size_t(std::find(id, id + s->size(), bad_id) - id);
    ASSERT_LT(row, s->size());
    s->data<Vec<D>>(ids.velocity)[row][0] = std::numeric_limits<Real>::quiet_NaN();
  }
  gpu->sync_from_host();
  const auto h_cpu = cpu->check_health(0.5);
  const auto h_gpu = gpu->check_health(0.5);
  ASSERT_TRUE(h_cpu.has_value());
  ASSERT_TRUE(h_gpu.has_value());
  EXPECT_EQ(h_cpu->id, bad_id);
  EXPECT_EQ(h_gpu->id, h_cpu->id);
  EXPECT_EQ(h_gpu->field, h_cpu->field);
}

class CudaParity : public ::testing::TestWithParam<Case> {};

TEST_P(CudaParity, MatchesCpuBackend) {
  const Case& c = GetParam();
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    if (c.dimensions == 2) run_parity<2>(c, device);
    else run_parity<3>(c, device);
  });
}

INSTANTIATE_TEST_SUITE_P(
    CudaBackend, CudaParity,
    ::testing::Values(Case{"wendland_fourtakas_2d", 2, KernelKind::wendland_c2, Diffusion::fourtakas, Viscosity::artificial},
                      Case{"cubic_antuono_laminar_2d", 2, KernelKind::cubic_spline, Diffusion::antuono, Viscosity::laminar},
                      Case{"wendland_molteni_3d", 3, KernelKind::wendland_c2, Diffusion::molteni, Viscosity::artificial},
                      Case{"water_and_hbp_debris_2d", 2, KernelKind::wendland_c2, Diffusion::fourtakas, Viscosity::laminar, true},
                      Case{"water_and_hbp_debris_3d", 3, KernelKind::wendland_c2, Diffusion::fourtakas, Viscosity::laminar, true}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

// ---- splitting on both backends (GPU only) -----------------------------------------------------

// As in test_splitting.cpp: variable h (a scene with transitions runs that path), rheology on so
// the shear stress the criterion reads is registered, water (0), debris (1) and turbidity (2).
PhysicsParams splitting_params(int d) {
  PhysicsParams p;
  p.dimensions = d;
  p.smoothing_length = Real(2.0 * kDx);
  p.max_smoothing_length = p.smoothing_length;
  p.uniform_h = false;
  p.diffusion = Diffusion::none;
  p.viscosity = Viscosity::laminar;
  p.rheology = true;
  p.material_count = 3;
  for (int m = 0; m < 3; ++m) {
    p.materials[m].eos = TaitEos::make(m == 0 ? kRho0 : kSlideRho, 30.0, 7.0, 0.0);
    p.materials[m].sound_speed = Real(30.0);
    p.materials[m].dynamic_viscosity = Real(1e-3);
  }
  return p;
}

SplitParams debris_to_turbidity(double threshold, bool interface_only) {
  SplitParams sp;
  sp.rule_count = 1;
  sp.rules[0].from = 1;
  sp.rules[0].to = 2;
  sp.rules[0].threshold = Real(threshold);
  sp.rules[0].interface_only = interface_only;
  sp.rules[0].min_smoothing_length = Real(1.5 * kDx);  // one level: daughters do not split again
  return sp;
}

// n^D particles on a lattice of spacing kDx with random velocities, densities within 0.5% of
// kSlideRho and masses within 1% of rho dx^D; material(x) and the shear stress stress(i) [Pa] by index.
template <int D, class Material, class Stress>
FieldIds build_lattice(ParticleStore& s, const PhysicsParams& p, Domain& dom, int n, std::size_t capacity,
                       Material material, Stress stress) {
  const FieldIds ids = register_fields(s, p);
  std::size_t count = 1;
  for (int k = 0; k < D; ++k) {
    dom.min[k] = -0.1;
    dom.max[k] = n * kDx + 0.1;
    count *= std::size_t(n);
  }
  s.reserve(capacity);
  s.resize(count);
  std::mt19937 g(42);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (std::size_t i = 0; i < count; ++i) {
    Vec<D> x, v;
    std::size_t r = i;
    for (int k = 0; k < D; ++k) {
      x[k] = Real((double(r % std::size_t(n)) + 0.5) * kDx);
      r /= std::size_t(n);
      v[k] = Real(u(g));
    }
    const double rho = kSlideRho * (1.0 + 0.01 * u(g));
    s.data<Vec<D>>(ids.position)[i] = x;
    s.data<Vec<D>>(ids.velocity)[i] = v;
    s.data<Real>(ids.density)[i] = Real(rho);
    // Masses vary on their own, so the volumes m/rho (and the cube roots of the 3D edges) do too.
    s.data<Real>(ids.mass)[i] = Real(rho * std::pow(kDx, D) * (1.0 + 0.02 * u(g)));
    s.data<Real>(ids.smoothing_length)[i] = p.smoothing_length;
    s.data<std::uint8_t>(ids.kind)[i] = std::uint8_t(Kind::fluid);
    s.data<std::uint8_t>(ids.material)[i] = std::uint8_t(material(x));
    s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
    s.data<Real>(ids.shear_stress)[i] = Real(stress(i));
  }
  return ids;
}

// Mass, linear momentum and kinetic energy of a store, summed in double over its float fields.
struct Totals {
  double mass = 0, energy = 0, momentum_scale = 0;  // scale: sum m |v_k| (the momentum may be near 0)
  double momentum[3] = {0, 0, 0};
};

template <int D>
Totals totals(const ParticleStore& s, const FieldIds& ids) {
  Totals t;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double m = s.data<Real>(ids.mass)[i];
    const Vec<D>& v = s.data<Vec<D>>(ids.velocity)[i];
    t.mass += m;
    for (int k = 0; k < D; ++k) {
      t.momentum[k] += m * double(v[k]);
      t.momentum_scale += m * std::abs(double(v[k]));
      t.energy += 0.5 * m * double(v[k]) * double(v[k]);
    }
  }
  return t;
}

struct SplitRun {
  SplitCounts cpu, gpu;
  std::size_t before = 0;
};

// Builds the same lattice twice, splits it on the CPU (2 threads) and the GPU after one neighbour
// update (the same sorted order on both, see the parity test above), and checks the counts, the
// sizes and every field byte for byte. Conservation is checked on the GPU's store.
template <int D, class Material, class Stress>
SplitRun split_on_both(const std::string& device, int n, std::size_t capacity, Material material, Stress stress, const SplitParams& rules) {
  SplitRun run;
  const PhysicsParams p = splitting_params(D);
  ParticleStore cpu_store, gpu_store;
  Domain dom;
  const FieldIds ids = build_lattice<D>(cpu_store, p, dom, n, capacity, material, stress);
  build_lattice<D>(gpu_store, p, dom, n, capacity, material, stress);
  auto cpu = make_cpu_backend(2);
  auto gpu = turbid::testing::make_device_backend(device);
  EXPECT_TRUE(gpu->supports_splitting());
  cpu->bind(cpu_store, ids, p, dom);
  gpu->bind(gpu_store, ids, p, dom);
  EXPECT_EQ(cpu->update_neighbours(), 0u);
  EXPECT_EQ(gpu->update_neighbours(), 0u);
  gpu->sync_to_host();
  run.before = gpu_store.size();
  const Totals t0 = totals<D>(gpu_store, ids);

  run.cpu = cpu->split(rules);
  run.gpu = gpu->split(rules);
  EXPECT_EQ(run.gpu.splits, run.cpu.splits);
  EXPECT_EQ(run.gpu.daughters, run.cpu.daughters);
  EXPECT_EQ(run.gpu.refused, run.cpu.refused);
  EXPECT_EQ(run.gpu.smallest_h, run.cpu.smallest_h);
  EXPECT_EQ(gpu_store.size(), cpu_store.size()) << "the host count follows the device at the split";
  gpu->sync_to_host();
  EXPECT_EQ(cpu_store.size(), run.before + run.cpu.daughters);
  EXPECT_LE(cpu_store.size(), cpu_store.capacity());
  if (gpu_store.size() != cpu_store.size()) {
    ADD_FAILURE() << "sizes differ: cpu " << cpu_store.size() << ", gpu " << gpu_store.size();
    return run;
  }
  for (int f = 0; f < cpu_store.field_count(); ++f)
    EXPECT_EQ(std::memcmp(cpu_store.raw(f), gpu_store.raw(f), cpu_store.size() * cpu_store.field_bytes(f)), 0)
        << "field " << cpu_store.desc(f).name << " differs between the backends";

  // Conservation on the GPU (float32 fields, double sums): each daughter's m / 2^D is exact and the
  // velocities are copied, so the totals agree to the summation order (1e-12 on the CPU); the bound
  // asked of a float engine is 1e-6 relative.
  const Totals t1 = totals<D>(gpu_store, ids);
  EXPECT_NEAR(t1.mass, t0.mass, 1e-6 * t0.mass) << "mass";
  EXPECT_NEAR(t1.energy, t0.energy, 1e-6 * t0.energy) << "kinetic energy";
  for (int k = 0; k < D; ++k)
    EXPECT_NEAR(t1.momentum[k], t0.momentum[k], 1e-6 * t0.momentum_scale) << "momentum, axis " << k;

  // The grid is stale after a split: both backends sort the daughters in, in the same order.
  EXPECT_EQ(cpu->update_neighbours(), 0u);
  EXPECT_EQ(gpu->update_neighbours(), 0u);
  gpu->sync_to_host();
  EXPECT_EQ(gpu_store.size(), cpu_store.size());
  if (gpu_store.size() != cpu_store.size()) return run;
  const std::uint32_t* id_cpu = cpu_store.data<std::uint32_t>(ids.id);
  EXPECT_TRUE(std::equal(id_cpu, id_cpu + cpu_store.size(), gpu_store.data<std::uint32_t>(ids.id))) << "sorted order";
  EXPECT_EQ(gpu->pair_count(), cpu->pair_count());
  return run;
}

// Debris in the lower half under water, stress 0..299 Pa in a fixed pattern, threshold 150 Pa,
// only particles next to the water (`where: interface`) split.
TEST(CudaSplitting, InterfaceSplitMatchesCpuBitwise2D) {
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    constexpr int n = 40;
    const SplitRun r = split_on_both<2>(
        device, n, std::size_t(n * n) * 4, [](const Vec<2>& x) { return x[1] < Real(0.2) ? 1 : 0; },
        [](std::size_t i) { return double((i * 53) % 300); }, debris_to_turbidity(150.0, true));
    EXPECT_GT(r.cpu.splits, 10u);
    EXPECT_EQ(r.cpu.refused, 0u);
  });
}

// 3D, every debris particle above the threshold splits (8 daughters; the cube root of the edge).
TEST(CudaSplitting, SplitMatchesCpuBitwise3D) {
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    constexpr int n = 12;
    const SplitRun r = split_on_both<3>(
        device, n, std::size_t(n * n * n) * 8, [](const Vec<3>& x) { return x[2] < Real(0.08) ? 1 : 0; },
        [](std::size_t i) { return double((i * 37) % 200); }, debris_to_turbidity(100.0, false));
    EXPECT_GT(r.cpu.splits, 300u);
    EXPECT_EQ(r.cpu.daughters, 7 * r.cpu.splits);
    EXPECT_EQ(r.cpu.refused, 0u);
  });
}

// 3D with `where: interface`: the neighbour search of the flag pass on the GPU's grid.
TEST(CudaSplitting, InterfaceSplitMatchesCpuBitwise3D) {
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    constexpr int n = 12;
    const SplitRun r = split_on_both<3>(
        device, n, std::size_t(n * n * n) * 8, [](const Vec<3>& x) { return x[2] < Real(0.06) ? 1 : 0; },
        [](std::size_t i) { return double((i * 37) % 200); }, debris_to_turbidity(50.0, true));
    EXPECT_GT(r.cpu.splits, 50u);
    EXPECT_EQ(r.cpu.refused, 0u);
  });
}

// Room for 10 splits (30 new slots in 2D) among 50 candidates: on both backends the 10 lowest-index
// candidates split and 40 are refused, and nothing is written past the capacity.
TEST(CudaSplitting, FullStoreRefusesTheSameMothers) {
  turbid::testing::for_each_device_backend([&](const std::string& device) {
    constexpr int n = 10;
    const SplitRun r = split_on_both<2>(
        device, n, std::size_t(n * n) + 31, [](const Vec<2>&) { return 1; },
        [](std::size_t i) { return i % 2 == 0 ? 200.0 : 0.0; }, debris_to_turbidity(150.0, false));
    EXPECT_EQ(r.gpu.splits, 10u);
    EXPECT_EQ(r.gpu.refused, std::size_t(n * n / 2 - 10));
    EXPECT_EQ(r.gpu.daughters, 30u);
  });
}

}  // namespace
