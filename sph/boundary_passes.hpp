// Passes over boundary particles (walls and structures), shared by all backends:
//  - MdbcPass: the modified dynamic boundary condition (English et al. 2022, physics.md C5);
//  - StructureForcePass: the force of the fluid on each structure particle, the exact reaction of
//    the momentum pass's pair terms.
#pragma once
#include <cmath>
#include <cstdint>

#include "sph/config.hpp"
#include "sph/passes.hpp"

namespace turbid::sph {

// Solves the N x N system A x = b in place by Gaussian elimination with partial pivoting; returns
// the determinant of A (0 if a pivot vanishes, x then undefined).
template <int N>
TURBID_HD inline Real solve_small(Real (&A)[N][N], Real (&b)[N], Real (&x)[N]) {
  Real det = 1;
  for (int c = 0; c < N; ++c) {
    int p = c;
    for (int r = c + 1; r < N; ++r)
      if (std::fabs(A[r][c]) > std::fabs(A[p][c])) p = r;
    if (A[p][c] == Real(0)) return Real(0);
    if (p != c) {
      for (int k = 0; k < N; ++k) {
        const Real t = A[c][k];
        A[c][k] = A[p][k];
        A[p][k] = t;
      }
      const Real t = b[c];
      b[c] = b[p];
      b[p] = t;
      det = -det;
    }
    det *= A[c][c];
    for (int r = c + 1; r < N; ++r) {
      const Real f = A[r][c] / A[c][c];
      for (int k = c; k < N; ++k) A[r][k] -= f * A[c][k];
      b[r] -= f * b[c];
    }
  }
  for (int r = N - 1; r >= 0; --r) {
    Real s = b[r];
    for (int k = r + 1; k < N; ++k) s -= A[r][k] * x[k];
    x[r] = s / A[r][r];
  }
  return det;
}

// Smallest singular value of a D x D matrix (D = 2 or 3): the square root of the smallest
// eigenvalue of S^T S (closed form in 2D; in 3D the trigonometric solution of the characteristic
// cubic of a symmetric matrix).
template <int D>
TURBID_HD inline Real smallest_singular_value(const Real (&S)[D][D]) {
  Real M[D][D];
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) {
      Real m = 0;
      for (int k = 0; k < D; ++k) m += S[k][a] * S[k][b];
      M[a][b] = m;
    }
  Real lambda;
  if constexpr (D == 2) {
    const Real t = M[0][0] + M[1][1], d = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    const Real disc = t * t - Real(4) * d;
    const Real big = Real(0.5) * (t + std::sqrt(disc > Real(0) ? disc : Real(0)));
    lambda = big > Real(0) ? d / big : Real(0);  // the product over the larger root: no cancellation
  } else {
    const Real q = (M[0][0] + M[1][1] + M[2][2]) / Real(3);
    const Real off = M[0][1] * M[0][1] + M[0][2] * M[0][2] + M[1][2] * M[1][2];
    const Real p2 = (M[0][0] - q) * (M[0][0] - q) + (M[1][1] - q) * (M[1][1] - q) + (M[2][2] - q) * (M[2][2] - q) +
                    Real(2) * off;
    if (!(p2 > Real(0))) {
      lambda = q;  // a multiple of the identity
    } else {
      const Real p = std::sqrt(p2 / Real(6));
      Real B[3][3];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) B[a][b] = (M[a][b] - (a == b ? q : Real(0))) / p;
      Real r = Real(0.5) * (B[0][0] * (B[1][1] * B[2][2] - B[1][2] * B[2][1]) -
                            B[0][1] * (B[1][0] * B[2][2] - B[1][2] * B[2][0]) +
                            B[0][2] * (B[1][0] * B[2][1] - B[1][1] * B[2][0]));
      r = r < Real(-1) ? Real(-1) : (r > Real(1) ? Real(1) : r);
      const Real phi = std::acos(r) / Real(3);
      lambda = q + Real(2) * p * std::cos(phi + Real(2.0943951023931957));  // + 2 pi / 3: the smallest root
    }
  }
  return std::sqrt(lambda > Real(0) ? lambda : Real(0));
}

// Smallest gain (see ghost_interpolation) at which the first-order extrapolation is trusted: a
// full support has about 1, a ghost beside a flat wall or a free surface 0.2-0.3, the thin tip of a
// surge 0.003-0.1 (whose gradient across itself would be amplified 10-300 times).
inline constexpr Real kMdbcMinGradientGain = Real(0.1);

// First-order corrected SPH interpolation at a ghost node x_g over the fluid (physics.md C5):
//   [ sum W V        sum x_jg^T W V        ] [ rho_g      ]   [ sum rho*_j W V      ]
//   [ sum grad W V   sum grad W (x) x_jg V ] [ grad rho_g ] = [ sum rho*_j grad W V ]
// `density` gets rho_g + (x_b - x_g) . grad rho_g with offset = x_g - x_b; where |det| < 1e-3
// (too few neighbours on one side), or where the fluid resolves the gradient in some direction
// with a gain below kMdbcMinGradientGain (a film one or two particles thick: its gradient across
// itself is noise amplified up to 300 times, which blew up a dam break's surge tip at the far
// wall), the Shepard value sum rho* W V / sum V W. rho*_j is the density
// that the boundary particle's equation of state `eos` (material `ref`) gives at j's pressure: rho_j
// itself for a neighbour of material `ref` (m_j W, bit for bit as with one material), and
// eos.density(p_j(rho_j)) for another. What is extrapolated is thus the fluid's pressure, which is
// continuous across an interface; the relative density is not (a wall beside debris of 1950 kg/m^3
// read as water would be at 1.95 rho0, p = B (1.95^7 - 1)).
// `velocity` gets the Shepard-interpolated fluid velocity at x_g. Returns the fluid's share of the
// kernel support at x_g, sum_fluid V_j W_gj (about 1 inside the fluid, 0 when no fluid is in reach:
// nothing set then); `boundary_share` gets the same sum over the other particles (walls, structures,
// buffers) with their rest volumes: their densities are what the calling pass writes, so reading
// them would race with it (and depend on the thread schedule).
// WithDensity = false (DBC walls that only want the no-slip velocity): only the Shepard sums are
// built; no moment matrix, no solve, `density` untouched.
template <int D, class K, bool UniformH, bool WithDensity = true>
TURBID_HD inline Real ghost_interpolation(const ParticleView<D>& P, const GridView<D>& G, const PhysicsParams& prm,
                                          const Vec<D>& xg, const Vec<D>& offset, Real h_b, int ref, Real& density,
                                          Vec<D>& velocity, Real& boundary_share) {
  boundary_share = 0;
  int c[D] = {};
  if (!G.cell_of(xg, c) || !G.fluid_near(c)) return Real(0);
  const Real support2 = Real(4) * prm.max_smoothing_length * prm.max_smoothing_length;
  constexpr int N = D + 1;
  Real A[N][N] = {};
  Real rhs[N] = {};
  Vec<D> vsum = Vec<D>::zero();
  const TaitEos& eos = prm.materials[ref].eos;
  G.for_each_neighbour_range(c, [&](std::uint32_t j0, std::uint32_t j1, const Vec<D>& image) {
    const Vec<D> xo = xg - image;
    for (std::uint32_t j = j0; j < j1; ++j) {
      const bool fluid = P.kind[j] == std::uint8_t(Kind::fluid);
      const Vec<D> r = xo - P.position[j];  // x_g - x_j = -x_jg
      const Real r2 = norm2(r);
      if (r2 >= support2) continue;
      const Real h = UniformH ? prm.smoothing_length : Real(0.5) * (h_b + P.smoothing_length[j]);
      if (!UniformH && r2 >= Real(4) * h * h) continue;
      const Real rr = std::sqrt(r2);
      const Real W = K::w(rr, h);
      if (!fluid) {
        // Rest volume: walls and structures are in the wall material's units, buffers in their own.
        const int mb = P.kind[j] == std::uint8_t(Kind::buffer) ? int(P.material[j]) : prm.wall_material;
        boundary_share += W * P.mass[j] / prm.materials[mb].eos.rest_density;
        continue;
      }
      const Real V = P.mass[j] / P.density[j];
      vsum += (W * V) * P.velocity[j];
      A[0][0] += W * V;
      if constexpr (!WithDensity) continue;
      const Real F = K::f_inv(rr, Real(1) / h);  // grad_g W_gj = F r
      const int mat = P.material[j];
      const Real m = mat == ref ? P.mass[j] : V * eos.density_at(prm.materials[mat].eos.pressure(P.density[j]));
      rhs[0] += m * W;
      for (int a = 0; a < D; ++a) {
        A[0][1 + a] -= r[a] * W * V;
        A[1 + a][0] += F * r[a] * V;
        rhs[1 + a] += m * F * r[a];
        for (int k = 0; k < D; ++k) A[1 + a][1 + k] -= F * r[a] * r[k] * V;
      }
    }
  });
  const Real shepard = A[0][0];
  if (!(shepard > Real(0))) return Real(0);
  velocity = (Real(1) / shepard) * vsum;
  if constexpr (!WithDensity) return shepard;
  const Real shepard_density = rhs[0] / shepard;
  // The gradient block once rho_g is eliminated: the Schur complement S = A_gg - A_g0 A_0g / A_00
  // (dimensionless; about the identity in a full support). Its smallest singular value is the gain
  // with which the fluid around x_g resolves the gradient in its worst direction.
  Real S[D][D];
  for (int a = 0; a < D; ++a)
    for (int k = 0; k < D; ++k) S[a][k] = A[1 + a][1 + k] - A[1 + a][0] * A[0][1 + k] / shepard;
  const Real gain = smallest_singular_value<D>(S);
  Real x[N] = {};
  const Real det = solve_small<N>(A, rhs, x);
  if (std::fabs(det) >= Real(1e-3) && gain >= kMdbcMinGradientGain) {
    density = x[0];
    for (int a = 0; a < D; ++a) density -= offset[a] * x[1 + a];  // (x_b - x_g) . grad rho_g
  } else {
    density = shepard_density;
  }
  return shepard;
}

// mDBC (English et al. 2022, physics.md C5) for walls and structures. Each boundary particle b
// has a ghost node x_g = x_b + n_b mirrored across the wall surface into the fluid; its density is
// the fluid's extrapolated from there (ghost_interpolation); with no fluid near, rest density.
// A ghost node is dry, and b gets rest density, when fluid fills less than mdbc_wet_share (1/2) of
// the part of its kernel support that boundary particles do not fill: walls above a free surface
// would otherwise carry the surface's pressure upwards and push the water away from the wall along
// the contact line (a 3D tank at rest kept 0.05-0.2 m/s there; 0.03-0.1 m/s with the test).
// The test needs no geometry: in a corner the walls fill most of the support and the fluid the rest.
// Like our DBC walls, rho_b never falls below the density of zero absolute pressure (rest density
// without background pressure; TaitEos::no_tension_density).
// No-slip: the velocity the viscous terms see at the particle (field viscous_velocity) becomes
// 2 v_wall - v~_g, v~_g the fluid velocity at the ghost node, so that it goes through v_wall at the
// wall surface (English et al. 2022; Adami et al. 2012, C6); continuity keeps the wall's own
// velocity (mirroring the normal component there doubled the compression in front of a cylinder
// and let fluid through). Fixed walls: v_wall = 0; moving structures carry their rigid velocity;
// free-slip walls, which no viscous term reads, their own. With DBC walls (density = false) the
// pass sets only the no-slip velocity (the full viscous stress asks for it, PhysicsParams::wall_no_slip).
template <int D, class K, bool UniformH>
struct MdbcPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  bool no_slip = true;
  bool density = true;  // false: DBC walls, whose density continuity keeps

  TURBID_HD void operator()(std::uint32_t b) const {
    const std::uint8_t kind = P.kind[b];
    if (!solid_kind(kind)) return;
    const Real rho0 = prm.materials[prm.wall_material].eos.rest_density;
    const Vec<D> n = P.boundary_normal[b];
    const Real h_b = UniformH ? prm.smoothing_length : P.smoothing_length[b];
    Real rho = rho0;
    Vec<D> v_ghost = Vec<D>::zero();
    if (norm2(n) > Real(0)) {
      Real walls = 0;
      const Vec<D> xg = P.position[b] + n;
      if (density) {
        const Real fluid = ghost_interpolation<D, K, UniformH>(P, G, prm, xg, n, h_b, prm.wall_material, rho, v_ghost,
                                                               walls);
        if (fluid < prm.mdbc_wet_share * (Real(1) - walls)) rho = rho0;
      } else {
        ghost_interpolation<D, K, UniformH, false>(P, G, prm, xg, n, h_b, prm.wall_material, rho, v_ghost, walls);
      }
    }
    const Real rho_min = prm.materials[prm.wall_material].eos.no_tension_density();
    if (density) P.density[b] = rho > rho_min ? rho : rho_min;
    // 2 v_wall - v~_g; a fixed wall has v_wall = 0, a moving structure its rigid velocity.
    const bool free_slip = P.free_slip && P.free_slip[b];
    if (no_slip) P.viscous_velocity[b] = free_slip ? P.velocity[b] : Real(2) * P.velocity[b] - v_ghost;
  }
};

// Velocity an inlet prescribes at x: along the zone's axis, uniform or parabolic across the
// zone's transverse extent (4 s (1 - s) per transverse axis, scaled so that the mean over the
// cross-section is the zone's velocity: x 3/2 in 2D, x 9/4 in 3D).
template <int D>
TURBID_HD inline Vec<D> zone_velocity(const BufferZone& z, const Vec<D>& x) {
  Real u = z.velocity;
  if (z.profile == Profile::parabolic) {
    for (int a = 0; a < D; ++a) {
      if (a == z.axis) continue;
      Real s = (x[a] - z.lo[a]) / (z.hi[a] - z.lo[a]);
      s = s < Real(0) ? Real(0) : (s > Real(1) ? Real(1) : s);
      u *= Real(6) * s * (Real(1) - s);  // 4 s (1 - s) / (2/3)
    }
  }
  Vec<D> v = Vec<D>::zero();
  v[z.axis] = z.sign * u;
  return v;
}

// Buffer particles of open boundaries (see BufferZone): ghost = the particle mirrored across the
// zone's plane. Inlet: prescribed velocity, density extrapolated from the fluid (rest density
// when no fluid is near). Outlet: rest density, the fluid's velocity at the ghost (unchanged when
// no fluid is near).
template <int D, class K, bool UniformH>
struct BufferPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;

  TURBID_HD void operator()(std::uint32_t b) const {
    if (P.kind[b] != std::uint8_t(Kind::buffer)) return;
    const BufferZone& z = prm.zones[P.zone[b]];
    // The particle's own material: an inlet's, or that of the fluid particle that entered an outlet.
    const Real rho0 = prm.materials[P.material[b]].eos.rest_density;
    const Vec<D> xb = P.position[b];
    Vec<D> n = Vec<D>::zero();
    n[z.axis] = Real(2) * (z.plane - xb[z.axis]);
    const Real h_b = UniformH ? prm.smoothing_length : P.smoothing_length[b];
    Real rho = rho0;
    Vec<D> v_ghost = P.velocity[b];
    Real walls = 0;
    const bool found =
        ghost_interpolation<D, K, UniformH>(P, G, prm, xb + n, n, h_b, P.material[b], rho, v_ghost, walls) > Real(0);
    if (z.type == ZoneType::inlet) {
      P.density[b] = found ? rho : rho0;
      P.velocity[b] = zone_velocity<D>(z, xb);
    } else {
      P.density[b] = rho0;
      P.velocity[b] = v_ghost;
    }
  }
};

// Force of the fluid on every structure particle b: minus the sum over fluid neighbours i of
// m_i times the acceleration the momentum pass gives i because of b (momentum_pair, the same
// function with the same arguments), so the forces on structures and fluid cancel to rounding.
// With PhysicsParams::wall_loads, on every wall particle too (load sensors on walls). The
// implicit viscous reaction (viscous_load) is kept for structures only.
template <int D, class K, bool UniformH>
struct StructureForcePass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;

  TURBID_HD void operator()(std::uint32_t b) const {
    Vec<D> f = Vec<D>::zero();
    const bool wall = prm.wall_loads && P.kind[b] == std::uint8_t(Kind::wall);
    if (P.kind[b] != std::uint8_t(Kind::structure) && !wall) {
      P.structure_force[b] = f;
      return;
    }
    const Vec<D> xb = P.position[b];
    int c[D] = {};
    if (G.cell_of(xb, c) && G.fluid_near(c)) {
      for_each_neighbour<D>(P, G, NeighbourList{}, prm, b, xb, [&](std::uint32_t i, const Vec<D>& rbi, Real r2) {
        if (P.kind[i] != std::uint8_t(Kind::fluid)) return;
        const Real h_i = UniformH ? prm.smoothing_length : P.smoothing_length[i];
        const MaterialParams& Mi = prm.materials[P.material[i]];
        const Real mu_i = P.effective_viscosity ? P.effective_viscosity[i] : Mi.dynamic_viscosity;
        const Vec<D> rib = Real(-1) * rbi;
        const Vec<D> a = momentum_pair<D, K, UniformH>(P, prm, P.velocity[i], P.density[i], P.pressure[i], h_i, Mi, mu_i,
                                                       b, rib, r2);
        f -= P.mass[i] * a;
      });
    }
    // The implicit viscous updates' load on b for this step (sph/implicit_viscosity.hpp).
    if (P.viscous_load) f += P.viscous_load[b];
    // The impulse of the last drift's put-backs off b (WallConstraintLoadPass).
    if (P.constraint_force) f += P.constraint_force[b];
    P.structure_force[b] = f;
  }
};

// Impermeable walls (issue #27 item 9). DBC and mDBC keep fluid out of walls by pressure alone,
// and a film that arrives thin and fast, or fluid in tension, can pass through before that pressure
// builds (docs/validation.md, W). After the drift, the boundary particles within `band` of fluid
// particle i's nearest decide, by i's signed distance to each one's surface,
//   s_b = (x_i - x_b) . n_b - |g_b| / 2,   n_b = g_b / |g_b|
// (g_b the ghost offset, twice b's depth below the surface: boundary_normal). i is behind the wall
// when it is behind some of those surfaces (s_b < 0; e the one it is least behind) and no surface
// it is in front of (s_b' >= 0) meets them at a convex edge, that is with every one of them behind
// the plane of b' (beside a box's side face, behind the plane of its top row, i is outside; above
// the floor but inside a box standing on it, a concave junction, i is inside; the diagonal ghost
// offsets of a tank's edge particles are among those it is behind there, not all of them). fsi/wall_penetration.cpp counts by
// the same rule. i is then put on e's surface, x_i -= s_e n_e, and its velocity into that wall,
// relative to e's, removed (an inelastic stop; the tangential velocity is kept). Fluid in front of
// the walls is untouched, so the pass changes nothing in flows that keep out of walls on their own.
// The neighbours are those of the step's start: walls move less than a spacing per step.
// The momentum the stop takes from i, m_i (v_after - v_before) over all its pushes, is kept in
// put_back_impulse with the boundary particle it goes to (put_back_from: the one whose push took
// the most normal speed, or the first pushed off when none took any), for WallConstraintLoadPass to
// book on walls and structures: the fluid loses no momentum that they do not receive.
inline constexpr std::uint32_t kNoPutBack = 0xffffffffu;

template <int D>
struct WallConstraintPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  NeighbourList L;
  unsigned long long* put_back = nullptr;  // fluid particles put back on a surface (one per drift)

  TURBID_HD static bool boundary(std::uint8_t k) { return solid_kind(k); }

  // The surface of boundary particle j: unit normal n (its ghost offset's direction) and half the
  // offset's length (the surface lies there in front of x_j). False without an offset.
  TURBID_HD bool surface(std::uint32_t j, Vec<D>& n, Real& half) const {
    const Vec<D> g = P.boundary_normal[j];
    const Real gl = std::sqrt(norm2(g));
    if (!(gl > Real(0))) return false;
    n = (Real(1) / gl) * g;
    half = Real(0.5) * gl;
    return true;
  }

  TURBID_HD void operator()(std::uint32_t i) const {
    if (P.kind[i] != std::uint8_t(Kind::fluid)) return;
    if (P.put_back_from) P.put_back_from[i] = kNoPutBack;
    int c[D] = {};
    if (G.cell_of(P.position[i], c) && !G.boundary_near(c)) return;  // most fluid: no wall within a cell
    // Pushes in turn: in a concave corner (the floor meeting an end wall) a particle behind both
    // is first put on the surface it is least behind and is then still behind the other, whose
    // plane does not have the first one's particles behind it. The corner's own particles have
    // diagonal ghost offsets, a surface across the corner, which takes a push of its own: 2 D
    // rounds bring a particle out of a corner of D faces (tested in 2D; 0 left in the 3D box case,
    // docs/validation.md W).
    const Vec<D> v_before = P.velocity[i];
    std::uint32_t from = kNoPutBack;
    Real largest = Real(-1);
    for (int round = 0; round < 2 * D; ++round) {
      std::uint32_t j = 0;
      Real taken = 0;
      if (!push_out(i, j, taken)) break;
      if (round == 0 && put_back) count_one(put_back);
      if (taken > largest) {
        largest = taken;
        from = j;
      }
    }
    if (from == kNoPutBack || !P.put_back_from) return;
    P.put_back_from[i] = from;
    P.put_back_impulse[i] = P.mass[i] * (P.velocity[i] - v_before);
  }

  // Puts i on the surface it is least behind unless it is in front of every surface near it or
  // outside a convex edge; true when it moved. `from`: the boundary particle of that surface;
  // `taken`: the normal speed into it removed (0 when i was moving away from it).
  TURBID_HD bool push_out(std::uint32_t i, std::uint32_t& from, Real& taken) const {
    const Vec<D> xi = P.position[i];
    // The nearest boundary particle, and whether i is behind any surface near it at all (most
    // fluid beside a wall is in front of every one: one loop then).
    Real nearest2 = Real(-1);
    bool behind_any = false;
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
      if (!boundary(P.kind[j])) return;
      if (nearest2 < Real(0) || r2 < nearest2) nearest2 = r2;
      const Vec<D> g = P.boundary_normal[j];
      behind_any = behind_any || dot(rij, g) < Real(0.5) * norm2(g);  // s_j < 0, times |g_j|
    });
    if (!behind_any || nearest2 > prm.wall_constraint_reach * prm.wall_constraint_reach) return false;
    const Real reach = std::sqrt(nearest2) + prm.wall_constraint_band;
    const Real reach2 = reach * reach;
    // Behind by less than this is on the surface: a particle just put on one is not behind it for
    // float rounding (positions of O(1) m hold ~1e-7 m).
    const Real on_surface = Real(1e-3) * prm.wall_constraint_band;
    // The surfaces i is behind (up to kMaxBehind of them), and the one it is least behind.
    constexpr int kMaxBehind = 24;
    std::uint32_t behind_j[kMaxBehind];
    int behind = 0;
    Real exit_s = Real(0);
    Vec<D> exit_n{};
    std::uint32_t exit_j = 0;
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
      Vec<D> n;
      Real half;
      if (!boundary(P.kind[j]) || r2 > reach2 || !surface(j, n, half)) return;
      const Real s = dot(rij, n) - half;
      if (!(s < -on_surface)) return;
      if (behind == 0 || s > exit_s) {
        exit_s = s;
        exit_n = n;
        exit_j = j;
      }
      if (behind < kMaxBehind) behind_j[behind] = j;
      ++behind;
    });
    if (behind == 0) return false;
    const int kept = behind < kMaxBehind ? behind : kMaxBehind;
    // In front of a surface whose plane has every surface i is behind behind it (a convex edge, as
    // beside a box's side face below its top): outside the wall. At a concave junction some of
    // them (the floor's, below a box standing on it) are in front of that plane. "Behind" here by
    // more than dx/4: a tank's edge particle has a diagonal ghost offset whose plane passes
    // through the floor particle next to it (behind it by 0 and rounding: a concave corner, not a
    // convex edge), while a convex edge's other face lies dx/2 or more behind.
    const Real edge_margin = Real(0.5) * prm.wall_constraint_band;
    bool outside = false;
    for_each_neighbour<D>(P, G, L, prm, i, xi, [&](std::uint32_t j, const Vec<D>& rij, Real r2) {
      Vec<D> n;
      Real half;
      if (outside || !boundary(P.kind[j]) || r2 > reach2 || !surface(j, n, half)) return;
      if (dot(rij, n) - half < -on_surface) return;
      bool all_behind = true;
      for (int k = 0; k < kept && all_behind; ++k)
        all_behind = dot(P.position[behind_j[k]] - P.position[j], n) - half < -edge_margin;
      outside = all_behind;
    });
    if (outside) return false;
    P.position[i] = xi - exit_s * exit_n;
    const Real vn = dot(P.velocity[i] - P.velocity[exit_j], exit_n);
    if (vn < Real(0)) P.velocity[i] -= vn * exit_n;
    from = exit_j;
    taken = vn < Real(0) ? -vn : Real(0);
    return true;
  }
};

// The constraint's reaction (issue #47 item 1): each wall and structure particle b receives minus
// the momentum put-backs took from the fluid particles booked to it (WallConstraintPass), as a
// force over the step, and the kinetic energy they removed, as a power. A gather over b's fluid
// neighbours, before the sort (put_back_from holds indices of this order): each fluid particle is
// booked to exactly one b, so the fluid and the boundary exchange the same momentum to rounding,
// without atomics, in the same order on every backend. The particle put back lies within 1.6 dx of
// the surface particle it was pushed off, well inside the support 2h where b looks for it.
// Kinetic energy removed from i: with J = m (v_after - v_before),
//   1/2 m |v_before|^2 - 1/2 m |v_after|^2 = |J|^2 / (2 m) - v_after . J.
// `counts`: [0] put-backs since bind, [1] the same before this drift; on a drift without any
// (most of them) b only writes zeros.
template <int D>
struct WallConstraintLoadPass {
  ParticleView<D> P;
  GridView<D> G;
  PhysicsParams prm;
  Real inv_dt;
  const unsigned long long* counts;

  TURBID_HD void operator()(std::uint32_t b) const {
    if (!WallConstraintPass<D>::boundary(P.kind[b])) return;
    Vec<D> f = Vec<D>::zero();
    Real power = 0;
    int c[D] = {};
    if (counts[0] != counts[1] && G.cell_of(P.position[b], c) && G.fluid_near(c)) {
      for_each_neighbour<D>(P, G, NeighbourList{}, prm, b, P.position[b], [&](std::uint32_t i, const Vec<D>&, Real) {
        if (P.kind[i] != std::uint8_t(Kind::fluid) || P.put_back_from[i] != b) return;
        const Vec<D> J = P.put_back_impulse[i];
        f -= J;
        power += norm2(J) / (Real(2) * P.mass[i]) - dot(P.velocity[i], J);
      });
    }
    P.constraint_force[b] = inv_dt * f;
    P.constraint_power[b] = inv_dt * power;
  }
};

// counts[1] = counts[0]: the put-backs before a drift (one thread).
struct MarkPutBacksPass {
  unsigned long long* counts;
  TURBID_HD void operator()(std::uint32_t) const { counts[1] = counts[0]; }
};

}  // namespace turbid::sph
