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

#include "sph/config.hpp"
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

}  // namespace turbid::sph
