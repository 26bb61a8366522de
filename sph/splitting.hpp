// Particle splitting, the debris-flow -> turbidity-current transition (seed paper sect. II.C, eq. 4,
// Figs. 2-3; physics.md C7, C9): a fluid particle of a "from" material whose effective shear stress
// sqrt(J2(tau)) passes a threshold becomes 2^D daughters of the "to" material.
//
// Geometry. A mother of volume V = m / rho stands for a cube (square in 2D) of edge a = V^(1/D);
// her daughters sit at the centres of its 2^D sub-cubes, x +- a/4 along every axis, each with mass
// m / 2^D, smoothing length h / 2 and the mother's velocity and acceleration. (Eq. 4 as printed
// reads (V/4)^(1/3), which would place daughters outside the mother's volume; the sub-cube centres
// match the daughters' mass m/8 and h/2.) Mass, linear momentum and kinetic energy are exactly those
// of the mother (m / 2^D is exact in binary); the centre of mass is the mother's position up to the
// rounding of x +- a/4 to the stored float.
//
// Parallel insertion (paper Fig. 3), the same on every backend: (1) each particle says how many new
// slots it needs (2^D - 1 if it splits, else 0); (2) an exclusive scan of those counts gives every
// mother the first of her slots after the current particles; (3) mothers whose slots would pass the
// store's capacity are refused, lowest index first served, so the outcome does not depend on thread
// or block scheduling; (4) each accepted mother writes daughter 0 into her own slot and daughters
// 1..2^D-1 into hers, every registered field carried by its Carry rule.
#pragma once
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "sph/config.hpp"
#include "sph/particle_store.hpp"
#include "sph/passes.hpp"
#include "sph/split_params.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

template <int D>
constexpr int daughters_per_split() {
  return 1 << D;
}

// Offset of daughter k (0 <= k < 2^D) from her mother: the centre of sub-cube k of the mother's
// cube of edge `edge`, bit d of k choosing + or - a/4 along axis d.
template <int D>
TURBID_HD inline Vec<D> daughter_offset(int k, Real edge) {
  Vec<D> o;
  for (int d = 0; d < D; ++d) o[d] = ((k >> d) & 1) ? Real(0.25) * edge : Real(-0.25) * edge;
  return o;
}

// The cube root of a positive normal float, correctly rounded (to nearest), so that the CPU and
// the GPU place 3D daughters on the same bits: libm's cbrtf is not correctly rounded (glibc 2.36
// differs from the correctly rounded root in about 1 float in 10 by one ulp; CUDA's cbrtf is
// documented within 1 ulp), and the two libraries round differently. The double cube root gives a
// candidate within one float ulp; the midpoints to its neighbours then decide exactly: a midpoint
// m has 25 significant bits, so m*m is exact and fma(m*m, m, -v) has the exact sign of m^3 - v
// (never zero: a 24-bit v is not the cube of a 25-bit m). Square roots need no such care: sqrt is
// correctly rounded on both backends.
TURBID_HD inline float cube_root_rn(float v) {
  if (!(v >= std::numeric_limits<float>::min() && v <= std::numeric_limits<float>::max()))
    return float(std::cbrt(double(v)));  // 0, subnormal, negative, inf, NaN: not met by a volume
  const auto step = [](float x, int by) {
    std::uint32_t b;
    std::memcpy(&b, &x, sizeof b);
    b = std::uint32_t(std::int64_t(b) + by);
    std::memcpy(&x, &b, sizeof b);
    return x;
  };
  const auto cube_minus_v = [v](double m) {
    const double m2 = m * m;
    return std::fma(m2, m, -double(v));
  };
  float c = float(std::cbrt(double(v)));
  for (int pass = 0; pass < 2; ++pass) {
    const float up = step(c, +1), down = step(c, -1);
    if (cube_minus_v(0.5 * (double(c) + double(up))) < 0.0) c = up;
    else if (cube_minus_v(0.5 * (double(c) + double(down))) > 0.0) c = down;
    else break;
  }
  return c;
}

// Edge a = V^(1/D) of the cube a particle of mass m and density rho stands for [m]. Both roots are
// correctly rounded, so every backend gets the same bits.
template <int D>
TURBID_HD inline Real split_edge(Real mass, Real density) {
  const Real volume = mass / density;
  if constexpr (D == 2) return std::sqrt(volume);
  else return cube_root_rn(volume);
}

// Step (1) for every particle: new_slots[i] = 2^D - 1 if i meets a rule, else 0; rule_of[i] the
// rule's index (or -1). The criterion reads the effective shear stress of the last force pass.
// `where: interface` asks for a fluid neighbour of a third material (neither the rule's `from` nor its
// `to`: the ambient fluid) within the pair's support, so the daughters next to a mother do not make
// her an interface particle and the split does not cascade through the slide.
template <int D, class K, bool UniformH>
struct SplitFlagPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  SplitParams sp;
  std::uint32_t* new_slots = nullptr;
  std::int8_t* rule_of = nullptr;

  TURBID_HD void operator()(std::uint32_t i) const {
    new_slots[i] = 0;
    rule_of[i] = -1;
    if (P.kind[i] != std::uint8_t(Kind::fluid) || P.shear_stress == nullptr) return;
    const std::uint8_t mat = P.material[i];
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    int rule = -1;
    for (int r = 0; r < sp.rule_count; ++r) {
      const SplitRule& R = sp.rules[r];
      if (R.from == mat && P.shear_stress[i] > R.threshold && h_i > R.min_smoothing_length) {
        rule = r;
        break;
      }
    }
    if (rule < 0) return;
    if (sp.rules[rule].interface_only) {
      const std::uint8_t to = sp.rules[rule].to;
      bool other = false;
      for_each_neighbour<D>(P, G, NeighbourList{}, prm, i, P.position[i], [&](std::uint32_t j, const Vec<D>&, Real r2) {
        const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
        if (!UniformH && r2 >= Real(4) * h * h) return;
        other = other || (P.kind[j] == std::uint8_t(Kind::fluid) && P.material[j] != mat && P.material[j] != to);
      });
      if (!other) return;
    }
    rule_of[i] = std::int8_t(rule);
    new_slots[i] = std::uint32_t(daughters_per_split<D>() - 1);
  }
};

// Step (3), the rule every backend applies: a mother is accepted when all her new slots lie within
// `room` = capacity - count. The scan runs over every candidate, refused or not, so the accepted
// mothers are the lowest-index ones, whatever order threads or blocks run in.
TURBID_HD inline bool split_accepted(std::uint64_t first_slot, std::uint32_t new_slots, std::uint64_t room) {
  return new_slots != 0 && first_slot + new_slots <= room;
}

// What a split reports, gathered per particle and combined (sums, max and min: exact in any order,
// so a parallel reduction gives what a loop over the particles gives).
struct SplitTally {
  std::uint64_t splits;
  std::uint64_t refused;
  std::uint64_t added;     // new slots up to the last accepted mother (her inclusive scan)
  std::uint32_t next_id;   // one past the largest id present: daughters' ids start here
  Real smallest_h;         // half the smallest accepted mother's h

  // The identity of CombineSplitTally (a plain aggregate, so device reductions may hold it raw).
  TURBID_HD static SplitTally none() { return {0, 0, 0, 0, std::numeric_limits<Real>::max()}; }
  TURBID_HD static SplitTally of(std::uint32_t id, Real h, std::uint64_t first_slot, std::uint32_t new_slots,
                                 std::uint64_t room) {
    SplitTally t = none();
    t.next_id = id + 1u;
    if (new_slots == 0) return t;
    if (split_accepted(first_slot, new_slots, room)) {
      t.splits = 1;
      t.added = first_slot + new_slots;
      t.smallest_h = Real(0.5) * h;
    } else {
      t.refused = 1;
    }
    return t;
  }
};

struct CombineSplitTally {
  TURBID_HD SplitTally operator()(const SplitTally& a, const SplitTally& b) const {
    SplitTally t = SplitTally::none();
    t.splits = a.splits + b.splits;
    t.refused = a.refused + b.refused;
    t.added = a.added < b.added ? b.added : a.added;
    t.next_id = a.next_id < b.next_id ? b.next_id : a.next_id;
    t.smallest_h = b.smallest_h < a.smallest_h ? b.smallest_h : a.smallest_h;
    return t;
  }
};

// Every registered field of one backend's storage, so a split carries each by its Carry rule without
// code per field (a field registered later is carried too). Passed by value into the write pass.
constexpr int kMaxSplitFields = 32;

struct SplitFieldTable {
  struct Field {
    std::byte* data = nullptr;
    std::uint32_t bytes = 0;      // per particle
    std::uint16_t components = 0;
    ScalarType type = ScalarType::f32;
    Carry carry = Carry::copy;
  };
  int count = 0;
  Field field[kMaxSplitFields];

  // Particle `to` becomes a copy of particle `from` in every field.
  TURBID_HD void copy(std::size_t from, std::size_t to) const {
    for (int f = 0; f < count; ++f) {
      const Field& F = field[f];
      std::memcpy(F.data + to * F.bytes, F.data + from * F.bytes, F.bytes);
    }
  }
  // Particle i's value of every Carry::divide field divided by `shares` (the daughters that share it).
  TURBID_HD void divide(std::size_t i, int shares) const {
    for (int f = 0; f < count; ++f) {
      const Field& F = field[f];
      if (F.carry != Carry::divide) continue;
      if (F.type == ScalarType::f32) {
        float* v = reinterpret_cast<float*>(F.data) + i * F.components;
        for (int k = 0; k < F.components; ++k) v[k] /= float(shares);
      } else if (F.type == ScalarType::f64) {
        double* v = reinterpret_cast<double*>(F.data) + i * F.components;
        for (int k = 0; k < F.components; ++k) v[k] /= double(shares);
      }
    }
  }
};

// The first `count` fields of `store`'s registry, with their data where data_of(FieldId) says (the
// host store's arrays, or a device copy of them).
template <class DataOf>
SplitFieldTable split_field_table(const ParticleStore& store, int count, DataOf&& data_of) {
  if (count > kMaxSplitFields)
    throw std::length_error("splitting carries at most " + std::to_string(kMaxSplitFields) + " particle fields, the store has " +
                            std::to_string(count));
  SplitFieldTable t;
  t.count = count;
  for (int f = 0; f < count; ++f) {
    const FieldDesc& d = store.desc(f);
    t.field[f].data = static_cast<std::byte*>(data_of(FieldId(f)));
    t.field[f].bytes = std::uint32_t(store.field_bytes(f));
    t.field[f].components = std::uint16_t(d.components);
    t.field[f].type = d.type;
    t.field[f].carry = d.carry;
  }
  return t;
}

// Step (4) for every particle i < n (the count before the split): an accepted mother copies herself
// into her new slots n + first_slot[i] + k - 1 (k = 1..2^D-1), then each of her 2^D daughters (k = 0
// in her own slot) takes its share of the divided fields, its sub-cube centre, h/2 and the rule's
// material; daughters beyond the first get fresh ids in slot order. A thread writes only its
// mother's slots and reads only her values, so any schedule gives the same bytes.
template <int D>
struct SplitWritePass {
  SplitFieldTable fields;
  ParticleView<D> P;
  DriftPass<D> periodic;  // only its wrap(): daughters of a mother near a periodic face
  SplitParams sp;
  const std::uint32_t* new_slots = nullptr;
  const std::int8_t* rule_of = nullptr;
  const std::uint64_t* first_slot = nullptr;
  std::uint64_t room = 0;
  std::uint32_t n = 0;
  std::uint32_t next_id = 0;
  std::uint32_t* id = nullptr;

  TURBID_HD void operator()(std::uint32_t i) const {
    if (!split_accepted(first_slot[i], new_slots[i], room)) return;
    constexpr int kD = daughters_per_split<D>();
    const SplitRule& rule = sp.rules[rule_of[i]];
    const std::size_t base = std::size_t(n) + first_slot[i];  // daughter k >= 1 goes to base + k - 1
    const Vec<D> x0 = P.position[i];
    const Real edge = split_edge<D>(P.mass[i], P.density[i]);
    const Real h = P.smoothing_length[i];
    for (int k = 1; k < kD; ++k) fields.copy(i, base + std::size_t(k - 1));
    for (int k = 0; k < kD; ++k) {
      const std::size_t slot = k == 0 ? i : base + std::size_t(k - 1);
      fields.divide(slot, kD);
      // +-a/4 is exact (a power-of-two scaling), so where a compiler fuses it with the addition
      // (nvcc does) the position has the same bits.
      P.position[slot] = periodic.wrap(x0 + daughter_offset<D>(k, edge));
      P.smoothing_length[slot] = Real(0.5) * h;
      P.material[slot] = rule.to;
      if (P.split_fresh) P.split_fresh[slot] = 1;  // the relaxation after the split starts from here
      if (k > 0) id[slot] = next_id + std::uint32_t(first_slot[i]) + std::uint32_t(k - 1);
    }
  }
};

// Relaxation after a split (docs/choices.md, "Splitting"). Where daughters of h/2 meet particles of
// h, no symmetric pair kernel gives both sides their summation density: on a lattice at rest the
// kernel of the mean h puts the daughters on the edge of a split block 15.5% above the mother's
// (tests/unit/test_splitting.cpp). A few Jacobi steps of a shifting displacement,
//   dx_i = -beta h_i^2 sum_j V_j grad_i W(r_ij, h_ij)     (|dx_i| <= 0.05 h_i per step),
// applied to the new daughters and to the fluid particles within a pair support of one, move that
// zone towards a uniform kernel sum (below 1% on the lattice after 10 steps of beta = 0.2). Only
// positions move: mass, velocities and densities stay, so mass, momentum and kinetic energy are
// untouched, and the zone's mass-weighted mean displacement is removed, so the centre of mass stays.
// Particles with a truncated kernel sum (below 0.8: a free surface) keep their place.
inline constexpr Real kSplitRelaxMaxStep = Real(0.05);  // largest displacement per step [h_i]
inline constexpr Real kSplitRelaxMinFill = Real(0.8);   // sum_j V_j W_ij below which a particle stays

// zone[i] = 1 for a fluid particle that is a new daughter or has one within the pair's support.
template <int D, class K, bool UniformH>
struct SplitRelaxZonePass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  std::uint8_t* zone = nullptr;

  TURBID_HD void operator()(std::uint32_t i) const {
    zone[i] = 0;
    if (P.kind[i] != std::uint8_t(Kind::fluid)) return;
    if (P.split_fresh[i]) {
      zone[i] = 1;
      return;
    }
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    bool near = false;
    for_each_neighbour<D>(P, G, NeighbourList{}, prm, i, P.position[i], [&](std::uint32_t j, const Vec<D>&, Real r2) {
      const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
      near = near || (P.split_fresh[j] && r2 < Real(4) * h * h);
    });
    zone[i] = near ? 1 : 0;
  }
};

// One Jacobi step: shift[i] for the zone's particles from the positions as they are (zero elsewhere).
template <int D, class K, bool UniformH>
struct SplitRelaxShiftPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  const std::uint8_t* zone = nullptr;
  Vec<D>* shift = nullptr;
  Real strength = Real(0.2);  // beta

  TURBID_HD void operator()(std::uint32_t i) const {
    shift[i] = Vec<D>{};
    if (!zone[i]) return;
    const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
    Real fill = K::w(Real(0), h_i) * P.mass[i] / P.density[i];
    Vec<D> grad{};
    for_each_neighbour<D>(P, G, NeighbourList{}, prm, i, P.position[i], [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
      const Real h = pair_h<D, K>(P, prm, UniformH, h_i, j);
      if (r2 >= Real(4) * h * h) return;
      const Real r = std::sqrt(r2);
      const Real vol = P.mass[j] / P.density[j];
      fill += vol * K::w(r, h);
      const Real F = K::f_inv(r, Real(1) / h);
      for (int a = 0; a < D; ++a) grad[a] += vol * F * rij[a];
    });
    if (fill < kSplitRelaxMinFill) return;
    Vec<D> s;
    Real len2 = 0;
    for (int a = 0; a < D; ++a) {
      s[a] = -strength * h_i * h_i * grad[a];
      len2 += s[a] * s[a];
    }
    const Real cap = kSplitRelaxMaxStep * h_i;
    if (len2 > cap * cap) {
      const Real k = cap / std::sqrt(len2);
      for (int a = 0; a < D; ++a) s[a] *= k;
    }
    shift[i] = s;
  }
};

// Applies shift[i] - mean (the zone's mass-weighted mean shift) to the zone, back into a periodic
// domain where a particle crosses a face.
template <int D>
struct SplitRelaxApplyPass {
  ParticleView<D> P;
  DriftPass<D> periodic;  // only its wrap()
  const std::uint8_t* zone = nullptr;
  const Vec<D>* shift = nullptr;
  Vec<D> mean{};

  TURBID_HD void operator()(std::uint32_t i) const {
    if (!zone[i]) return;
    Vec<D> x = P.position[i];
    for (int a = 0; a < D; ++a) x[a] += shift[i][a] - mean[a];
    P.position[i] = periodic.wrap(x);
  }
};

// The zone's count, mass and mass-weighted shift, per particle and summed (a device reduction).
struct RelaxMoment {
  double count;
  double mass;
  double moment[3];
};

struct SumRelaxMoment {
  TURBID_HD RelaxMoment operator()(const RelaxMoment& a, const RelaxMoment& b) const {
    return {a.count + b.count, a.mass + b.mass,
            {a.moment[0] + b.moment[0], a.moment[1] + b.moment[1], a.moment[2] + b.moment[2]}};
  }
};

// Particle i's share (the summand of a device transform-reduction).
template <int D>
struct RelaxMomentPass {
  const std::uint8_t* zone = nullptr;
  const Real* mass = nullptr;
  const Vec<D>* shift = nullptr;

  TURBID_HD RelaxMoment operator()(std::uint32_t i) const {
    RelaxMoment r{0, 0, {0, 0, 0}};
    if (zone[i]) {
      r.count = 1;
      r.mass = double(mass[i]);
      for (int a = 0; a < D; ++a) r.moment[a] = double(mass[i]) * double(shift[i][a]);
    }
    return r;
  }
};

}  // namespace turbid::sph
