// The CUDA backend: the same pass functors as the CPU backend (passes.hpp) launched through one
// generic kernel, a CUB radix sort by cell (stable, so the order equals the CPU counting sort's),
// a generic gather of every field that follows the sort, and CUB reductions for step statistics,
// health checks and pair counts; particle splitting runs the shared splitting passes around a CUB
// exclusive scan (sph/splitting.hpp), so it writes the CPU's bytes. The passes search the grid every time: the NeighbourList and
// position_soa shortcuts are the CPU's, and they visit the same pairs in the same order.
// Device memory holds one buffer per registered field, sized from the field registry, so a new
// field needs no code here. The store on the host is current only after sync_to_host(); its size
// follows the device count at every neighbour update.
//
// Kept thin on purpose: no logging, YAML, JSON or CLI headers (they break nvcc in C++20).
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cuda/std/functional>
#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sph/backend.hpp"
#include "sph/backend/cuda/cuda_check.hpp"
#include "sph/backend/cuda/device_buffer.hpp"
#include "sph/boundary_passes.hpp"
#include "sph/dispatch.hpp"
#include "sph/passes.hpp"
#include "sph/splitting.hpp"

#ifndef TURBID_CUDA_ARCHITECTURES
#define TURBID_CUDA_ARCHITECTURES "unknown"
#endif

namespace turbid::sph {
namespace cuda {
namespace {

constexpr unsigned kBlock = 256;

unsigned blocks_for(std::size_t n) { return unsigned((n + kBlock - 1) / kBlock); }

// The one kernel every per-particle functor runs through.
template <class F>
__global__ void run_pass(F f, std::uint32_t n) {
  const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(std::uint32_t(i));
}

template <class F>
void launch(const char* name, std::uint32_t n, const F& f) {
  if (n == 0) return;
  run_pass<<<blocks_for(n), kBlock>>>(f, n);
  TURBID_CUDA_CHECK_LAUNCH(name);
}

// The same kernel with a register bound: at least MinBlocks blocks of kBlock threads per
// multiprocessor (3: <= 80 registers a thread, 4: <= 64). The 3D pair passes need 84-108 registers
// unbounded, which leaves 2 blocks (25% occupancy) on sm_90 for loops that wait on loads.
template <class F, int MinBlocks>
__global__ void __launch_bounds__(kBlock, MinBlocks) run_pass_bounded(F f, std::uint32_t n) {
  const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(std::uint32_t(i));
}

// Blocks per multiprocessor the 3D pair passes are compiled for: 4 (<= 64 registers) unless
// TURBID_CUDA_MIN_BLOCKS says 3 or 0 (unbounded). Measured on an H200 (docs/performance.md, the 3D
// dam break at 4 M particles): 0.88, 1.15 and 1.25 x 10^8 particle-steps/s for 0, 3 and 4.
int pair_min_blocks() {
  static const int v = [] {
    const char* e = std::getenv("TURBID_CUDA_MIN_BLOCKS");
    if (e == nullptr || *e == '\0') return 4;
    const int b = std::atoi(e);
    return b == 3 || b == 4 ? b : 0;
  }();
  return v;
}

// Launches a pair pass (a neighbour loop per particle): in 3D with the register bound above.
template <int D, class F>
void launch_pairs(const char* name, std::uint32_t n, const F& f) {
  if constexpr (D == 3) {
    if (n == 0) return;
    switch (pair_min_blocks()) {
      case 3: run_pass_bounded<F, 3><<<blocks_for(n), kBlock>>>(f, n); break;
      case 4: run_pass_bounded<F, 4><<<blocks_for(n), kBlock>>>(f, n); break;
      default: run_pass<<<blocks_for(n), kBlock>>>(f, n); break;
    }
    TURBID_CUDA_CHECK_LAUNCH(name);
  } else {
    launch(name, n, f);
  }
}

// dst[i] = src[order[i]] for elements of `per` words of type T (generic over the field's size).
template <class T>
__global__ void gather_elements(const T* __restrict__ src, T* __restrict__ dst, const std::uint32_t* __restrict__ order,
                                std::size_t n, unsigned per) {
  const std::size_t total = n * per;
  const std::size_t stride = std::size_t(gridDim.x) * blockDim.x;
  for (std::size_t k = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x; k < total; k += stride) {
    const std::size_t i = k / per;
    const std::size_t w = k - i * per;
    dst[k] = src[std::size_t(order[i]) * per + w];
  }
}

// Does nothing; cudaFuncGetAttributes on it tells whether this binary has code for the device.
__global__ void probe_kernel() {}

// ---- device functors (same formulas as the CPU backend's loops) -----------------------------

// Cell key of each particle; outside the grid (or NaN) -> cell_count, which sorts last. The grid
// is a whole number of cells and may reach past the domain's upper faces: those particles are
// outside too (as on the CPU).
template <int D>
struct KeysPass {
  GridView<D> G;
  Real upper[D];
  const Vec<D>* x;
  std::uint32_t* keys;
  std::uint32_t* values;
  std::uint32_t outside;
  __device__ void operator()(std::uint32_t i) const {
    int c[D] = {};
    bool inside = G.cell_of(x[i], c);
    for (int k = 0; k < D; ++k) inside = inside && x[i][k] <= upper[k];
    keys[i] = inside ? G.linear(c) : outside;
    values[i] = i;
  }
};

// cell_start[c] = number of sorted keys below c (a lower bound per cell, so every cell, empty
// or not, is found in parallel without atomics).
struct CellStartPass {
  const std::uint32_t* keys;
  std::uint32_t n;
  std::uint32_t* cell_start;
  __device__ void operator()(std::uint32_t c) const {
    std::uint32_t lo = 0, hi = n;
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (keys[mid] < c) lo = mid + 1;
      else hi = mid;
    }
    cell_start[c] = lo;
  }
};

// 1 for a fluid particle, 0 otherwise, and 0 past the last particle (the scan's total).
struct FluidFlagPass {
  const std::uint8_t* kind;
  std::uint32_t n;
  std::uint32_t* flag;
  __device__ void operator()(std::uint32_t i) const { flag[i] = i < n && kind[i] == std::uint8_t(Kind::fluid) ? 1u : 0u; }
};

// fluid_before[c] = fluid particles in cells [0, c): the scan of the flags at the cell's first
// particle (GridView::fluid_before, as the CPU's counting sort builds it).
struct FluidBeforePass {
  const std::uint32_t* cell_start;
  const std::uint32_t* fluid_scan;
  std::uint32_t* fluid_before;
  __device__ void operator()(std::uint32_t c) const { fluid_before[c] = fluid_scan[cell_start[c]]; }
};

struct SpeedPair {
  float v2, a2;
};

struct MaxSpeedPair {
  __host__ __device__ SpeedPair operator()(const SpeedPair& a, const SpeedPair& b) const {
    return {a.v2 < b.v2 ? b.v2 : a.v2, a.a2 < b.a2 ? b.a2 : a.a2};
  }
};

// |v|^2 and |a|^2 of fluid particles (0 otherwise). The CPU's running max skips NaN; mapping NaN
// to 0 gives the same result for a reduction in any order.
template <int D>
struct SpeedPass {
  ParticleView<D> P;
  SpeedPair* out;
  __device__ void operator()(std::uint32_t i) const {
    SpeedPair s{0.f, 0.f};
    if (P.kind[i] == std::uint8_t(Kind::fluid)) {
      const float v2 = norm2(P.velocity[i]);
      const float a2 = norm2(P.acceleration[i]);
      s.v2 = isnan(v2) ? 0.f : v2;
      s.a2 = isnan(a2) ? 0.f : a2;
    }
    out[i] = s;
  }
};

constexpr std::uint32_t kHealthy = 0xffffffffu;

// i for an unhealthy particle, kHealthy otherwise; the minimum is the CPU's "first" particle.
template <int D>
struct HealthPass {
  ParticleView<D> P;
  PhysicsParams prm;
  double limit;
  std::uint32_t* out;
  __device__ bool healthy(std::uint32_t i) const {
    for (int k = 0; k < D; ++k)
      if (!isfinite(P.position[i][k]) || !isfinite(P.velocity[i][k]) || !isfinite(P.acceleration[i][k])) return false;
    // Walls and structures hold density in the wall material's units, buffers in their own.
    const bool own = P.kind[i] == std::uint8_t(Kind::fluid) || P.kind[i] == std::uint8_t(Kind::buffer);
    const int m = own ? P.material[i] : prm.wall_material;
    const double ratio = double(P.density[i]) / prm.materials[m].eos.rest_density - 1.0;
    return isfinite(ratio) && fabs(ratio) <= limit;
  }
  __device__ void operator()(std::uint32_t i) const { out[i] = healthy(i) ? kHealthy : i; }
};

// Neighbours within the support 2h of each particle (itself excluded), as the CPU counts them.
template <int D>
struct PairCountPass {
  ParticleView<D> P;
  GridView<D> G;
  Real h;
  unsigned long long* out;
  __device__ void operator()(std::uint32_t i) const {
    int c[D] = {};
    G.cell_of(P.position[i], c);
    unsigned long long local = 0;
    const Vec<D> xi = P.position[i];
    G.for_each_neighbour_range(c, [&](std::uint32_t b, std::uint32_t e, const Vec<D>& offset) {
      for (std::uint32_t j = b; j < e; ++j)
        if (j != i && norm2(xi - P.position[j] - offset) < Real(4) * h * h) ++local;
    });
    out[i] = local;
  }
};

// What each particle adds to a split's counts (SplitTally::of, the CPU's rule); summed by CUB.
struct SplitTallyPass {
  const std::uint32_t* id;
  const Real* h;
  const std::uint64_t* first_slot;
  const std::uint32_t* new_slots;
  std::uint64_t room;
  SplitTally* out;
  __device__ void operator()(std::uint32_t i) const { out[i] = SplitTally::of(id[i], h[i], first_slot[i], new_slots[i], room); }
};

// ---- the backend -----------------------------------------------------------------------------

// Runs a CUB device algorithm twice: once to size its temporary storage, once to do the work.
#define TURBID_CUB_CALL(name, ...)                                                          \
  cub_call(name, __FILE__, __LINE__, [&](void* cub_temp, std::size_t& cub_temp_bytes) {   \
    return __VA_ARGS__;                                                                     \
  })

class CudaBackend final : public Backend {
 public:
  CudaBackend() {
    TURBID_CUDA_CHECK(cudaSetDevice(0));
    TURBID_CUDA_CHECK(cudaFree(nullptr));  // create the context now, so that a broken device fails here
  }

  std::string name() const override { return "cuda"; }
  int threads() const override { return 1; }  // host threads; the device does the work

  void bind(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain) override {
    store_ = &store;
    ids_ = ids;
    params_ = params;
    layout_ = GridLayout::make(domain, params.dimensions, 2.0 * params.smoothing_length * max_h_ratio());
    cell_count_ = layout_.cell_count;
    for (int k = 0; k < params.dimensions; ++k) domain_max_[k] = domain.max[k];
    key_bits_ = 1;
    while (key_bits_ < 32 && (std::uint64_t(1) << key_bits_) <= cell_count_) ++key_bits_;
    cell_start_.allocate((cell_count_ + 1) * sizeof(std::uint32_t));
    TURBID_CUDA_CHECK(cudaMemset(cell_start_.get(), 0, cell_start_.bytes()));
    fluid_before_.allocate((cell_count_ + 1) * sizeof(std::uint32_t));
    TURBID_CUDA_CHECK(cudaMemset(fluid_before_.get(), 0, fluid_before_.bytes()));
    put_backs_.allocate(sizeof(unsigned long long));
    TURBID_CUDA_CHECK(cudaMemset(put_backs_.get(), 0, put_backs_.bytes()));
    allocate_fields();
    upload();
  }

  std::size_t update_neighbours() override {
    return params_.dimensions == 2 ? sort_by_cell<2>() : sort_by_cell<3>();
  }

  void compute_density_rate() override {
    if (params_.dimensions == 2) compute_rate<2>();
    else compute_rate<3>();
  }

  void compute_forces() override {
    if (params_.dimensions == 2) compute_momentum<2>();
    else compute_momentum<3>();
  }

  void kick(double half_dt) override {
    if (params_.dimensions == 2) launch("KickPass<2>", n_, KickPass<2>{view<2>(), Real(half_dt)});
    else launch("KickPass<3>", n_, KickPass<3>{view<3>(), Real(half_dt)});
  }

  void drift(double dt) override {
    const Real wall_rho_min = params_.materials[params_.wall_material].eos.no_tension_density();
    if (params_.dimensions == 2) launch("DriftPass<2>", n_, DriftPass<2>{view<2>(), Real(dt), wall_rho_min, params_});
    else launch("DriftPass<3>", n_, DriftPass<3>{view<3>(), Real(dt), wall_rho_min, params_});
    if (!params_.wall_constraint) return;
    auto* put_backs = put_backs_.as<unsigned long long>();
    if (params_.dimensions == 2)
      launch("WallConstraintPass<2>", n_, WallConstraintPass<2>{view<2>(), grid<2>(), params_, NeighbourList{}, put_backs});
    else
      launch("WallConstraintPass<3>", n_, WallConstraintPass<3>{view<3>(), grid<3>(), params_, NeighbourList{}, put_backs});
  }

  std::uint64_t wall_put_backs() override {
    unsigned long long n = 0;
    if (put_backs_.get())
      TURBID_CUDA_CHECK(cudaMemcpy(&n, put_backs_.get(), sizeof(n), cudaMemcpyDeviceToHost));
    return n;
  }

  // Conversions at open boundaries run on the host (few particles change; the store is copied
  // both ways only in scenes with open boundaries).
  OpenBoundaryCounts update_open_boundaries() override {
    sync_to_host();
    const OpenBoundaryCounts c = sph::update_open_boundaries(*store_, ids_, params_);
    sync_from_host();
    return c;
  }

  StepStats stats() override { return params_.dimensions == 2 ? stats_impl<2>() : stats_impl<3>(); }

  std::optional<HealthIssue> check_health(double limit) override {
    return params_.dimensions == 2 ? health_impl<2>(limit) : health_impl<3>(limit);
  }

  void sync_to_host() override {
    if (store_ == nullptr) return;
    store_->resize(n_);
    // A field registered on the host after bind() lives on the host until sync_from_host().
    const int on_device = std::min(store_->field_count(), int(fields_.size()));
    for (int f = 0; f < on_device; ++f) {
      const std::size_t bytes = n_ * store_->field_bytes(f);
      if (bytes > 0) TURBID_CUDA_CHECK(cudaMemcpy(store_->raw(f), fields_[std::size_t(f)].get(), bytes, cudaMemcpyDeviceToHost));
    }
  }

  void sync_from_host() override {
    if (store_ == nullptr) return;
    // The host may have grown the store or registered fields since bind().
    if (store_->capacity() > capacity_ || store_->size() > capacity_ || std::size_t(store_->field_count()) != fields_.size())
      allocate_fields();
    upload();
  }

  std::size_t pair_count() override { return params_.dimensions == 2 ? count_pairs<2>() : count_pairs<3>(); }

  // The per-particle forces are summed on the host (few structure particles; double precision).
  std::vector<BodyLoad> body_loads(const std::vector<std::array<double, 3>>& reference) override {
    if (params_.body_count == 0 || ids_.structure_force < 0) return std::vector<BodyLoad>(reference.size());
    if (params_.dimensions == 2) return loads_impl<2>(reference);
    return loads_impl<3>(reference);
  }

  // Moving structures: the bodies' states (a few hundred bytes) go up each call and the shared
  // placement pass (sph/body_motion.hpp) moves their particles on the device.
  bool supports_moving_bodies() const override { return true; }
  void place_bodies(const std::vector<BodyPlacement>& bodies, bool move) override {
    if (ids_.body_offset < 0) throw std::logic_error("place_bodies: the store has no body_offset field");
    if (bodies.empty() || n_ == 0) return;
    placements_.ensure(bodies.size() * sizeof(BodyPlacement));
    TURBID_CUDA_CHECK(cudaMemcpy(placements_.get(), bodies.data(), bodies.size() * sizeof(BodyPlacement),
                                 cudaMemcpyHostToDevice));
    if (params_.dimensions == 2) place_impl<2>(int(bodies.size()), move);
    else place_impl<3>(int(bodies.size()), move);
  }

  template <int D>
  void place_impl(int body_count, bool move) {
    auto field = [&](FieldId id) { return fields_[std::size_t(id)].get(); };
    PlaceBodiesPass<D> pass;
    pass.position = static_cast<Vec<D>*>(field(ids_.position));
    pass.velocity = static_cast<Vec<D>*>(field(ids_.velocity));
    pass.kind = static_cast<const std::uint8_t*>(field(ids_.kind));
    pass.body = static_cast<const std::uint8_t*>(field(ids_.body));
    pass.offset = static_cast<const Vec<D>*>(field(ids_.body_offset));
    if (ids_.body_normal >= 0 && ids_.boundary_normal >= 0) {
      pass.boundary_normal = static_cast<Vec<D>*>(field(ids_.boundary_normal));
      pass.normal0 = static_cast<const Vec<D>*>(field(ids_.body_normal));
    }
    pass.bodies = placements_.as<BodyPlacement>();
    pass.body_count = body_count;
    pass.move = move;
    launch(D == 2 ? "PlaceBodiesPass<2>" : "PlaceBodiesPass<3>", n_, pass);
  }

  bool supports_splitting() const override { return true; }
  SplitCounts split(const SplitParams& rules) override {
    return params_.dimensions == 2 ? split_impl<2>(rules) : split_impl<3>(rules);
  }
  std::size_t relax_split(const SplitParams& rules) override {
    return params_.dimensions == 2 ? relax_impl<2>(rules) : relax_impl<3>(rules);
  }

  template <int D>
  std::vector<BodyLoad> loads_impl(const std::vector<std::array<double, 3>>& reference) {
    std::vector<Vec<D>> x(n_), f(n_);
    std::vector<std::uint8_t> body(n_);
    auto copy = [&](void* dst, FieldId id, std::size_t bytes) {
      if (bytes > 0) TURBID_CUDA_CHECK(cudaMemcpy(dst, fields_[std::size_t(id)].get(), bytes, cudaMemcpyDeviceToHost));
    };
    copy(x.data(), ids_.position, n_ * sizeof(Vec<D>));
    copy(f.data(), ids_.structure_force, n_ * sizeof(Vec<D>));
    copy(body.data(), ids_.body, n_);
    return sum_body_loads<D>(x.data(), f.data(), body.data(), n_, reference);
  }

 private:
  double max_h_ratio() const {
    // Largest h present relative to the initial h (PhysicsParams::max_smoothing_length): the cells
    // must be at least the largest pair support 2 h_max, or pairs beyond one cell are never seen.
    // Splitting only halves h (ratio 1), but a store may carry h above the lattice's.
    const double h0 = params_.smoothing_length, h_max = params_.max_smoothing_length;
    return h_max > h0 ? h_max / h0 : 1.0;
  }

  void allocate_fields() {
    const ParticleStore& s = *store_;
    capacity_ = std::max<std::size_t>({s.capacity(), s.size(), 1});
    fields_.clear();
    fields_.resize(std::size_t(s.field_count()));
    std::size_t max_bytes = 1;
    for (int f = 0; f < s.field_count(); ++f) {
      const std::size_t fb = s.field_bytes(f);
      max_bytes = std::max(max_bytes, fb);
      fields_[std::size_t(f)].allocate(capacity_ * fb);
    }
    scratch_.allocate(capacity_ * max_bytes);
    // One more than the capacity: the fluid count scan after the sort (fluid_before) reuses keys_in_
    // and values_in_ for n + 1 entries.
    for (DeviceBuffer* b : {&keys_in_, &keys_out_, &values_in_, &values_out_})
      b->allocate((capacity_ + 1) * sizeof(std::uint32_t));
    reduce_in_.allocate(capacity_ * 8);  // per-particle SpeedPair, u32 or u64
    result_.ensure(16);
  }

  void upload() {
    const ParticleStore& s = *store_;
    n_ = std::uint32_t(s.size());
    for (int f = 0; f < s.field_count(); ++f) {
      const std::size_t bytes = std::size_t(n_) * s.field_bytes(f);
      if (bytes > 0) TURBID_CUDA_CHECK(cudaMemcpy(fields_[std::size_t(f)].get(), s.raw(f), bytes, cudaMemcpyHostToDevice));
    }
  }

  template <class Call>
  void cub_call(const char* name, const char* file, int line, Call&& call) {
    std::size_t bytes = 0;
    check_call(call(nullptr, bytes), name, file, line);
    temp_.ensure(bytes);
    bytes = temp_.bytes();
    check_call(call(temp_.get(), bytes), name, file, line);
  }

  template <class T>
  T download_result() {
    T v{};
    TURBID_CUDA_CHECK(cudaMemcpy(&v, result_.get(), sizeof(T), cudaMemcpyDeviceToHost));
    return v;
  }

  template <int D>
  ParticleView<D> view() const {
    ParticleView<D> v;
    auto field = [&](FieldId id) { return fields_[std::size_t(id)].get(); };
    v.position = static_cast<Vec<D>*>(field(ids_.position));
    v.velocity = static_cast<Vec<D>*>(field(ids_.velocity));
    v.acceleration = static_cast<Vec<D>*>(field(ids_.acceleration));
    v.density = static_cast<Real*>(field(ids_.density));
    v.density_rate = static_cast<Real*>(field(ids_.density_rate));
    v.pressure = static_cast<Real*>(field(ids_.pressure));
    v.mass = static_cast<Real*>(field(ids_.mass));
    v.smoothing_length = static_cast<Real*>(field(ids_.smoothing_length));
    v.material = static_cast<std::uint8_t*>(field(ids_.material));
    v.kind = static_cast<std::uint8_t*>(field(ids_.kind));
    if (ids_.density_gradient >= 0) v.density_gradient = static_cast<Vec<D>*>(field(ids_.density_gradient));
    if (ids_.boundary_normal >= 0) v.boundary_normal = static_cast<Vec<D>*>(field(ids_.boundary_normal));
    if (ids_.structure_force >= 0) v.structure_force = static_cast<Vec<D>*>(field(ids_.structure_force));
    if (ids_.body >= 0) v.body = static_cast<std::uint8_t*>(field(ids_.body));
    if (ids_.zone >= 0) v.zone = static_cast<std::uint8_t*>(field(ids_.zone));
    if (ids_.free_slip >= 0) v.free_slip = static_cast<std::uint8_t*>(field(ids_.free_slip));
    if (ids_.viscous_velocity >= 0) v.viscous_velocity = static_cast<Vec<D>*>(field(ids_.viscous_velocity));
    if (ids_.shifting_velocity >= 0) v.shifting_velocity = static_cast<Vec<D>*>(field(ids_.shifting_velocity));
    if (ids_.shear_rate >= 0) v.shear_rate = static_cast<Real*>(field(ids_.shear_rate));
    if (ids_.effective_viscosity >= 0) v.effective_viscosity = static_cast<Real*>(field(ids_.effective_viscosity));
    if (ids_.shear_stress >= 0) v.shear_stress = static_cast<Real*>(field(ids_.shear_stress));
    if (ids_.split_fresh >= 0) v.split_fresh = static_cast<std::uint8_t*>(field(ids_.split_fresh));
    v.count = n_;
    return v;
  }

  template <int D>
  GridView<D> grid() const {
    return layout_.view<D>(cell_start_.as<std::uint32_t>(), fluid_before_.as<std::uint32_t>());
  }

  // new[i] = old[order[i]] for one field, by its size in bytes per particle.
  void gather_field(FieldId f, const std::uint32_t* order, std::uint32_t n) {
    DeviceBuffer& buf = fields_[std::size_t(f)];
    const std::size_t fb = store_->field_bytes(f);
    const std::size_t total = std::size_t(n) * fb;
    const unsigned blocks = unsigned(std::min<std::size_t>(blocks_for(fb % 4 == 0 ? total / 4 : total), 1u << 20));
    if (fb % 4 == 0) {
      gather_elements<std::uint32_t><<<blocks, kBlock>>>(buf.as<std::uint32_t>(), scratch_.as<std::uint32_t>(), order, n,
                                                         unsigned(fb / 4));
    } else {
      gather_elements<std::uint8_t><<<blocks, kBlock>>>(buf.as<std::uint8_t>(), scratch_.as<std::uint8_t>(), order, n,
                                                        unsigned(fb));
    }
    TURBID_CUDA_CHECK_LAUNCH("gather_elements");
    // The scratch buffer has the size of the widest field; swap with fields of that size, copy the others.
    if (buf.bytes() == scratch_.bytes()) buf.swap(scratch_);
    else TURBID_CUDA_CHECK(cudaMemcpy(buf.get(), scratch_.get(), total, cudaMemcpyDeviceToDevice));
  }

  template <int D>
  std::size_t sort_by_cell() {
    const std::uint32_t n = n_;
    const GridView<D> g = grid<D>();
    std::uint32_t* keys_in = keys_in_.as<std::uint32_t>();
    std::uint32_t* keys_out = keys_out_.as<std::uint32_t>();
    std::uint32_t* values_in = values_in_.as<std::uint32_t>();
    std::uint32_t* values_out = values_out_.as<std::uint32_t>();
    const ParticleView<D> P = view<D>();
    KeysPass<D> keys{g, {}, P.position, keys_in, values_in, std::uint32_t(cell_count_)};
    for (int k = 0; k < D; ++k) keys.upper[k] = Real(domain_max_[k]);
    launch("KeysPass", n, keys);
    if (n > 0) {
      // Radix sort is stable: inside a cell particles keep their order, as in the CPU counting sort.
      TURBID_CUB_CALL("cub::DeviceRadixSort::SortPairs",
                      cub::DeviceRadixSort::SortPairs(cub_temp, cub_temp_bytes, keys_in, keys_out, values_in, values_out,
                                                      n, 0, key_bits_));
      for (int f = 0; f < int(fields_.size()); ++f)
        if (store_->desc(f).follows_sort) gather_field(f, values_out, n);
    }
    launch("CellStartPass", std::uint32_t(cell_count_ + 1), CellStartPass{keys_out, n, cell_start_.as<std::uint32_t>()});
    std::uint32_t kept = 0;
    TURBID_CUDA_CHECK(cudaMemcpy(&kept, cell_start_.as<std::uint32_t>() + cell_count_, sizeof kept, cudaMemcpyDeviceToHost));
    n_ = kept;
    // fluid_before, so that wall particles with no fluid in their 3^d cells skip the search (the
    // CPU's shortcut, same results): flags of the kept particles (and a 0 after them), scanned.
    const std::uint8_t* kind = fields_[std::size_t(ids_.kind)].as<std::uint8_t>();
    launch("FluidFlagPass", kept + 1, FluidFlagPass{kind, kept, values_in});
    TURBID_CUB_CALL("cub::DeviceScan::ExclusiveSum(fluid flags)",
                    cub::DeviceScan::ExclusiveSum(cub_temp, cub_temp_bytes, values_in, keys_in, kept + 1));
    launch("FluidBeforePass", std::uint32_t(cell_count_ + 1),
           FluidBeforePass{cell_start_.as<std::uint32_t>(), keys_in, fluid_before_.as<std::uint32_t>()});
    // Keep the host's count in step (shrinking only moves the size); the data follow at sync_to_host().
    if (store_->size() > kept) store_->resize(kept);
    return n - kept;
  }

  template <int D>
  void compute_rate() {
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      if (params_.diffusion == Diffusion::antuono)
        launch_pairs<D>("DensityGradientPass", P.count, DensityGradientPass<D, K, U>{P, G, params_, NeighbourList{}});
      dispatch_diffusion(params_.diffusion, [&](auto diff_tag) {
        constexpr Diffusion Df = decltype(diff_tag)::value;
        launch_pairs<D>("ContinuityPass", P.count, ContinuityPass<D, K, Df, U>{P, G, params_, NeighbourList{}});
      });
    });
  }

  template <int D>
  void compute_momentum() {
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      if (params_.boundary == Boundary::mdbc || params_.wall_no_slip)
        launch_pairs<D>("MdbcPass", P.count, MdbcPass<D, K, U>{P, G, params_, params_.wall_no_slip, params_.boundary == Boundary::mdbc});
      if (params_.zone_count > 0) launch("BufferPass", P.count, BufferPass<D, K, U>{P, G, params_});
      if (params_.rheology) launch("RheologyPass", P.count, RheologyPass<D, K, U>{P, G, params_});
      launch("PressurePass", P.count, PressurePass<D>{P, params_});
      launch_pairs<D>("MomentumPass", P.count, MomentumPass<D, K, U>{P, G, params_, NeighbourList{}});
      if (params_.body_count > 0) launch("StructureForcePass", P.count, StructureForcePass<D, K, U>{P, G, params_});
    });
  }

  // Splitting in the four steps of sph/splitting.hpp, as the CPU backend does them: the flag pass,
  // an exclusive scan of the new slots, the capacity rule tallied per particle and reduced (the
  // counts, the last accepted mother's slots, the smallest daughter h, the next free id), then the
  // write pass. Only the tally comes back to the host; the store on the host gets the new count
  // now and the data at sync_to_host().
  template <int D>
  SplitCounts split_impl(const SplitParams& rules) {
    SplitCounts c;
    const std::uint32_t n = n_;
    if (rules.rule_count == 0 || n == 0) return c;
    // Allocated at the first split, for the whole capacity: scenes without transitions hold none.
    split_slots_.ensure(capacity_ * sizeof(std::uint32_t));
    split_rule_.ensure(capacity_ * sizeof(std::int8_t));
    split_first_.ensure(capacity_ * sizeof(std::uint64_t));
    split_tally_.ensure(capacity_ * sizeof(SplitTally));
    result_.ensure(sizeof(SplitTally));
    std::uint32_t* slots = split_slots_.as<std::uint32_t>();
    std::int8_t* rule_of = split_rule_.as<std::int8_t>();
    std::uint64_t* first = split_first_.as<std::uint64_t>();
    SplitTally* tally = split_tally_.as<SplitTally>();
    if (ids_.split_fresh >= 0)  // the last split's daughters are old now
      TURBID_CUDA_CHECK(cudaMemset(fields_[std::size_t(ids_.split_fresh)].get(), 0, n));
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      launch("SplitFlagPass", n, SplitFlagPass<D, K, U>{P, G, params_, rules, slots, rule_of});
    });
    // ExclusiveSum would add in the counts' own type (32 bits); a 64-bit initial value makes CUB
    // accumulate in 64 bits, like the CPU's std::exclusive_scan.
    TURBID_CUB_CALL("cub::DeviceScan::ExclusiveScan(split slots)",
                    cub::DeviceScan::ExclusiveScan(cub_temp, cub_temp_bytes, slots, first, ::cuda::std::plus<>{},
                                                   std::uint64_t(0), n));
    // The store's capacity, as on the CPU (the device buffers hold at least as much).
    const std::uint64_t capacity = std::min<std::uint64_t>(capacity_, store_->capacity());
    const std::uint64_t room = capacity > n ? capacity - n : 0;
    std::uint32_t* id = fields_[std::size_t(ids_.id)].as<std::uint32_t>();
    launch("SplitTallyPass", n, SplitTallyPass{id, P.smoothing_length, first, slots, room, tally});
    TURBID_CUB_CALL("cub::DeviceReduce::Reduce(split tally)",
                    cub::DeviceReduce::Reduce(cub_temp, cub_temp_bytes, tally, result_.as<SplitTally>(), n,
                                              CombineSplitTally{}, SplitTally::none()));
    const SplitTally t = download_result<SplitTally>();
    c.splits = t.splits;
    c.refused = t.refused;
    if (c.splits == 0) return c;
    c.smallest_h = t.smallest_h;
    // Every field on the device (one registered on the host after bind() stays there, as in sync_to_host()).
    const int on_device = std::min(store_->field_count(), int(fields_.size()));
    const SplitFieldTable table =
        split_field_table(*store_, on_device, [&](FieldId f) { return fields_[std::size_t(f)].get(); });
    launch("SplitWritePass", n,
           SplitWritePass<D>{table, P, DriftPass<D>{P, Real(0), Real(0), params_}, rules, slots, rule_of, first, room, n,
                             t.next_id, id});
    n_ = std::uint32_t(n + t.added);
    store_->resize(n_);  // within the capacity; the host's data follow at sync_to_host()
    c.daughters = t.added;
    return c;
  }

  // The relaxation after a split, as on the CPU (sph/splitting.hpp); the zone's mean shift is a
  // CUB reduction in double (its last bits may differ from the CPU's ordered sum).
  template <int D>
  std::size_t relax_impl(const SplitParams& rules) {
    if (ids_.split_fresh < 0 || rules.relax_iterations <= 0 || n_ == 0) return 0;
    const std::uint32_t n = n_;
    relax_zone_.ensure(capacity_ * sizeof(std::uint8_t));
    relax_shift_.ensure(capacity_ * sizeof(Vec<D>));
    relax_moment_.ensure(capacity_ * sizeof(RelaxMoment));
    result_.ensure(sizeof(RelaxMoment));
    std::uint8_t* zone = relax_zone_.as<std::uint8_t>();
    Vec<D>* shift = relax_shift_.as<Vec<D>>();
    RelaxMoment* moment = relax_moment_.as<RelaxMoment>();
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    std::size_t zone_count = 0;
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      launch("SplitRelaxZonePass", n, SplitRelaxZonePass<D, K, U>{P, G, params_, zone});
      for (int it = 0; it < rules.relax_iterations; ++it) {
        launch("SplitRelaxShiftPass", n, SplitRelaxShiftPass<D, K, U>{P, G, params_, zone, shift, rules.relax_strength});
        launch("RelaxMomentPass", n, RelaxMomentPass<D>{zone, P.mass, shift, moment});
        TURBID_CUB_CALL("cub::DeviceReduce::Reduce(relaxation moment)",
                        cub::DeviceReduce::Reduce(cub_temp, cub_temp_bytes, moment, result_.as<RelaxMoment>(), n,
                                                  SumRelaxMoment{}, RelaxMoment{0, 0, {0, 0, 0}}));
        const RelaxMoment m = download_result<RelaxMoment>();
        zone_count = std::size_t(m.count);
        if (zone_count == 0) return;
        Vec<D> mean;
        for (int a = 0; a < D; ++a) mean[a] = Real(m.moment[a] / m.mass);
        launch("SplitRelaxApplyPass", n, SplitRelaxApplyPass<D>{P, DriftPass<D>{P, Real(0), Real(0), params_}, zone, shift, mean});
      }
    });
    return zone_count;
  }

  template <int D>
  StepStats stats_impl() {
    const std::uint32_t n = n_;
    if (n == 0) return {};
    SpeedPair* in = reduce_in_.as<SpeedPair>();
    SpeedPair* out = result_.as<SpeedPair>();
    launch("SpeedPass", n, SpeedPass<D>{view<D>(), in});
    TURBID_CUB_CALL("cub::DeviceReduce::Reduce(max speed)",
                    cub::DeviceReduce::Reduce(cub_temp, cub_temp_bytes, in, out, n, MaxSpeedPair{}, SpeedPair{0.f, 0.f}));
    const SpeedPair s = download_result<SpeedPair>();
    return {std::sqrt(double(s.v2)), std::sqrt(double(s.a2))};
  }

  template <int D>
  std::optional<HealthIssue> health_impl(double limit) {
    const std::uint32_t n = n_;
    if (n == 0) return std::nullopt;
    std::uint32_t* in = reduce_in_.as<std::uint32_t>();
    std::uint32_t* out = result_.as<std::uint32_t>();
    launch("HealthPass", n, HealthPass<D>{view<D>(), params_, limit, in});
    TURBID_CUB_CALL("cub::DeviceReduce::Min(health)", cub::DeviceReduce::Min(cub_temp, cub_temp_bytes, in, out, n));
    const std::uint32_t i = download_result<std::uint32_t>();
    if (i == kHealthy) return std::nullopt;

    // Copy the one particle down and describe it exactly as the CPU backend does.
    const ParticleView<D> P = view<D>();
    Vec<D> x, v, a;
    Real rho = 0;
    std::uint32_t id = 0;
    TURBID_CUDA_CHECK(cudaMemcpy(&x, P.position + i, sizeof x, cudaMemcpyDeviceToHost));
    TURBID_CUDA_CHECK(cudaMemcpy(&v, P.velocity + i, sizeof v, cudaMemcpyDeviceToHost));
    TURBID_CUDA_CHECK(cudaMemcpy(&a, P.acceleration + i, sizeof a, cudaMemcpyDeviceToHost));
    TURBID_CUDA_CHECK(cudaMemcpy(&rho, P.density + i, sizeof rho, cudaMemcpyDeviceToHost));
    TURBID_CUDA_CHECK(cudaMemcpy(&id, fields_[std::size_t(ids_.id)].as<std::uint32_t>() + i, sizeof id, cudaMemcpyDeviceToHost));
    HealthIssue h;
    h.index = i;
    h.id = id;
    for (int k = 0; k < D; ++k) {
      if (!std::isfinite(x[k])) { h.field = "position"; h.value = x[k]; return h; }
      if (!std::isfinite(v[k])) { h.field = "velocity"; h.value = v[k]; return h; }
      if (!std::isfinite(a[k])) { h.field = "acceleration"; h.value = a[k]; return h; }
    }
    h.field = "density";
    h.value = rho;
    return h;
  }

  template <int D>
  std::size_t count_pairs() {
    const std::uint32_t n = n_;
    if (n == 0) return 0;
    auto* in = reduce_in_.as<unsigned long long>();
    auto* out = result_.as<unsigned long long>();
    launch("PairCountPass", n, PairCountPass<D>{view<D>(), grid<D>(), params_.smoothing_length, in});
    TURBID_CUB_CALL("cub::DeviceReduce::Sum(pairs)", cub::DeviceReduce::Sum(cub_temp, cub_temp_bytes, in, out, n));
    return std::size_t(download_result<unsigned long long>());
  }

  ParticleStore* store_ = nullptr;
  FieldIds ids_;
  PhysicsParams params_;
  GridLayout layout_;
  double domain_max_[3] = {0, 0, 0};
  std::size_t cell_count_ = 1;
  int key_bits_ = 1;          // radix sort bits: enough for keys 0..cell_count
  std::uint32_t n_ = 0;       // particles on the device
  std::size_t capacity_ = 0;  // particles the device buffers hold
  std::vector<DeviceBuffer> fields_;  // indexed by FieldId
  DeviceBuffer scratch_;              // gather target, capacity x widest field
  DeviceBuffer cell_start_, keys_in_, keys_out_, values_in_, values_out_;
  DeviceBuffer fluid_before_;  // cell_count + 1: fluid particles in the cells before each cell
  DeviceBuffer put_backs_;     // one counter: WallConstraintPass's put-backs since bind
  DeviceBuffer reduce_in_, result_, temp_;
  DeviceBuffer split_slots_, split_rule_, split_first_, split_tally_;  // splitting only, from the first split
  DeviceBuffer relax_zone_, relax_shift_, relax_moment_;  // relaxation after a split, from the first one
  DeviceBuffer placements_;  // moving structures' BodyPlacement, one per structure
};

#undef TURBID_CUB_CALL

}  // namespace
}  // namespace cuda

bool cuda_backend_compiled() { return true; }

int cuda_device_count(std::string* reason) {
  auto say = [&](std::string s) {
    if (reason) *reason = std::move(s);
  };
  int n = 0;
  cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(std::string("cudaGetDeviceCount: ") + cudaGetErrorString(e));
    return 0;
  }
  if (n <= 0) {
    say("cudaGetDeviceCount: no CUDA device found");
    return 0;
  }
  cudaDeviceProp prop{};
  e = cudaGetDeviceProperties(&prop, 0);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(std::string("cudaGetDeviceProperties(0): ") + cudaGetErrorString(e));
    return 0;
  }
  char text[512];
  std::snprintf(text, sizeof text, "%s (%.1f GiB, sm_%d%d)", prop.name, double(prop.totalGlobalMem) / double(1ull << 30),
                prop.major, prop.minor);
  std::string what = text;
  if (n > 1) what += " and " + std::to_string(n - 1) + " more (device 0 is used)";
  // A device this binary has no code for (e.g. built for sm_90, run on sm_80) cannot run a step.
  cudaFuncAttributes attr{};
  e = cudaFuncGetAttributes(&attr, cuda::probe_kernel);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(what + ": no kernel image for this device (built for CUDA architectures " TURBID_CUDA_ARCHITECTURES "): " +
        cudaGetErrorString(e));
    return 0;
  }
  say(what);
  return n;
}

std::unique_ptr<Backend> make_cuda_backend() {
  std::string why;
  if (cuda_device_count(&why) <= 0) throw std::runtime_error("cuda backend: no usable CUDA device: " + why);
  return std::make_unique<cuda::CudaBackend>();
}

}  // namespace turbid::sph
