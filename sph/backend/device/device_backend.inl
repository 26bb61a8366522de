// The device backend, written once for Thrust's two device systems (device_system.hpp): included
// by backend/cuda/cuda_backend.cu (nvcc, CUDA: the "cuda" backend) and by
// backend/omp_device/omp_device_backend.cpp (g++, OpenMP: the "device-omp" backend, which runs
// this same code on CPU threads so that CI executes it without a GPU).
//
// The same pass functors as the CPU backend (passes.hpp) launched through one generic launch, a
// stable Thrust sort by cell key (so the order equals the CPU counting sort's), a generic gather of
// every field that follows the sort, and Thrust reductions for step statistics, health checks and
// pair counts; particle splitting runs the shared splitting passes around a Thrust exclusive scan
// (sph/splitting.hpp), so it writes the CPU's bytes. The passes search the grid every time: the
// NeighbourList and position_soa shortcuts are the CPU's, and they visit the same pairs in the
// same order. Device memory holds one buffer per registered field, sized from the field registry,
// so a new field needs no code here. The store on the host is current only after sync_to_host();
// its size follows the device count at every neighbour update.
//
// Kept thin on purpose: no logging, YAML, JSON or CLI headers (they break nvcc in C++20).
#include <thrust/copy.h>
#include <thrust/fill.h>
#include <thrust/functional.h>
#include <thrust/reduce.h>
#include <thrust/scan.h>
#include <thrust/sort.h>
#include <thrust/transform_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sph/backend.hpp"
#include "sph/backend/device/device_buffer.hpp"
#include "sph/backend/device/device_system.hpp"
#include "sph/boundary_passes.hpp"
#include "sph/dispatch.hpp"
#include "sph/implicit_viscosity_solve.hpp"
#include "sph/passes.hpp"
#include "sph/splitting.hpp"

namespace turbid::sph {
namespace TURBID_DEVICE_NS {
namespace {

// dst[k] = src[order[k / per] * per + k % per]: one word of a field of `per` words of type T per
// particle (generic over the field's size).
template <class T>
struct GatherWords {
  const T* src;
  T* dst;
  const std::uint32_t* order;
  std::size_t per;
  TURBID_HD void operator()(std::size_t k) const {
    const std::size_t i = k / per;
    const std::size_t w = k - i * per;
    dst[k] = src[std::size_t(order[i]) * per + w];
  }
};

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
  TURBID_HD void operator()(std::uint32_t i) const {
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
  TURBID_HD void operator()(std::uint32_t c) const {
    std::uint32_t lo = 0, hi = n;
    while (lo < hi) {
      const std::uint32_t mid = lo + (hi - lo) / 2;
      if (keys[mid] < c) lo = mid + 1;
      else hi = mid;
    }
    cell_start[c] = lo;
  }
};

// 1 for a fluid particle, 0 otherwise, and 0 past the last kept particle (the scan's total); the
// kept count is read on the device (cell_start[cell_count]), so the host need not wait for it.
struct FluidFlagPass {
  const std::uint8_t* kind;
  const std::uint32_t* kept;
  std::uint32_t* flag;
  TURBID_HD void operator()(std::uint32_t i) const { flag[i] = i < *kept && kind[i] == std::uint8_t(Kind::fluid) ? 1u : 0u; }
};

// fluid_before[c] = fluid particles in cells [0, c): the scan of the flags at the cell's first
// particle (GridView::fluid_before, as the CPU's counting sort builds it).
struct FluidBeforePass {
  const std::uint32_t* cell_start;
  const std::uint32_t* fluid_scan;
  std::uint32_t* fluid_before;
  TURBID_HD void operator()(std::uint32_t c) const { fluid_before[c] = fluid_scan[cell_start[c]]; }
};

struct SpeedPair {
  float v2, a2;
};

struct MaxSpeedPair {
  TURBID_HD SpeedPair operator()(const SpeedPair& a, const SpeedPair& b) const {
    return {a.v2 < b.v2 ? b.v2 : a.v2, a.a2 < b.a2 ? b.a2 : a.a2};
  }
};

// |v|^2 and |a|^2 of fluid particles (0 otherwise). The CPU's running max skips NaN; mapping NaN
// to 0 gives the same result for a reduction in any order.
template <int D>
struct SpeedPass {
  ParticleView<D> P;
  TURBID_HD SpeedPair operator()(std::uint32_t i) const {
    SpeedPair s{0.f, 0.f};
    if (P.kind[i] == std::uint8_t(Kind::fluid)) {
      const float v2 = norm2(P.velocity[i]);
      const float a2 = norm2(P.acceleration[i]);
      s.v2 = is_nan(v2) ? 0.f : v2;
      s.a2 = is_nan(a2) ? 0.f : a2;
    }
    return s;
  }
};

constexpr std::uint32_t kHealthy = 0xffffffffu;

// i for an unhealthy particle, kHealthy otherwise; the minimum is the CPU's "first" particle.
template <int D>
struct HealthPass {
  // Only the rest densities of PhysicsParams: this functor runs inside Thrust's reduction kernels,
  // which copy it to local memory per thread (the whole PhysicsParams made that 2.5 KB).
  using RestDensity = decltype(TaitEos{}.rest_density);
  ParticleView<D> P;
  double limit;
  RestDensity rest[kMaxMaterials];
  int wall_material;
  static HealthPass make(const ParticleView<D>& P, const PhysicsParams& prm, double limit) {
    HealthPass h{P, limit, {}, prm.wall_material};
    for (int m = 0; m < kMaxMaterials; ++m) h.rest[m] = prm.materials[m].eos.rest_density;
    return h;
  }
  TURBID_HD bool healthy(std::uint32_t i) const {
    for (int k = 0; k < D; ++k)
      if (!finite(P.position[i][k]) || !finite(P.velocity[i][k]) || !finite(P.acceleration[i][k])) return false;
    // Walls and structures hold density in the wall material's units, buffers in their own.
    const bool own = P.kind[i] == std::uint8_t(Kind::fluid) || P.kind[i] == std::uint8_t(Kind::buffer);
    const int m = own ? P.material[i] : wall_material;
    const double ratio = double(P.density[i]) / rest[m] - 1.0;
    return finite(ratio) && (ratio < 0 ? -ratio : ratio) <= limit;
  }
  TURBID_HD std::uint32_t operator()(std::uint32_t i) const { return healthy(i) ? kHealthy : i; }
};

// The health check, the speeds and the particle count in one reduction (Backend::check_step).
// After a neighbour update inside the step the count is the sort's kept particles, read on the
// device (`kept`, else all n): the particles past it left the domain and are not reported on.
// With a drift's put-backs to report, the same reduction sums their booked force and power over
// walls and structures (WallConstraintLoadPass; the fields follow the sort).
struct StepReport {
  SpeedPair speed;
  std::uint32_t bad;   // the first unhealthy particle, kHealthy if none
  std::uint32_t kept;  // particles in the domain
  double load[4];      // sum of constraint_force (D components) and constraint_power
};
struct CombineStepReport {
  TURBID_HD StepReport operator()(const StepReport& a, const StepReport& b) const {
    return {MaxSpeedPair{}(a.speed, b.speed),
            a.bad < b.bad ? a.bad : b.bad,
            a.kept < b.kept ? b.kept : a.kept,
            {a.load[0] + b.load[0], a.load[1] + b.load[1], a.load[2] + b.load[2], a.load[3] + b.load[3]}};
  }
};
template <int D>
struct StepReportPass {
  SpeedPass<D> speed;
  HealthPass<D> health;
  const std::uint32_t* kept;  // nullptr: all n are kept
  std::uint32_t n;
  bool constraint;            // sum the booked put-backs too
  TURBID_HD StepReport operator()(std::uint32_t i) const {
    const std::uint32_t k = kept ? *kept : n;
    if (i >= k) return {{0.f, 0.f}, kHealthy, k, {0, 0, 0, 0}};
    StepReport r{speed(i), health(i), k, {0, 0, 0, 0}};
    const ParticleView<D>& P = speed.P;
    if (constraint && WallConstraintPass<D>::boundary(P.kind[i])) {
      for (int a = 0; a < D; ++a) r.load[a] = double(P.constraint_force[i][a]);
      r.load[3] = double(P.constraint_power[i]);
    }
    return r;
  }
};

// Neighbours within the support 2h of each particle (itself excluded), as the CPU counts them.
template <int D>
struct PairCountPass {
  ParticleView<D> P;
  GridView<D> G;
  Real h;
  TURBID_HD unsigned long long operator()(std::uint32_t i) const {
    int c[D] = {};
    G.cell_of(P.position[i], c);
    unsigned long long local = 0;
    const Vec<D> xi = P.position[i];
    G.for_each_neighbour_range(c, [&](std::uint32_t b, std::uint32_t e, const Vec<D>& offset) {
      for (std::uint32_t j = b; j < e; ++j)
        if (j != i && norm2(xi - P.position[j] - offset) < Real(4) * h * h) ++local;
    });
    return local;
  }
};

// What each particle adds to a split's counts (SplitTally::of, the CPU's rule); summed by Thrust.
struct SplitTallyPass {
  const std::uint32_t* id;
  const Real* h;
  const std::uint64_t* first_slot;
  const std::uint32_t* new_slots;
  std::uint64_t room;
  TURBID_HD SplitTally operator()(std::uint32_t i) const {
    return SplitTally::of(id[i], h[i], first_slot[i], new_slots[i], room);
  }
};

// ---- open boundaries (sph/open_boundary.hpp's rule, on the device) ----------------------------

// Counts of one update, and the largest id (new buffer particles take the ids after it).
struct ZoneTally {
  std::uint32_t inflow, outflow, to_outlet, max_id;
};
struct CombineZoneTally {
  TURBID_HD ZoneTally operator()(const ZoneTally& a, const ZoneTally& b) const {
    return {a.inflow + b.inflow, a.outflow + b.outflow, a.to_outlet + b.to_outlet, a.max_id < b.max_id ? b.max_id : a.max_id};
  }
};

// Applies zone_crossing to particle i in place (kind, material, zone) and records what happened:
// crossing[i], spawn[i] (1: a new buffer particle is copied from it) and keep[i] (0: removed).
struct ZoneCrossingPass {
  const Real* x;  // d per particle
  int d;
  std::uint8_t* kind;
  std::uint8_t* material;
  std::uint8_t* zone;
  PhysicsParams prm;
  std::uint8_t* crossing;
  std::uint32_t* spawn;
  std::uint32_t* keep;
  TURBID_HD void operator()(std::uint32_t i) const {
    std::uint8_t outlet = kNoZone;
    const ZoneCrossing c = zone_crossing(x + std::size_t(i) * std::size_t(d), d, kind[i], zone[i], prm, &outlet);
    if (c == ZoneCrossing::inflow) {
      kind[i] = std::uint8_t(Kind::fluid);
      material[i] = prm.zones[zone[i]].material;
    } else if (c == ZoneCrossing::to_outlet) {
      kind[i] = std::uint8_t(Kind::buffer);
      zone[i] = outlet;
    }
    crossing[i] = std::uint8_t(c);
    spawn[i] = c == ZoneCrossing::inflow ? 1u : 0u;
    keep[i] = c == ZoneCrossing::outflow ? 0u : 1u;
  }
};

struct ZoneTallyPass {
  const std::uint8_t* crossing;
  const std::uint32_t* id;
  TURBID_HD ZoneTally operator()(std::uint32_t i) const {
    const auto c = ZoneCrossing(crossing[i]);
    return {c == ZoneCrossing::inflow ? 1u : 0u, c == ZoneCrossing::outflow ? 1u : 0u, c == ZoneCrossing::to_outlet ? 1u : 0u,
            id[i]};
  }
};

// The new buffer particle of an inflow at i: a copy at n + slot[i], one zone thickness upstream,
// as update_open_boundaries appends them (index order, ids from next_id).
struct ZoneSpawnPass {
  SplitFieldTable fields;
  Real* x;
  int d;
  std::uint8_t* kind;
  std::uint8_t* zone;
  std::uint32_t* id;
  const std::uint8_t* crossing;
  const std::uint32_t* slot;
  PhysicsParams prm;
  std::uint32_t n;
  std::uint32_t next_id;
  TURBID_HD void operator()(std::uint32_t i) const {
    if (ZoneCrossing(crossing[i]) != ZoneCrossing::inflow) return;
    const std::size_t to = std::size_t(n) + slot[i];
    fields.copy(i, to);
    const BufferZone& z = prm.zones[zone[i]];
    x[to * std::size_t(d) + std::size_t(z.axis)] -= z.sign * z.thickness;
    kind[to] = std::uint8_t(Kind::buffer);
    id[to] = next_id + slot[i];
    zone[i] = kNoZone;  // the particle that became fluid
  }
};

// ---- structure loads (sph/body_loads.hpp's sums, on the device) --------------------------------

struct DeviceLoad {
  double f[3], t[3];
};
struct SumDeviceLoad {
  TURBID_HD DeviceLoad operator()(const DeviceLoad& a, const DeviceLoad& b) const {
    DeviceLoad r;
    for (int k = 0; k < 3; ++k) {
      r.f[k] = a.f[k] + b.f[k];
      r.t[k] = a.t[k] + b.t[k];
    }
    return r;
  }
};

struct NonZero {
  TURBID_HD bool operator()(std::uint32_t v) const { return v != 0; }
};

// 1 for a particle of some structure: the list the per-body sums run over.
struct OnBodyPred {
  const std::uint8_t* body;
  int body_count;
  TURBID_HD bool operator()(std::uint32_t i) const { return body[i] < body_count; }
};

// Force and torque about ref of particle list[k] if it belongs to body b (in double, as on the host).
template <int D>
struct BodyLoadPass {
  const Vec<D>* x;
  const Vec<D>* force;
  const std::uint8_t* body;
  const std::uint32_t* list;
  int b;
  double ref[3];
  TURBID_HD DeviceLoad operator()(std::uint32_t k) const {
    DeviceLoad L{{0, 0, 0}, {0, 0, 0}};
    const std::uint32_t i = list[k];
    if (body[i] != b) return L;
    double r[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a) {
      L.f[a] = force[i][a];
      r[a] = double(x[i][a]) - ref[a];
    }
    L.t[0] = r[1] * L.f[2] - r[2] * L.f[1];
    L.t[1] = r[2] * L.f[0] - r[0] * L.f[2];
    L.t[2] = r[0] * L.f[1] - r[1] * L.f[0];
    return L;
  }
};

// ---- the backend -----------------------------------------------------------------------------

class DeviceBackend final : public Backend {
 public:
  // `name`: "cuda" or "device-omp"; `threads`: the OpenMP threads that run the passes in the
  // OpenMP build (0: OpenMP's default), ignored by the CUDA build.
  DeviceBackend(std::string name, int threads) : name_(std::move(name)), threads_(threads) {}

  std::string name() const override { return name_; }
  int threads() const override { return host_threads(threads_); }

  void bind(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain) override {
    store_ = &store;
    ids_ = ids;
    params_ = params;
    layout_ = GridLayout::make(domain, params.dimensions, 2.0 * params.smoothing_length * max_h_ratio());
    cell_count_ = layout_.cell_count;
    for (int k = 0; k < params.dimensions; ++k) domain_max_[k] = domain.max[k];
    use_host_threads(threads_);
    cell_start_.allocate((cell_count_ + 1) * sizeof(std::uint32_t));
    cell_start_.clear();
    fluid_before_.allocate((cell_count_ + 1) * sizeof(std::uint32_t));
    fluid_before_.clear();
    put_backs_.allocate(2 * sizeof(unsigned long long));
    put_backs_.clear();
    constraint_dt_ = 0;
    constraint_totals_ = {};
    allocate_fields();
    upload();
  }

  // The sort leaves the count of particles still in the domain on the device (count_pending_):
  // update_neighbours reads it at once, update_neighbours_in_step leaves it to the step's one
  // reduction (check_step). Until then n_ is an upper bound: the particles past the kept ones left
  // the domain, sit in no cell (no pair sees them) and the force pass and the kick, which write
  // only each particle's own values, may run over them. Every other entry point settles first.
  std::size_t update_neighbours() override {
    sort();
    return settle_now();
  }
  std::size_t update_neighbours_in_step() override {
    sort();
    return 0;
  }

  void compute_density_rate() override {
    settle();
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
    settle();
    const Real wall_rho_min = params_.materials[params_.wall_material].eos.no_tension_density();
    if (params_.dimensions == 2) launch("DriftPass<2>", n_, DriftPass<2>{view<2>(), Real(dt), wall_rho_min, params_});
    else launch("DriftPass<3>", n_, DriftPass<3>{view<3>(), Real(dt), wall_rho_min, params_});
    if (!params_.wall_constraint) return;
    auto* put_backs = put_backs_.as<unsigned long long>();
    launch("MarkPutBacksPass", 1, MarkPutBacksPass{put_backs});
    const Real inv_dt = Real(1) / Real(dt);
    if (params_.dimensions == 2) {
      launch("WallConstraintPass<2>", n_, WallConstraintPass<2>{view<2>(), grid<2>(), params_, NeighbourList{}, put_backs});
      launch("WallConstraintLoadPass<2>", n_, WallConstraintLoadPass<2>{view<2>(), grid<2>(), params_, inv_dt, put_backs});
    } else {
      launch("WallConstraintPass<3>", n_, WallConstraintPass<3>{view<3>(), grid<3>(), params_, NeighbourList{}, put_backs});
      launch("WallConstraintLoadPass<3>", n_, WallConstraintLoadPass<3>{view<3>(), grid<3>(), params_, inv_dt, put_backs});
    }
    // Summed into the totals by the step's check (one reduction: no wait here).
    constraint_dt_ = double(Real(dt));
  }

  WallConstraintTotals wall_constraint_totals() override { return constraint_totals_; }
  void restore_wall_constraint_totals(const WallConstraintTotals& t) override { constraint_totals_ = t; }

  std::uint64_t wall_put_backs() override {
    unsigned long long n = 0;
    if (put_backs_.get()) to_host(&n, put_backs_.get(), sizeof(n));
    return n;
  }

  // Conversions at open boundaries on the device, with update_open_boundaries' rule and order:
  // the crossing pass, one reduction (the counts and the largest id: the only copy back), an
  // exclusive scan of the inflows for the new particles' slots, their copies, and a stable
  // compaction of the kept particles when some left. The buffers grow (on the device) when the
  // new particles do not fit; the host store follows the count, its data at sync_to_host().
  OpenBoundaryCounts update_open_boundaries() override {
    OpenBoundaryCounts c;
    settle();
    if (params_.zone_count == 0 || n_ == 0) return c;
    const std::uint32_t n = n_;
    zone_crossing_.ensure(capacity_);
    auto field = [&](FieldId f) { return fields_[std::size_t(f)].get(); };
    launch("ZoneCrossingPass", n,
           ZoneCrossingPass{static_cast<const Real*>(field(ids_.position)), params_.dimensions,
                            static_cast<std::uint8_t*>(field(ids_.kind)), static_cast<std::uint8_t*>(field(ids_.material)),
                            static_cast<std::uint8_t*>(field(ids_.zone)), params_, zone_crossing_.as<std::uint8_t>(),
                            keys_.as<std::uint32_t>(), order_.as<std::uint32_t>()});
    const ZoneTally t = reduce(n, ZoneTallyPass{zone_crossing_.as<std::uint8_t>(), static_cast<const std::uint32_t*>(field(ids_.id))},
                               ZoneTally{0, 0, 0, 0}, CombineZoneTally{});
    c.inflow = t.inflow;
    c.outflow = t.outflow;
    c.to_outlet = t.to_outlet;
    std::uint32_t total = n;
    if (t.inflow > 0) {
      if (std::size_t(n) + t.inflow > capacity_) grow(std::max<std::size_t>(2 * capacity_, std::size_t(n) + t.inflow));
      // spawn flags (keys_) -> slots: scanned in place.
      std::uint32_t* slot = keys_.as<std::uint32_t>();
      thrust::exclusive_scan(async_policy(cache_), slot, slot + n, slot);
      const int on_device = std::min(store_->field_count(), int(fields_.size()));
      const SplitFieldTable table = split_field_table(*store_, on_device, [&](FieldId f) { return field(f); });
      launch("ZoneSpawnPass", n,
             ZoneSpawnPass{table, static_cast<Real*>(field(ids_.position)), params_.dimensions,
                           static_cast<std::uint8_t*>(field(ids_.kind)), static_cast<std::uint8_t*>(field(ids_.zone)),
                           static_cast<std::uint32_t*>(field(ids_.id)), zone_crossing_.as<std::uint8_t>(), slot, params_, n,
                           t.max_id + 1});
      total = n + t.inflow;
      // The new particles are kept.
      thrust::fill(async_policy(cache_), order_.as<std::uint32_t>() + n, order_.as<std::uint32_t>() + total, 1u);
    }
    if (t.outflow > 0) {
      // keep flags (order_) -> the kept particles' indices, in order (keys_), then every field gathered.
      const std::uint32_t* keep = order_.as<std::uint32_t>();
      std::uint32_t* kept_index = keys_.as<std::uint32_t>();
      std::uint32_t* end = thrust::copy_if(policy(cache_), thrust::counting_iterator<std::uint32_t>(0),
                                           thrust::counting_iterator<std::uint32_t>(total), keep, kept_index,
                                           NonZero{});
      ++waits_;  // the count comes back
      const std::uint32_t kept = std::uint32_t(end - kept_index);
      for (int f = 0; f < int(fields_.size()); ++f) gather_field(f, kept_index, kept);
      total = kept;
    }
    n_ = total;
    store_->resize(n_);  // the host's data follow at sync_to_host()
    return c;
  }

  StepStats stats() override {
    settle();
    return params_.dimensions == 2 ? stats_impl<2>() : stats_impl<3>();
  }

  std::optional<HealthIssue> check_health(double limit) override {
    settle();
    return params_.dimensions == 2 ? health_impl<2>(limit) : health_impl<3>(limit);
  }

  StepCheck check_step(double limit) override {
    return params_.dimensions == 2 ? check_step_impl<2>(limit) : check_step_impl<3>(limit);
  }

  void sync_to_host() override {
    if (store_ == nullptr) return;
    settle();
    store_->resize(n_);
    // A field registered on the host after bind() lives on the host until sync_from_host().
    const int on_device = std::min(store_->field_count(), int(fields_.size()));
    for (int f = 0; f < on_device; ++f) {
      const std::size_t bytes = n_ * store_->field_bytes(f);
      to_host(store_->raw(f), fields_[std::size_t(f)].get(), bytes);
    }
  }

  void sync_from_host() override {
    if (store_ == nullptr) return;
    // The host may have grown the store or registered fields since bind().
    if (store_->capacity() > capacity_ || store_->size() > capacity_ || std::size_t(store_->field_count()) != fields_.size())
      allocate_fields();
    upload();
  }

  std::uint64_t host_device_bytes() const override { return moved_; }
  std::uint64_t host_waits() const override { return waits_; }
  std::size_t temporary_allocations() const override { return cache_.allocations(); }
  std::size_t device_bytes() const override {
    std::size_t b = cache_.bytes();
    for (const DeviceBuffer& f : fields_) b += f.bytes();
    for (const DeviceBuffer* x : {&scratch_, &cell_start_, &keys_, &order_, &fluid_before_, &put_backs_, &split_slots_,
                                  &split_rule_, &split_first_, &relax_zone_, &relax_shift_, &placements_, &zone_crossing_,
                                  &body_list_, &viscous_work_, &full_stress_work_})
      b += x->bytes();
    return b;
  }

  std::size_t pair_count() override {
    settle();
    return params_.dimensions == 2 ? count_pairs<2>() : count_pairs<3>();
  }

  // The per-particle forces are summed on the host (few structure particles; double precision).
  std::vector<BodyLoad> body_loads(const std::vector<std::array<double, 3>>& reference) override {
    if (params_.body_count == 0 || ids_.structure_force < 0) return std::vector<BodyLoad>(reference.size());
    settle();
    if (params_.dimensions == 2) return loads_impl<2>(reference);
    return loads_impl<3>(reference);
  }

  // Moving structures: the bodies' states (a few hundred bytes) go up each call and the shared
  // placement pass (sph/body_motion.hpp) moves their particles on the device.
  bool supports_moving_bodies() const override { return true; }
  void place_bodies(const std::vector<BodyPlacement>& bodies, bool move) override {
    if (ids_.body_offset < 0) throw std::logic_error("place_bodies: the store has no body_offset field");
    settle();
    if (bodies.empty() || n_ == 0) return;
    placements_.ensure(bodies.size() * sizeof(BodyPlacement));
    to_device(placements_.get(), bodies.data(), bodies.size() * sizeof(BodyPlacement));
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

  // The implicit viscous solve (sph/implicit_viscosity_solve.hpp, the CPU's algorithm): its passes
  // launched here, its dot products Thrust reductions in double (one value back each).
  bool supports_implicit_viscosity() const override { return true; }
  ViscousSolve solve_viscosity(double dt, double share, bool first_half) override {
    settle();
    return params_.dimensions == 2 ? viscosity_impl<2>(Real(dt), Real(share), first_half)
                                   : viscosity_impl<3>(Real(dt), Real(share), first_half);
  }

  template <int D>
  struct Exec {
    DeviceBackend* backend;
    template <class F>
    void run(std::uint32_t n, const F& f) {
      launch_pairs<D>("implicit viscosity pass", n, f);
    }
    template <class F>
    double sum(std::uint32_t n, const F& f) {
      return backend->reduce(n, f, 0.0, thrust::plus<double>());
    }
  };

  template <int D>
  ViscousSolve viscosity_impl(Real dt, Real share, bool first_half) {
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    // Work arrays for the whole capacity, from the first solve (scenes without it hold none).
    const std::size_t cap = capacity_;
    viscous_work_.ensure(8 * cap * sizeof(Vec<D>));
    Mat<D>* fs = nullptr;
    Real* carrier = nullptr;  // after the tensors, in the same buffer
    if (params_.full_stress) {
      full_stress_work_.ensure(3 * cap * sizeof(Mat<D>) + cap * sizeof(Real));
      fs = full_stress_work_.as<Mat<D>>();
      carrier = reinterpret_cast<Real*>(fs + 3 * cap);
    }
    const ViscousWork<D> w = ViscousWork<D>::over(viscous_work_.as<Vec<D>>(), fs, carrier, cap);
    ViscousSolve out;
    Exec<D> ex{this};
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      out = solve_implicit_viscosity<D, K, U>(ex, P, G, NeighbourList{}, params_, dt, share, first_half, w);
    });
    return out;
  }

  bool supports_splitting() const override { return true; }
  SplitCounts split(const SplitParams& rules) override {
    settle();
    return params_.dimensions == 2 ? split_impl<2>(rules) : split_impl<3>(rules);
  }
  std::size_t relax_split(const SplitParams& rules) override {
    settle();
    return params_.dimensions == 2 ? relax_impl<2>(rules) : relax_impl<3>(rules);
  }

  // Summed on the device (sph/body_loads.hpp's sums in double, in another order): the indices of
  // the structures' particles are compacted once per call, then one reduction per structure over
  // them brings back its force and torque (48 bytes a structure).
  template <int D>
  std::vector<BodyLoad> loads_impl(const std::vector<std::array<double, 3>>& reference) {
    std::vector<BodyLoad> out(reference.size());
    if (n_ == 0 || reference.empty()) return out;
    auto field = [&](FieldId f) { return fields_[std::size_t(f)].get(); };
    const auto* body = static_cast<const std::uint8_t*>(field(ids_.body));
    body_list_.ensure(capacity_ * sizeof(std::uint32_t));
    std::uint32_t* list = body_list_.as<std::uint32_t>();
    std::uint32_t* end = thrust::copy_if(policy(cache_), thrust::counting_iterator<std::uint32_t>(0),
                                         thrust::counting_iterator<std::uint32_t>(n_), list,
                                         OnBodyPred{body, int(reference.size())});
    ++waits_;  // the count comes back
    const std::uint32_t count = std::uint32_t(end - list);
    moved_ += sizeof(std::uint32_t);  // the count
    for (std::size_t b = 0; b < reference.size(); ++b) {
      BodyLoadPass<D> pass{static_cast<const Vec<D>*>(field(ids_.position)),
                           static_cast<const Vec<D>*>(field(ids_.structure_force)), body, list, int(b), {0, 0, 0}};
      for (int a = 0; a < 3; ++a) pass.ref[a] = reference[b][a];
      const DeviceLoad L = reduce(count, pass, DeviceLoad{{0, 0, 0}, {0, 0, 0}}, SumDeviceLoad{});
      for (int a = 0; a < 3; ++a) {
        out[b].force[a] = L.f[a];
        out[b].torque[a] = L.t[a];
      }
    }
    return out;
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
    // One more than the capacity: the fluid count scan after the sort (fluid_before) reuses keys_
    // and order_ for n + 1 entries.
    for (DeviceBuffer* b : {&keys_, &order_}) b->allocate((capacity_ + 1) * sizeof(std::uint32_t));
  }

  // Grows every per-particle buffer to `capacity` particles, keeping its contents.
  void grow(std::size_t capacity) {
    auto regrow = [&](DeviceBuffer& b, std::size_t bytes) {
      DeviceBuffer bigger(bytes);
      if (b.get() != nullptr) copy_on_device(bigger.get(), b.get(), std::min(b.bytes(), bytes));
      b = std::move(bigger);
    };
    std::size_t max_bytes = 1;
    for (int f = 0; f < int(fields_.size()); ++f) {
      const std::size_t fb = store_->field_bytes(f);
      max_bytes = std::max(max_bytes, fb);
      regrow(fields_[std::size_t(f)], capacity * fb);
    }
    scratch_.allocate(capacity * max_bytes);
    for (DeviceBuffer* b : {&keys_, &order_}) regrow(*b, (capacity + 1) * sizeof(std::uint32_t));
    if (zone_crossing_.get() != nullptr) regrow(zone_crossing_, capacity);
    capacity_ = capacity;
  }

  void upload() {
    const ParticleStore& s = *store_;
    n_ = std::uint32_t(s.size());
    count_pending_ = false;
    for (int f = 0; f < s.field_count(); ++f) {
      const std::size_t bytes = std::size_t(n_) * s.field_bytes(f);
      to_device(fields_[std::size_t(f)].get(), s.raw(f), bytes);
    }
  }

  // Copies between the host and the device, counted (bytes_moved()).
  // Both block the host (cudaMemcpy from or to pageable memory).
  void to_device(void* dst, const void* src, std::size_t bytes) {
    copy_to_device(dst, src, bytes);
    moved_ += bytes;
    ++waits_;
  }
  void to_host(void* dst, const void* src, std::size_t bytes) {
    copy_to_host(dst, src, bytes);
    moved_ += bytes;
    ++waits_;
  }
  // The kept count of the last sort, if it is still on the device: read it (one wait) and make it
  // the particle count. Returns the particles the sort removed.
  std::size_t settle_now() {
    if (!count_pending_) return 0;
    return take_count(read_one(kept_on_device()));
  }
  std::size_t take_count(std::uint32_t kept) {
    count_pending_ = false;
    const std::size_t removed = n_ - kept;
    n_ = kept;
    // Keep the host's count in step (shrinking only moves the size); the data follow at sync_to_host().
    if (store_->size() > kept) store_->resize(kept);
    return removed;
  }
  // As settle_now, for entry points that need the exact count: the removed particles are reported
  // at the next check_step.
  void settle() { unreported_removed_ += settle_now(); }
  // Where the sort leaves its kept count: cell_start[cell_count], the keys below "outside".
  const std::uint32_t* kept_on_device() const { return cell_start_.as<std::uint32_t>() + cell_count_; }
  // One value of type T at p on the device.
  template <class T>
  T read_one(const T* p) {
    T v{};
    to_host(&v, p, sizeof(T));
    return v;
  }
  // The reduction of f(i) over [0, n) with op from init (one value back to the host).
  template <class T, class F, class Op>
  T reduce(std::uint32_t n, const F& f, T init, Op op) {
    if (n == 0) return init;
    const T v = thrust::transform_reduce(policy(cache_), thrust::counting_iterator<std::uint32_t>(0),
                                         thrust::counting_iterator<std::uint32_t>(n), f, init, op);
    moved_ += sizeof(T);
    ++waits_;
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
    if (ids_.viscous_load >= 0) v.viscous_load = static_cast<Vec<D>*>(field(ids_.viscous_load));
    if (ids_.viscous_pending >= 0) v.viscous_pending = static_cast<Vec<D>*>(field(ids_.viscous_pending));
    if (ids_.put_back_impulse >= 0) v.put_back_impulse = static_cast<Vec<D>*>(field(ids_.put_back_impulse));
    if (ids_.put_back_from >= 0) v.put_back_from = static_cast<std::uint32_t*>(field(ids_.put_back_from));
    if (ids_.constraint_force >= 0) v.constraint_force = static_cast<Vec<D>*>(field(ids_.constraint_force));
    if (ids_.constraint_power >= 0) v.constraint_power = static_cast<Real*>(field(ids_.constraint_power));
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
    if (fb % 4 == 0)
      launch("GatherWords<u32>", total / 4,
             GatherWords<std::uint32_t>{buf.as<std::uint32_t>(), scratch_.as<std::uint32_t>(), order, fb / 4});
    else
      launch("GatherWords<u8>", total, GatherWords<std::uint8_t>{buf.as<std::uint8_t>(), scratch_.as<std::uint8_t>(), order, fb});
    // The scratch buffer has the size of the widest field; swap with fields of that size, copy the others.
    if (buf.bytes() == scratch_.bytes()) buf.swap(scratch_);
    else copy_on_device(buf.get(), scratch_.get(), total);
  }

  // A neighbour update after the last one's count is settled; its own count stays on the device.
  void sort() {
    settle();
    if (params_.dimensions == 2) sort_by_cell<2>();
    else sort_by_cell<3>();
  }

  // Sorts by cell key; the particles outside the domain go last, past cell_start[cell_count] (the
  // kept count, left on the device: count_pending_).
  template <int D>
  void sort_by_cell() {
    const std::uint32_t n = n_;
    const GridView<D> g = grid<D>();
    std::uint32_t* keys = keys_.as<std::uint32_t>();
    std::uint32_t* order = order_.as<std::uint32_t>();
    const ParticleView<D> P = view<D>();
    KeysPass<D> key_pass{g, {}, P.position, keys, order, std::uint32_t(cell_count_)};
    for (int k = 0; k < D; ++k) key_pass.upper[k] = Real(domain_max_[k]);
    launch("KeysPass", n, key_pass);
    if (n > 0) {
      // A stable sort: inside a cell particles keep their order, as in the CPU counting sort.
      thrust::stable_sort_by_key(async_policy(cache_), keys, keys + n, order);
      for (int f = 0; f < int(fields_.size()); ++f)
        if (store_->desc(f).follows_sort) gather_field(f, order, n);
    }
    launch("CellStartPass", std::uint32_t(cell_count_ + 1), CellStartPass{keys, n, cell_start_.as<std::uint32_t>()});
    count_pending_ = true;
    // fluid_before, so that wall particles with no fluid in their 3^d cells skip the search (the
    // CPU's shortcut, same results): flags of the kept particles (0 after them and at n), scanned.
    const std::uint8_t* kind = fields_[std::size_t(ids_.kind)].as<std::uint8_t>();
    std::uint32_t* flags = order;  // the order is spent once the fields are gathered
    launch("FluidFlagPass", n + 1, FluidFlagPass{kind, kept_on_device(), flags});
    thrust::exclusive_scan(async_policy(cache_), flags, flags + n + 1, keys);
    launch("FluidBeforePass", std::uint32_t(cell_count_ + 1),
           FluidBeforePass{cell_start_.as<std::uint32_t>(), keys, fluid_before_.as<std::uint32_t>()});
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
      if (params_.body_count > 0 || params_.wall_loads)
        launch("StructureForcePass", P.count, StructureForcePass<D, K, U>{P, G, params_});
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
    std::uint32_t* slots = split_slots_.as<std::uint32_t>();
    std::int8_t* rule_of = split_rule_.as<std::int8_t>();
    std::uint64_t* first = split_first_.as<std::uint64_t>();
    if (ids_.split_fresh >= 0)  // the last split's daughters are old now
      clear_device(fields_[std::size_t(ids_.split_fresh)].get(), n);
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      launch("SplitFlagPass", n, SplitFlagPass<D, K, U>{P, G, params_, rules, slots, rule_of});
    });
    // Accumulated in 64 bits (the initial value's and the operator's type), like the CPU's
    // std::exclusive_scan.
    thrust::exclusive_scan(async_policy(cache_), slots, slots + n, first, std::uint64_t(0), thrust::plus<std::uint64_t>());
    // The store's capacity, as on the CPU (the device buffers hold at least as much).
    const std::uint64_t capacity = std::min<std::uint64_t>(capacity_, store_->capacity());
    const std::uint64_t room = capacity > n ? capacity - n : 0;
    std::uint32_t* id = fields_[std::size_t(ids_.id)].as<std::uint32_t>();
    const SplitTally t =
        reduce(n, SplitTallyPass{id, P.smoothing_length, first, slots, room}, SplitTally::none(), CombineSplitTally{});
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
  // Thrust reduction in double (its last bits may differ from the CPU's ordered sum).
  template <int D>
  std::size_t relax_impl(const SplitParams& rules) {
    if (ids_.split_fresh < 0 || rules.relax_iterations <= 0 || n_ == 0) return 0;
    const std::uint32_t n = n_;
    relax_zone_.ensure(capacity_ * sizeof(std::uint8_t));
    relax_shift_.ensure(capacity_ * sizeof(Vec<D>));
    std::uint8_t* zone = relax_zone_.as<std::uint8_t>();
    Vec<D>* shift = relax_shift_.as<Vec<D>>();
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    std::size_t zone_count = 0;
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      launch("SplitRelaxZonePass", n, SplitRelaxZonePass<D, K, U>{P, G, params_, zone});
      for (int it = 0; it < rules.relax_iterations; ++it) {
        launch("SplitRelaxShiftPass", n, SplitRelaxShiftPass<D, K, U>{P, G, params_, zone, shift, rules.relax_strength});
        const RelaxMoment m = reduce(n, RelaxMomentPass<D>{zone, P.mass, shift}, RelaxMoment{0, 0, {0, 0, 0}}, SumRelaxMoment{});
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
    const SpeedPair s = reduce(n, SpeedPass<D>{view<D>()}, SpeedPair{0.f, 0.f}, MaxSpeedPair{});
    return {std::sqrt(double(s.v2)), std::sqrt(double(s.a2))};
  }

  template <int D>
  std::optional<HealthIssue> health_impl(double limit) {
    const std::uint32_t n = n_;
    if (n == 0) return std::nullopt;
    const std::uint32_t i = reduce(n, HealthPass<D>::make(view<D>(), params_, limit), kHealthy, thrust::minimum<std::uint32_t>());
    if (i == kHealthy) return std::nullopt;
    return describe_unhealthy<D>(i);
  }

  // One reduction, the step's one wait for the device: health, speeds and, after a neighbour update
  // inside the step, the count of particles still in the domain.
  template <int D>
  StepCheck check_step_impl(double limit) {
    StepCheck c;
    if (n_ == 0) {
      count_pending_ = false;
      c.removed = std::exchange(unreported_removed_, 0);
      return c;
    }
    const ParticleView<D> P = view<D>();
    const std::uint32_t* kept = count_pending_ ? kept_on_device() : nullptr;
    const bool constraint = constraint_dt_ > 0;
    const StepReport r =
        reduce(n_, StepReportPass<D>{SpeedPass<D>{P}, HealthPass<D>::make(P, params_, limit), kept, n_, constraint},
               StepReport{{0.f, 0.f}, kHealthy, 0u, {0, 0, 0, 0}}, CombineStepReport{});
    if (constraint) {
      for (int a = 0; a < D; ++a) constraint_totals_.impulse[a] += constraint_dt_ * r.load[a];
      constraint_totals_.energy += constraint_dt_ * r.load[3];
      constraint_dt_ = 0;  // a drift's put-backs are counted once (a split's check comes again)
    }
    if (count_pending_) unreported_removed_ += take_count(r.kept);
    c.removed = std::exchange(unreported_removed_, 0);
    if (r.bad != kHealthy) c.issue = describe_unhealthy<D>(r.bad);
    else c.stats = {std::sqrt(double(r.speed.v2)), std::sqrt(double(r.speed.a2))};
    return c;
  }

  template <int D>
  HealthIssue describe_unhealthy(std::uint32_t i) {
    // Copy the one particle down and describe it exactly as the CPU backend does.
    const ParticleView<D> P = view<D>();
    const Vec<D> x = read_one(P.position + i), v = read_one(P.velocity + i), a = read_one(P.acceleration + i);
    const Real rho = read_one(P.density + i);
    const std::uint32_t id = read_one(fields_[std::size_t(ids_.id)].as<std::uint32_t>() + i);
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
    return std::size_t(reduce(n, PairCountPass<D>{view<D>(), grid<D>(), params_.smoothing_length}, 0ull,
                              thrust::plus<unsigned long long>()));
  }

  std::string name_;
  int threads_ = 0;
  ParticleStore* store_ = nullptr;
  FieldIds ids_;
  PhysicsParams params_;
  GridLayout layout_;
  double domain_max_[3] = {0, 0, 0};
  std::size_t cell_count_ = 1;
  std::uint32_t n_ = 0;       // particles on the device (an upper bound while count_pending_)
  bool count_pending_ = false;          // the last sort's kept count is on the device only
  std::size_t unreported_removed_ = 0;  // removed by sorts, not yet reported (check_step)
  std::size_t capacity_ = 0;  // particles the device buffers hold
  std::vector<DeviceBuffer> fields_;  // indexed by FieldId
  DeviceBuffer scratch_;              // gather target, capacity x widest field
  DeviceBuffer cell_start_, keys_, order_;
  DeviceBuffer fluid_before_;  // cell_count + 1: fluid particles in the cells before each cell
  DeviceBuffer put_backs_;     // WallConstraintPass's put-backs since bind; [1]: before this drift
  double constraint_dt_ = 0;   // > 0: the last drift's booked put-backs await the step's check
  WallConstraintTotals constraint_totals_;
  DeviceBuffer split_slots_, split_rule_, split_first_;  // splitting only, from the first split
  DeviceBuffer relax_zone_, relax_shift_;  // relaxation after a split, from the first one
  DeviceBuffer placements_;  // moving structures' BodyPlacement, one per structure
  DeviceBuffer zone_crossing_;  // open boundaries: ZoneCrossing per particle
  DeviceBuffer body_list_;      // moving structures: indices of structure particles (body_loads)
  DeviceBuffer viscous_work_, full_stress_work_;  // implicit viscosity: the solve's arrays, from the first solve
  CachingAllocator cache_;   // Thrust's temporary storage
  std::uint64_t moved_ = 0;  // bytes copied between host and device since construction
  std::uint64_t waits_ = 0;  // times the host waited for the device since construction (host_waits)
};

}  // namespace
}  // namespace TURBID_DEVICE_NS
}  // namespace turbid::sph
