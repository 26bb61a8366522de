// The CPU backend: OpenMP loops over the shared passes and a stable counting sort by cell.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "sph/backend.hpp"
#include "sph/backend/memory_plan.hpp"
#include "sph/boundary_passes.hpp"
#include "sph/dispatch.hpp"
#include "sph/implicit_viscosity.hpp"
#include "sph/implicit_viscosity_solve.hpp"
#include "sph/passes.hpp"
#include "sph/splitting.hpp"

namespace turbid::sph {
namespace {

// Below this many particles a loop runs on one thread: thread start-up and barriers would cost
// more than the work (and much more on a loaded machine).
constexpr std::int64_t kParallelThreshold = 4096;
// The passes (parallel_for) do tens to thousands of flops per particle, so they pay for their
// threads from far fewer particles: a 2D scene of 3,000 particles with a yield-stress material ran
// on one of two cores.
constexpr std::int64_t kPassParallelThreshold = 1024;

template <class F>
void parallel_for(std::uint32_t n_particles, const F& f) {
  const std::int64_t n = n_particles;
#pragma omp parallel for schedule(dynamic, 128) if (n >= kPassParallelThreshold)
  for (std::int64_t i = 0; i < n; ++i) f(std::uint32_t(i));
}

class CpuBackend final : public Backend {
 public:
  explicit CpuBackend(int threads) : threads_(threads > 0 ? threads : omp_get_max_threads()) {}

  std::string name() const override { return "cpu"; }
  int threads() const override { return threads_; }

  void bind(ParticleStore& store, const FieldIds& ids, const PhysicsParams& params, const Domain& domain) override {
    store_ = &store;
    ids_ = ids;
    params_ = params;
    put_backs_[0] = put_backs_[1] = 0;
    constraint_totals_ = {};
    omp_set_num_threads(threads_);
    layout_ = GridLayout::make(domain, params.dimensions, 2.0 * params.smoothing_length * max_h_ratio());
    cell_count_ = layout_.cell_count;
    for (int k = 0; k < params.dimensions; ++k) domain_max_[k] = domain.max[k];
    cell_start_.assign(cell_count_ + 1, 0);
  }

  std::size_t update_neighbours() override {
    list_valid_ = false;
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
    if (params_.dimensions == 2) kick_impl<2>(Real(half_dt));
    else kick_impl<3>(Real(half_dt));
  }

  void drift(double dt) override {
    soa_valid_ = false;
    if (params_.dimensions == 2) drift_impl<2>(Real(dt));
    else drift_impl<3>(Real(dt));
  }
  std::uint64_t wall_put_backs() override { return put_backs_[0]; }
  WallConstraintTotals wall_constraint_totals() override { return constraint_totals_; }
  void restore_wall_constraint_totals(const WallConstraintTotals& t) override { constraint_totals_ = t; }

  OpenBoundaryCounts update_open_boundaries() override {
    const OpenBoundaryCounts c = sph::update_open_boundaries(*store_, ids_, params_);
    list_valid_ = false;  // indices may have changed; the next sort rebuilds everything
    return c;
  }

  StepStats stats() override { return params_.dimensions == 2 ? stats_impl<2>() : stats_impl<3>(); }

  std::optional<HealthIssue> check_health(double limit) override {
    return params_.dimensions == 2 ? health_impl<2>(limit) : health_impl<3>(limit);
  }

  void prepare_resume() override {
    if (params_.dimensions == 2) record_list<2>();
    else record_list<3>();
  }

  template <int D>
  void record_list() {
    parallel_for(std::uint32_t(store_->size()), RecordNeighboursPass<D>{view<D>(), grid<D>(), params_, list(true)});
    list_valid_ = true;
  }

  void sync_to_host() override {}
  void sync_from_host() override {}

  std::size_t pair_count() override { return params_.dimensions == 2 ? count_pairs<2>() : count_pairs<3>(); }

  std::vector<BodyLoad> body_loads(const std::vector<std::array<double, 3>>& reference) override {
    if (params_.body_count == 0 || ids_.structure_force < 0) return std::vector<BodyLoad>(reference.size());
    if (params_.dimensions == 2) return loads_impl<2>(reference);
    return loads_impl<3>(reference);
  }

  bool supports_moving_bodies() const override { return true; }
  void place_bodies(const std::vector<BodyPlacement>& bodies, bool move) override {
    if (ids_.body_offset < 0) throw std::logic_error("place_bodies: the store has no body_offset field");
    if (params_.dimensions == 2) place_impl<2>(bodies, move);
    else place_impl<3>(bodies, move);
  }

  bool supports_splitting() const override { return true; }
  SplitCounts split(const SplitParams& rules) override {
    return params_.dimensions == 2 ? split_impl<2>(rules) : split_impl<3>(rules);
  }
  std::size_t relax_split(const SplitParams& rules) override {
    return params_.dimensions == 2 ? relax_impl<2>(rules) : relax_impl<3>(rules);
  }

  bool supports_implicit_viscosity() const override { return true; }
  ViscousSolve solve_viscosity(double dt, double share, bool first_half) override {
    return params_.dimensions == 2 ? viscosity_impl<2>(Real(dt), Real(share), first_half)
                                   : viscosity_impl<3>(Real(dt), Real(share), first_half);
  }

  // Sum over particles of f(i) in double, in blocks of fixed size added in order: the same bits
  // for any number of threads (an OpenMP reduction would combine partial sums per thread).
  template <class F>
  double fixed_order_sum(std::uint32_t n, const F& f) {
    constexpr std::uint32_t kBlock = 2048;
    const std::int64_t blocks = (std::int64_t(n) + kBlock - 1) / kBlock;
    block_sums_.assign(std::size_t(blocks), 0.0);
#pragma omp parallel for schedule(static) if (n >= kParallelThreshold)
    for (std::int64_t b = 0; b < blocks; ++b) {
      double s = 0;
      const std::uint32_t end = std::min<std::uint32_t>(n, std::uint32_t(b + 1) * kBlock);
      for (std::uint32_t i = std::uint32_t(b) * kBlock; i < end; ++i) s += f(i);
      block_sums_[std::size_t(b)] = s;
    }
    double total = 0;
    for (double s : block_sums_) total += s;
    return total;
  }

  // The implicit viscous solve (sph/implicit_viscosity_solve.hpp), with OpenMP loops and dot
  // products summed in blocks of fixed order.
  struct Exec {
    CpuBackend* backend;
    template <class F>
    void run(std::uint32_t n, const F& f) {
      parallel_for(n, f);
    }
    template <class F>
    double sum(std::uint32_t n, const F& f) {
      return backend->fixed_order_sum(n, f);
    }
  };

  template <int D>
  ViscousSolve viscosity_impl(Real dt, Real share, bool first_half) {
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    const std::uint32_t n = P.count;
    std::vector<Vec<D>>& cg = cg_vectors<D>();
    cg.resize(8 * std::size_t(n));
    Mat<D>* tensors = nullptr;
    if (params_.full_stress) {
      // The full-stress form (sph/full_stress.hpp): renormalisation, gradient and Q per particle.
      std::vector<Mat<D>>& fs = full_stress_tensors<D>();
      fs.resize(3 * std::size_t(n));
      tensors = fs.data();
      carrier_mu_.resize(n);
    }
    const ViscousWork<D> w = ViscousWork<D>::over(cg.data(), tensors, carrier_mu_.data(), n);
    const NeighbourList L = list(false);
    ViscousSolve out;
    Exec ex{this};
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      out = solve_implicit_viscosity<D, K, U>(ex, P, G, L, params_, dt, share, first_half, w);
    });
    return out;
  }

  template <int D>
  void place_impl(const std::vector<BodyPlacement>& bodies, bool move) {
    auto& s = *store_;
    PlaceBodiesPass<D> pass;
    pass.position = s.data<Vec<D>>(ids_.position);
    pass.velocity = s.data<Vec<D>>(ids_.velocity);
    pass.kind = s.data<std::uint8_t>(ids_.kind);
    pass.body = s.data<std::uint8_t>(ids_.body);
    pass.offset = s.data<Vec<D>>(ids_.body_offset);
    if (ids_.body_normal >= 0) {
      pass.boundary_normal = s.data<Vec<D>>(ids_.boundary_normal);
      pass.normal0 = s.data<Vec<D>>(ids_.body_normal);
    }
    pass.bodies = bodies.data();
    pass.body_count = int(bodies.size());
    pass.move = move;
    parallel_for(std::uint32_t(s.size()), pass);
    if (move) soa_valid_ = false;  // the sorted coordinate copy no longer matches the positions
  }

  template <int D>
  std::vector<BodyLoad> loads_impl(const std::vector<std::array<double, 3>>& reference) {
    const ParticleView<D> P = view<D>();
    return sum_body_loads<D>(P.position, P.structure_force, P.body, P.count, reference);
  }

 private:
  // Splitting in the four steps of sph/splitting.hpp. The scan and the tally of the capacity test
  // run on one thread (one add per particle); flags and writes in parallel, each mother writing
  // only her own slots, so the result is the same for every thread count.
  template <int D>
  SplitCounts split_impl(const SplitParams& rules) {
    SplitCounts c;
    const std::uint32_t n = std::uint32_t(store_->size());
    if (rules.rule_count == 0 || n == 0) return c;
    new_slots_.resize(n);
    rule_of_.resize(n);
    first_slot_.resize(n);
    {
      const ParticleView<D> P = view<D>();
      const GridView<D> G = grid<D>();
      dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
        using K = typename decltype(kernel_tag)::type;
        constexpr bool U = decltype(uniform_tag)::value;
        parallel_for(n, SplitFlagPass<D, K, U>{P, G, params_, rules, new_slots_.data(), rule_of_.data()});
      });
    }
    if (ids_.split_fresh >= 0) std::fill_n(store_->data<std::uint8_t>(ids_.split_fresh), n, std::uint8_t(0));
    std::exclusive_scan(new_slots_.begin(), new_slots_.end(), first_slot_.begin(), std::uint64_t(0));
    const std::uint64_t room = store_->capacity() - n;
    const Real* h = store_->data<Real>(ids_.smoothing_length);
    const std::uint32_t* id = store_->data<std::uint32_t>(ids_.id);
    SplitTally t = SplitTally::none();
    const CombineSplitTally combine;
    for (std::uint32_t i = 0; i < n; ++i) t = combine(t, SplitTally::of(id[i], h[i], first_slot_[i], new_slots_[i], room));
    c.splits = t.splits;
    c.refused = t.refused;
    if (c.splits == 0) return c;
    c.smallest_h = t.smallest_h;
    store_->resize(n + t.added);  // within the capacity: the arrays stay where they are
    const ParticleView<D> P = view<D>();
    const SplitFieldTable fields = split_field_table(*store_, store_->field_count(), [&](FieldId f) { return store_->raw(f); });
    parallel_for(n, SplitWritePass<D>{fields, P, DriftPass<D>{P, Real(0), Real(0), params_}, rules, new_slots_.data(),
                                      rule_of_.data(), first_slot_.data(), room, n, t.next_id,
                                      store_->data<std::uint32_t>(ids_.id)});
    c.daughters = t.added;
    list_valid_ = false;
    soa_valid_ = false;
    return c;
  }

  // The relaxation after a split (sph/splitting.hpp): zone, then Jacobi steps whose shifts read the
  // positions of the step before; the zone's mass-weighted mean shift summed in double on one thread
  // in index order (the same bits for every thread count). The grid is the one built after the
  // split: the zone moves by well under a cell (at most 0.05 h per step).
  template <int D>
  std::size_t relax_impl(const SplitParams& rules) {
    if (ids_.split_fresh < 0 || rules.relax_iterations <= 0) return 0;
    const std::uint32_t n = std::uint32_t(store_->size());
    relax_zone_.resize(n);
    relax_shift_.resize(std::size_t(n) * D);
    ParticleView<D> P = view<D>();
    P.position_soa = nullptr;  // positions move during the relaxation: read them, not the sorted copy
    const GridView<D> G = grid<D>();
    auto* shift = reinterpret_cast<Vec<D>*>(relax_shift_.data());
    std::size_t zone_count = 0;
    dispatch_kernel<D>(params_, [&](auto kernel_tag, auto uniform_tag) {
      using K = typename decltype(kernel_tag)::type;
      constexpr bool U = decltype(uniform_tag)::value;
      parallel_for(n, SplitRelaxZonePass<D, K, U>{P, G, params_, relax_zone_.data()});
      double zone_mass = 0;
      for (std::uint32_t i = 0; i < n; ++i)
        if (relax_zone_[i]) {
          ++zone_count;
          zone_mass += double(P.mass[i]);
        }
      if (zone_count == 0) return;
      for (int it = 0; it < rules.relax_iterations; ++it) {
        parallel_for(n, SplitRelaxShiftPass<D, K, U>{P, G, params_, relax_zone_.data(), shift, rules.relax_strength});
        double moment[D] = {};
        for (std::uint32_t i = 0; i < n; ++i)
          if (relax_zone_[i])
            for (int a = 0; a < D; ++a) moment[a] += double(P.mass[i]) * double(shift[i][a]);
        Vec<D> mean;
        for (int a = 0; a < D; ++a) mean[a] = Real(moment[a] / zone_mass);
        parallel_for(n, SplitRelaxApplyPass<D>{P, DriftPass<D>{P, Real(0), Real(0), params_}, relax_zone_.data(), shift, mean});
      }
    });
    list_valid_ = false;
    soa_valid_ = false;
    return zone_count;
  }

  double max_h_ratio() const {
    // Largest h present relative to the initial h (PhysicsParams::max_smoothing_length): the cells
    // must be at least the largest pair support 2 h_max, or pairs beyond one cell are never seen.
    // Splitting only halves h (ratio 1), but a store may carry h above the lattice's.
    const double h0 = params_.smoothing_length, h_max = params_.max_smoothing_length;
    return h_max > h0 ? h_max / h0 : 1.0;
  }

  template <int D>
  ParticleView<D> view() {
    ParticleView<D> v;
    auto& s = *store_;
    v.position = s.data<Vec<D>>(ids_.position);
    v.velocity = s.data<Vec<D>>(ids_.velocity);
    v.acceleration = s.data<Vec<D>>(ids_.acceleration);
    v.density = s.data<Real>(ids_.density);
    v.density_rate = s.data<Real>(ids_.density_rate);
    v.pressure = s.data<Real>(ids_.pressure);
    v.mass = s.data<Real>(ids_.mass);
    v.smoothing_length = s.data<Real>(ids_.smoothing_length);
    v.material = s.data<std::uint8_t>(ids_.material);
    v.kind = s.data<std::uint8_t>(ids_.kind);
    if (ids_.density_gradient >= 0) v.density_gradient = s.data<Vec<D>>(ids_.density_gradient);
    if (ids_.boundary_normal >= 0) v.boundary_normal = s.data<Vec<D>>(ids_.boundary_normal);
    if (ids_.structure_force >= 0) v.structure_force = s.data<Vec<D>>(ids_.structure_force);
    if (ids_.body >= 0) v.body = s.data<std::uint8_t>(ids_.body);
    if (ids_.zone >= 0) v.zone = s.data<std::uint8_t>(ids_.zone);
    if (ids_.free_slip >= 0) v.free_slip = s.data<std::uint8_t>(ids_.free_slip);
    if (ids_.viscous_velocity >= 0) v.viscous_velocity = s.data<Vec<D>>(ids_.viscous_velocity);
    if (ids_.shifting_velocity >= 0) v.shifting_velocity = s.data<Vec<D>>(ids_.shifting_velocity);
    if (ids_.shear_rate >= 0) v.shear_rate = s.data<Real>(ids_.shear_rate);
    if (ids_.effective_viscosity >= 0) v.effective_viscosity = s.data<Real>(ids_.effective_viscosity);
    if (ids_.shear_stress >= 0) v.shear_stress = s.data<Real>(ids_.shear_stress);
    if (ids_.split_fresh >= 0) v.split_fresh = s.data<std::uint8_t>(ids_.split_fresh);
    if (ids_.viscous_load >= 0) v.viscous_load = s.data<Vec<D>>(ids_.viscous_load);
    if (ids_.viscous_pending >= 0) v.viscous_pending = s.data<Vec<D>>(ids_.viscous_pending);
    if (ids_.put_back_impulse >= 0) v.put_back_impulse = s.data<Vec<D>>(ids_.put_back_impulse);
    if (ids_.put_back_from >= 0) v.put_back_from = s.data<std::uint32_t>(ids_.put_back_from);
    if (ids_.constraint_force >= 0) v.constraint_force = s.data<Vec<D>>(ids_.constraint_force);
    if (ids_.constraint_power >= 0) v.constraint_power = s.data<Real>(ids_.constraint_power);
    v.count = std::uint32_t(s.size());
    if (soa_valid_) {
      v.position_soa = soa_.data();
      v.soa_stride = soa_stride_;
    }
    return v;
  }

  template <int D>
  GridView<D> grid() const {
    return layout_.view<D>(cell_start_.data(), fluid_before_.empty() ? nullptr : fluid_before_.data());
  }

  // The neighbour list recorded by the momentum pass, reused by the next continuity pass (same
  // positions). Invalid after every sort.
  NeighbourList list(bool record) {
    NeighbourList L;
    if (!record && !list_valid_) return L;
    const std::size_t n = store_->size();
    if (record) {
      if (list_stride_ == 0) list_stride_ = neighbour_list_stride(params_, spacing_estimate());
      if (list_entries_.size() < n * list_stride_) list_entries_.resize(n * list_stride_);
      if (list_count_.size() < n) list_count_.resize(n);
    }
    L.entries = list_entries_.data();
    L.count = list_count_.data();
    L.stride = list_stride_;
    L.record = record;
    return L;
  }

  double spacing_estimate() const {
    // Volume per particle of the initial lattice, from the first particle's mass and density.
    if (store_->size() == 0) return params_.smoothing_length;
    const double m = store_->data<Real>(ids_.mass)[0];
    const double rho = store_->data<Real>(ids_.density)[0];
    return std::pow(m / rho, 1.0 / params_.dimensions);
  }

  template <int D>
  std::size_t sort_by_cell() {
    const std::uint32_t n = std::uint32_t(store_->size());
    const GridView<D> g = grid<D>();
    const Vec<D>* x = store_->data<Vec<D>>(ids_.position);
    const std::uint32_t outside = std::uint32_t(cell_count_);
    keys_.resize(n);
    // The grid is a whole number of cells and may reach past the domain's upper faces; those
    // particles are outside too.
    Real upper[D];
    for (int k = 0; k < D; ++k) upper[k] = Real(domain_max_[k]);
    parallel_for(n, [&](std::uint32_t i) {
      int c[D] = {};
      bool inside = g.cell_of(x[i], c);
      for (int k = 0; k < D; ++k) inside = inside && x[i][k] <= upper[k];
      keys_[i] = inside ? g.linear(c) : outside;
    });
    // Stable counting sort: particles keep their relative order inside a cell, so the result is
    // the same on every run and thread count.
    std::fill(cell_start_.begin(), cell_start_.end(), 0u);
    for (std::uint32_t i = 0; i < n; ++i) ++cell_start_[keys_[i]];
    std::uint32_t sum = 0;
    for (std::size_t c = 0; c <= cell_count_; ++c) {
      const std::uint32_t k = cell_start_[c];
      cell_start_[c] = sum;
      sum += k;
    }
    order_.resize(n);
    cursor_.assign(cell_start_.begin(), cell_start_.end());
    for (std::uint32_t i = 0; i < n; ++i) order_[cursor_[keys_[i]]++] = i;
    store_->permute(order_.data());
    const std::uint32_t kept = cell_start_[cell_count_];
    store_->resize(kept);
    // Fluid particles before each cell, for walls that look for fluid around them.
    fluid_before_.assign(cell_count_ + 1, 0);
    const std::uint8_t* kind = store_->data<std::uint8_t>(ids_.kind);
    for (std::uint32_t r = 0; r < kept; ++r)
      if (kind[r] == std::uint8_t(Kind::fluid)) ++fluid_before_[keys_[order_[r]] + 1];
    for (std::size_t c = 0; c < cell_count_; ++c) fluid_before_[c + 1] += fluid_before_[c];
    // Coordinate arrays for the vectorised distance checks of the passes that follow.
    soa_stride_ = kept;
    soa_.resize(std::size_t(D) * kept);
    const Vec<D>* xs = store_->data<Vec<D>>(ids_.position);
    Real* soa = soa_.data();
    const std::size_t stride = soa_stride_;
    parallel_for(kept, [=](std::uint32_t i) {
      for (int a = 0; a < D; ++a) soa[std::size_t(a) * stride + i] = xs[i][a];
    });
    soa_valid_ = true;
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
        parallel_for(P.count, DensityGradientPass<D, K, U>{P, G, params_, list(false)});
      dispatch_diffusion(params_.diffusion, [&](auto diff_tag) {
        constexpr Diffusion Df = decltype(diff_tag)::value;
        parallel_for(P.count, ContinuityPass<D, K, Df, U>{P, G, params_, list(false)});
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
        parallel_for(P.count, MdbcPass<D, K, U>{P, G, params_, params_.wall_no_slip, params_.boundary == Boundary::mdbc});
      if (params_.zone_count > 0) parallel_for(P.count, BufferPass<D, K, U>{P, G, params_});
      if (params_.rheology) parallel_for(P.count, RheologyPass<D, K, U>{P, G, params_});
      parallel_for(P.count, PressurePass<D>{P, params_});
      parallel_for(P.count, MomentumPass<D, K, U>{P, G, params_, list(true)});
      if (params_.body_count > 0 || params_.wall_loads) parallel_for(P.count, StructureForcePass<D, K, U>{P, G, params_});
    });
    list_valid_ = true;
  }

  template <int D>
  void kick_impl(Real half_dt) {
    parallel_for(std::uint32_t(store_->size()), KickPass<D>{view<D>(), half_dt});
  }

  template <int D>
  void drift_impl(Real dt) {
    parallel_for(std::uint32_t(store_->size()),
                 DriftPass<D>{view<D>(), dt, params_.materials[params_.wall_material].eos.no_tension_density(), params_});
    if (!params_.wall_constraint) return;
    const std::uint32_t n = std::uint32_t(store_->size());
    put_backs_[1] = put_backs_[0];
    parallel_for(n, WallConstraintPass<D>{view<D>(), grid<D>(), params_, list(false), &put_backs_[0]});
    const ParticleView<D> P = view<D>();
    parallel_for(n, WallConstraintLoadPass<D>{P, grid<D>(), params_, Real(1) / dt, put_backs_});
    if (put_backs_[0] == put_backs_[1]) return;
    // The drift's impulse and energy into the run's totals (fixed-order sums: any thread count).
    auto boundary = [P](std::uint32_t b) { return WallConstraintPass<D>::boundary(P.kind[b]); };
    for (int a = 0; a < D; ++a)
      constraint_totals_.impulse[a] += double(dt) * fixed_order_sum(n, [&](std::uint32_t b) {
        return boundary(b) ? double(P.constraint_force[b][a]) : 0.0;
      });
    constraint_totals_.energy += double(dt) * fixed_order_sum(n, [&](std::uint32_t b) {
      return boundary(b) ? double(P.constraint_power[b]) : 0.0;
    });
  }

  template <int D>
  StepStats stats_impl() {
    const ParticleView<D> P = view<D>();
    double v2 = 0, a2 = 0;
    const std::int64_t n = P.count;
#pragma omp parallel for reduction(max : v2, a2) schedule(static) if (n >= kParallelThreshold)
    for (std::int64_t i = 0; i < n; ++i) {
      if (P.kind[i] != std::uint8_t(Kind::fluid)) continue;
      v2 = std::max(v2, double(norm2(P.velocity[i])));
      a2 = std::max(a2, double(norm2(P.acceleration[i])));
    }
    return {std::sqrt(v2), std::sqrt(a2)};
  }

  template <int D>
  std::optional<HealthIssue> health_impl(double limit) {
    const ParticleView<D> P = view<D>();
    const std::uint32_t* id = store_->data<std::uint32_t>(ids_.id);
    const std::int64_t n = P.count;
    std::int64_t first = n;
#pragma omp parallel for reduction(min : first) schedule(static) if (n >= kParallelThreshold)
    for (std::int64_t i = 0; i < n; ++i) {
      if (!healthy<D>(P, std::uint32_t(i), limit)) first = std::min(first, i);
    }
    if (first == n) return std::nullopt;
    const std::uint32_t i = std::uint32_t(first);
    HealthIssue h;
    h.index = i;
    h.id = id[i];
    for (int k = 0; k < D; ++k) {
      if (!std::isfinite(P.position[i][k])) { h.field = "position"; h.value = P.position[i][k]; return h; }
      if (!std::isfinite(P.velocity[i][k])) { h.field = "velocity"; h.value = P.velocity[i][k]; return h; }
      if (!std::isfinite(P.acceleration[i][k])) { h.field = "acceleration"; h.value = P.acceleration[i][k]; return h; }
    }
    h.field = "density";
    h.value = P.density[i];
    return h;
  }

  template <int D>
  bool healthy(const ParticleView<D>& P, std::uint32_t i, double limit) const {
    for (int k = 0; k < D; ++k)
      if (!std::isfinite(P.position[i][k]) || !std::isfinite(P.velocity[i][k]) || !std::isfinite(P.acceleration[i][k]))
        return false;
    // Walls and structures hold density in the wall material's units, buffers in their own.
    const bool own = P.kind[i] == std::uint8_t(Kind::fluid) || P.kind[i] == std::uint8_t(Kind::buffer);
    const int m = own ? P.material[i] : params_.wall_material;
    const double ratio = double(P.density[i]) / params_.materials[m].eos.rest_density - 1.0;
    return std::isfinite(ratio) && std::abs(ratio) <= limit;
  }

  template <int D>
  std::size_t count_pairs() {
    const ParticleView<D> P = view<D>();
    const GridView<D> G = grid<D>();
    const Real h = params_.smoothing_length;
    std::size_t total = 0;
    const std::int64_t n = P.count;
#pragma omp parallel for reduction(+ : total) schedule(dynamic, 256) if (n >= kParallelThreshold)
    for (std::int64_t i = 0; i < n; ++i) {
      int c[D] = {};
      G.cell_of(P.position[i], c);
      std::size_t local = 0;
      G.for_each_neighbour_range(c, [&](std::uint32_t b, std::uint32_t e, const Vec<D>& offset) {
        for (std::uint32_t j = b; j < e; ++j)
          if (j != std::uint32_t(i) && norm2(P.position[i] - P.position[j] - offset) < Real(4) * h * h) ++local;
      });
      total += local;
    }
    return total;
  }

  int threads_;
  unsigned long long put_backs_[2] = {0, 0};  // WallConstraintPass's put-backs since bind; [1]: before this drift
  WallConstraintTotals constraint_totals_;
  ParticleStore* store_ = nullptr;
  FieldIds ids_;
  PhysicsParams params_;
  GridLayout layout_;
  double domain_max_[3] = {0, 0, 0};
  std::size_t cell_count_ = 1;
  std::vector<std::uint32_t> cell_start_, cursor_, keys_, order_;
  std::vector<std::uint32_t> list_entries_, list_count_, fluid_before_;
  std::vector<std::uint32_t> new_slots_;  // splitting: slots each particle asks for
  std::vector<std::int8_t> rule_of_;      // splitting: the rule a particle meets, or -1
  std::vector<std::uint64_t> first_slot_; // splitting: exclusive scan of new_slots_
  std::vector<std::uint8_t> relax_zone_;  // relaxation after a split: 1 for the particles it moves
  std::vector<Real> relax_shift_;         // relaxation after a split: each zone particle's shift
  std::uint32_t list_stride_ = 0;
  bool list_valid_ = false;
  std::vector<Real> soa_;
  // Implicit viscosity: the solve's eight vector arrays in blocks of the particle count (x, r, z,
  // p, A p, the diagonal, the full stress's direct part and dR/du: ViscousWork::over), per
  // dimension; the full stress's three tensor arrays (renormalisation, gradient, Q) likewise.
  std::vector<Vec<2>> cg2_;
  std::vector<Vec<3>> cg3_;
  std::vector<Real> carrier_mu_;  // full stress: the carriers' viscosity (0: not a carrier)
  std::vector<Mat<2>> fs2_;
  std::vector<Mat<3>> fs3_;
  template <int D>
  std::vector<Mat<D>>& full_stress_tensors() {
    if constexpr (D == 2) return fs2_;
    else return fs3_;
  }
  std::vector<double> block_sums_;  // the fixed-order reductions' block sums
  template <int D>
  std::vector<Vec<D>>& cg_vectors() {
    if constexpr (D == 2) return cg2_;
    else return cg3_;
  }
  std::size_t soa_stride_ = 0;
  bool soa_valid_ = false;
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend(int threads) { return std::make_unique<CpuBackend>(threads); }

}  // namespace turbid::sph
