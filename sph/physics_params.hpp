// Plain, device-copyable parameters of the fluid model for one run (materials, kernel, options).
#pragma once
#include <cstdint>

#include "sph/config.hpp"
#include "sph/eos.hpp"
#include "sph/kernels.hpp"
#include "sph/rheology.hpp"

namespace turbid::sph {

inline constexpr int kMaxMaterials = 8;

enum class Diffusion : std::uint8_t { none, molteni, antuono, fourtakas };
enum class Viscosity : std::uint8_t { artificial, laminar };
// Wall treatment: the dynamic boundary condition (boundary particles integrate continuity like
// fluid) or the modified DBC of English et al. (2022), whose boundary density is extrapolated from
// the fluid at a ghost node mirrored across the wall (physics.md C5).
enum class Boundary : std::uint8_t { dbc, mdbc };

inline constexpr std::uint8_t kNoBody = 0xff;  // body index of particles that belong to no structure
inline constexpr int kMaxBodies = 254;

// Particle kinds; the kind field is a u8.
enum class Kind : std::uint8_t { fluid = 0, wall = 1, structure = 2, buffer = 3 };

// Open boundaries: buffer zones beside the fluid (Tafuni et al. 2018, simplified). Buffer particles
// (kind buffer) move with their velocity; at an inlet it is prescribed and the density is
// extrapolated from the fluid across the zone's plane; at an outlet the density is the rest
// density (pressure p_b) and the velocity the fluid's, interpolated at the mirrored point.
inline constexpr int kMaxZones = 4;
inline constexpr std::uint8_t kNoZone = 0xff;
enum class ZoneType : std::uint8_t { inlet, outlet };
enum class Profile : std::uint8_t { uniform, parabolic };

struct BufferZone {
  ZoneType type = ZoneType::inlet;
  Profile profile = Profile::uniform;
  int axis = 0;           // flow axis
  Real sign = 1;          // +1: the flow goes towards +axis
  Real plane = 0;         // the zone's face towards the fluid, along axis [m]
  Real thickness = 0;     // extent of the zone along axis [m]
  Real velocity = 0;      // inlet: mean velocity [m/s]
  Real lo[3] = {0, 0, 0}; // the zone's box [m] (transverse extent of the parabolic profile)
  Real hi[3] = {0, 0, 0};
  std::uint8_t material = 0;  // material of the fluid an inlet creates
};

struct MaterialParams {
  TaitEos eos;
  Real sound_speed;        // c0 [m/s]
  Real dynamic_viscosity;  // mu [Pa s]; non-Newtonian: the largest mu_eff allowed (the cap)
  Rheology rheology;       // mu_eff(shear rate); Newtonian: consistency = mu, no yield stress
  bool non_newtonian = false;
  // Its laminar viscous terms (between two of its particles, and with boundary particles) are
  // integrated implicitly (sph/implicit_viscosity.hpp), the others explicitly in the momentum pass.
  bool implicit_viscosity = false;
  // Its laminar viscous terms take the central pair form (pair::ViscousPair: the divergence of
  // mu (grad v + grad v^T) + mu (div v) I), else Morris' Laplacian form div(mu grad v). A pair of
  // two materials takes the central form if either has it; a pair with a boundary particle, the fluid's.
  bool central_stress = false;
  // Its own pairs and its pairs with boundary particles take the full deviatoric stress
  // (sph/full_stress.hpp) in the implicit update; needs implicit_viscosity.
  bool full_stress = false;
  // Smallest h among this material's particles [m], for its time-step limits; 0: the lattice's h.
  // Splitting lowers it for the materials daughters are made of.
  Real min_smoothing_length = 0;
};

struct PhysicsParams {
  int dimensions = 2;
  KernelKind kernel = KernelKind::wendland_c2;
  Diffusion diffusion = Diffusion::fourtakas;
  Viscosity viscosity = Viscosity::artificial;
  Boundary boundary = Boundary::dbc;
  bool wall_no_slip = false;   // boundary velocity in viscous terms mirrors the fluid's (no-slip), else stays the wall's
  // Impermeable walls (WallConstraintPass): after the drift a fluid particle behind the surface of
  // every wall or structure particle near it is put back on that surface (needs boundary_normal).
  bool wall_constraint = false;
  Real wall_constraint_band = Real(0);  // boundary particles within nearest + band decide [m] (dx / 2)
  // Farther than this from every boundary particle a fluid particle is inside no wall [m] (dx: a
  // point behind a surface of a wall built on the lattice is within sqrt(D)/2 dx of one of its
  // particles). Without it a particle beside a box's corner, 4 dx off, saw only the top row's
  // plane and was put on it.
  Real wall_constraint_reach = Real(0);
  // Wall function: fluid sliding along a wall or structure (not a free-slip wall) feels the wall
  // shear stress rho u*^2 of the log law (pair::wall_friction_velocity2), spread over the fluid
  // particles by the wall's kernel gradient; with laminar viscosity it replaces the viscous pair
  // terms with boundary particles (needs boundary_normal). Off: walls act through the viscosity alone.
  bool wall_function = false;
  // Artificial viscosity between fluid and boundary particles takes the approach along the
  // boundary particle's normal, (v_ij . n)(r_ij . n), instead of v_ij . r_ij: fluid sliding along a
  // wall of particles approaches each wall particle ahead of it and leaves each behind, and the
  // viscosity, which acts only on approach, pushed it off the wall and back (needs boundary_normal).
  bool wall_viscosity_normal = false;
  Real wall_roughness_length = Real(0);  // z_r = k_s / 30 [m]; 0: hydraulically smooth
  Real wall_function_min_distance = Real(0);  // y is held at this or more [m] (dx / 10)
  Real mdbc_wet_share = Real(0.5);  // mDBC: a ghost node with less fluid than this share of its support is dry
  // Some walls are free-slip: their particles carry the `free_slip` field, and the viscous terms
  // (laminar viscosity, velocity gradient) leave them out.
  bool free_slip_walls = false;
  int body_count = 0;          // structures (particles of kind structure carry their index in `body`)
  // Wall particles get the force of the fluid on them too (StructureForcePass, field
  // structure_force), for load sensors on walls (fsi/probes.cpp, probe type wall_load).
  bool wall_loads = false;
  int zone_count = 0;          // open-boundary buffer zones (buffer particles carry their index in `zone`)
  BufferZone zones[kMaxZones];
  Real diffusion_delta = Real(0.1);
  Real artificial_viscosity = Real(0.01);
  // Particle shifting (Lind et al. 2012, coefficient form of Skillen et al. 2013): fluid particles
  // drift with v + u_s, u_s = -A h |v| grad C. A = 0: off (no pass, no field).
  Real shifting_coefficient = 0;
  // A particle whose position divergence div r = -sum_j V_j r_ij . grad_i W_ij (= D inside the
  // fluid) is below this is at a free surface and is not shifted; 0: no detection (internal flows).
  Real shifting_surface_threshold = 0;
  Real smoothing_length = 0;   // h of the initial lattice [m]
  bool uniform_h = true;       // every particle has h == smoothing_length (fast path)
  Real max_smoothing_length = 0;  // largest h present [m]; the neighbour search covers 2 h_max
  Real gravity[3] = {0, 0, 0}; // [m/s^2]
  // Gravity less its components along periodic axes (a uniform driving force there, no head):
  // the hydrostatic density difference of Fourtakas' diffusion uses this [m/s^2].
  Real hydrostatic_gravity[3] = {0, 0, 0};
  // Periodic axes: period[a] > 0 is the domain's length along a; particles leaving through one
  // face re-enter through the other at periodic_origin[a] + period[a].
  bool periodic = false;
  Real period[3] = {0, 0, 0};         // [m]
  Real periodic_origin[3] = {0, 0, 0}; // [m]
  Real periodic_end[3] = {0, 0, 0};    // the domain's upper face, as the sort tests it [m]
  // Some material is not Newtonian: a rheology pass computes each fluid particle's shear rate and
  // effective viscosity before the momentum pass (fields shear_rate, effective_viscosity, shear_stress).
  bool rheology = false;
  // The scene has transitions: particles may split (sph/splitting.hpp; field split_fresh).
  bool splitting = false;
  // The paper's ghost-density correction of density diffusion between fluids of different
  // materials (seed paper eq. 3); off: no diffusion across an interface.
  bool interface_correction = false;
  // Some material's viscous terms are implicit: the solver runs the implicit viscous update each
  // step (conjugate gradients to a relative residual of implicit_tolerance, at most
  // implicit_max_iterations iterations).
  bool implicit_viscosity = false;
  bool full_stress = false;  // some material has MaterialParams::full_stress
  Real implicit_tolerance = Real(1e-5);
  int implicit_max_iterations = 500;
  int material_count = 0;
  int wall_material = 0;       // EOS used for wall particles' pressure
  bool uniform_sound_speed = false;  // every material has the same c0 (pair loops skip the lookup)
  MaterialParams materials[kMaxMaterials];
};

}  // namespace turbid::sph
