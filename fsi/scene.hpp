// The plain description of a run that the engine executes. tools/ fills it from a YAML file;
// tests and benchmarks build it in code. SI units throughout. No I/O here.
#pragma once
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sph/kernels.hpp"

namespace turbid::fsi {

using Vec3d = std::array<double, 3>;  // 2D scenes leave the third component 0

// Where a value came from, so that errors found after parsing can still name file:line:column.
struct SourceLocation {
  std::string file;
  int line = 0;    // 1-based; 0 when the value was not read from a file
  int column = 0;  // 1-based
};

enum class DiffusionKind { none, molteni, antuono, fourtakas };
enum class ViscosityKind { artificial, laminar };
// How the laminar viscous terms are integrated: auto, implicitly for a non-Newtonian material
// whose largest viscosity would put the explicit viscous limit below the acoustic one, explicitly
// otherwise; explicit or implicit: every material that way (docs/choices.md).
enum class ViscousIntegration { automatic, explicit_, implicit };
// The laminar viscous stress (docs/choices.md): auto (for now Morris' Laplacian form div(mu grad v)
// for every material); full: the full deviatoric stress 2 mu D' (sph/full_stress.hpp, integrated
// implicitly) for every material; laplacian; or the central pair form (sph::pair::ViscousPair),
// whose limit is the divergence of mu (grad v + grad v^T) + mu (div v) I.
enum class ViscousStress { automatic, laplacian, central, full };
enum class BoundaryKind { dbc, mdbc };  // wall treatment; see docs/choices.md

// A material's rheology (physics.md C8): newtonian (viscosity), bingham (yield_stress and the
// plastic viscosity in `viscosity`), or herschel_bulkley (yield_stress, consistency, flow_index);
// the yield-stress models are regularised by Papanastasiou's exponent m.
struct MaterialSpec {
  std::string name;
  std::string model = "newtonian";  // newtonian | bingham | herschel_bulkley
  double density = 1000.0;          // rest density rho0 [kg/m^3]
  double viscosity = 1.0e-3;        // dynamic viscosity [Pa s]; bingham: plastic viscosity mu_B
  double yield_stress = 0.0;        // tau_y [Pa]
  double consistency = 0.0;         // herschel_bulkley: K [Pa s^n]
  double flow_index = 1.0;          // herschel_bulkley: n [-]
  double papanastasiou_exponent = 0.0;  // m [s]
  double max_viscosity = 0.0;       // cap on mu_eff [Pa s]; 0 = automatic (docs/choices.md)
  double sound_speed = 0.0;         // c0 [m/s]; 0 = automatic (10 x sqrt(2 g H_max))
  double gamma = 7.0;               // Tait exponent [-]
  double background_pressure = 0.0; // p_b [Pa]
  SourceLocation where;
};

struct Box {
  Vec3d min{0, 0, 0};
  Vec3d max{0, 0, 0};
};

// A velocity field: along one axis (`axis`, `sign`), uniform or parabolic across a box's
// transverse extent (mean `mean`; the parabola vanishes on the box faces parallel to the axis).
struct VelocityProfile {
  bool given = false;
  int axis = 0;
  int sign = 1;
  bool parabolic = false;
  double mean = 0;  // [m/s]
};

// 3D scenes extrude 2D cross-sections: a fluid polygon or a polyline wall is given in the vertical
// x-z plane (vertex = (x, z, 0), the plane's two coordinates in the first two slots, as in 2D) and
// spans y from span[0] to span[1]. A flume's cross-section is what experiments draw, and this keeps
// one polygon/polyline code path for both dimensions.
struct FluidBlock {
  std::string material;
  Box box;                       // the region; for a polygon its bounding box (3D: y from `span`)
  std::vector<Vec3d> polygon;    // the region is this polygon (>= 3 vertices) instead of `box`:
                                 // 2D vertices (x, y, 0); 3D the cross-section, vertices (x, z, 0)
  std::array<double, 2> span{0, 0};  // 3D polygon: its extent across y [m] (min, max)
  VelocityProfile initial_velocity;  // across this block's box; none: at rest
  SourceLocation where;
};

// An open boundary: a buffer zone (a box beside the fluid) whose particles feed the flow (inlet,
// prescribed velocity) or let it leave (outlet, pressure p_b). `direction` is the flow's.
struct OpenBoundarySpec {
  std::string name;
  bool inlet = true;
  Box box;
  VelocityProfile velocity;  // inlet: required; outlet: the direction only
  std::string material;      // inlet: the fluid it creates (default: the first material)
  SourceLocation where;
};

struct WallSpec {
  enum class Kind {
    container,  // layers of particles outside the faces of `box` (a tank); faces in `open` are left out
    solid_box,  // `box` filled with boundary particles (an obstacle); with `layers`, only a shell that thick
    polyline,   // a chain of segments through `points`, layers on the side given by `side`
                // (3D: the cross-section in the x-z plane, repeated across y over `span`)
  };
  Kind kind = Kind::container;
  Box box;
  // container faces left open, in the order -x, +x, -y, +y, -z, +z
  std::array<bool, 6> open{false, false, false, false, false, false};
  std::vector<Vec3d> points;  // polyline vertices: 2D (x, y, 0); 3D (x, z, 0) in the x-z plane
  std::array<double, 2> span{0, 0};  // 3D polyline: its extent across y [m] (min, max)
  bool closed = false;        // polyline: connect the last point to the first
  int side = -1;              // polyline: layers on the right (-1) or left (+1) of the direction of travel
  int layers = 0;             // number of particle layers; 0 = enough for the kernel support (solid_box: full)
  bool free_slip = false;     // slip: free, the fluid slides along it (no viscous stress); default no-slip
  SourceLocation where;
};

// DEM contact material of a moving structure (fsi/contact.hpp): Hertz normal force with a damping
// that gives `restitution`, Coulomb friction `friction` through a tangential spring. A structure
// without it (given = false) takes part in no contact. A bullet body's contacts are Bullet's rigid
// ones (fsi/bullet_world.hpp): restitution and friction only, youngs_modulus optional (0: not given).
struct ContactMaterialSpec {
  bool given = false;
  double youngs_modulus = 0;  // E [Pa]
  double poisson_ratio = 0.3; // nu [-]
  double restitution = 0.5;   // e [-], in (0, 1]
  double friction = 0.5;      // Coulomb mu [-]
  SourceLocation where;
};

// motion: prescribed (fsi/prescribed_path.hpp): the structure's displacement d(t) from its scene
// position and its rotation R(t) about its reference point, given as a constant velocity, a
// sinusoidal oscillation or samples over time. Internal units: m, s, rad (the scene gives degrees).
struct PrescribedPathSpec {
  enum class Kind { velocity, oscillation, samples };
  enum class Interpolation { spline, linear };  // samples: clamped cubic spline (default) or piecewise linear
  Kind kind = Kind::velocity;
  Vec3d velocity{0, 0, 0};           // velocity: d(t) = v t [m/s]
  Vec3d angular_velocity{0, 0, 0};   // velocity: R(t) = exp(t [w]x), w in the world frame [rad/s]
  Vec3d amplitude{0, 0, 0};          // oscillation: d(t) = A (sin(2 pi t / T + phi) - sin phi) [m]
  Vec3d angular_amplitude{0, 0, 0};  // oscillation: angles about x, y, z the same way [rad]
  double period = 0;                 // oscillation: T [s]
  double phase = 0;                  // oscillation: phi [rad]
  std::vector<double> times;         // samples: strictly increasing [s]
  std::vector<Vec3d> displacement;   // samples: d at each time [m]
  std::vector<Vec3d> angles;         // samples: angles about x, then y, then z (R = Rz Ry Rx) [rad]
  Interpolation interpolation = Interpolation::spline;
  std::string source;                // samples: the CSV file they came from (messages); empty: inline
  SourceLocation where;
};

// A structure: a solid sampled into boundary particles (kind structure), fixed, free (the built-in
// rigid-body integrator, fsi/rigid_body.hpp, coupled to the fluid by fsi/body_coupling.hpp),
// prescribed (moved along a given path) or bullet (moved by the Bullet physics library). The
// fluid force on it is reported in forces.csv.
struct StructureSpec {
  enum class Shape { box, sphere, cylinder, mesh };
  enum class Motion { fixed, free, prescribed, bullet };
  std::string name;
  Shape shape = Shape::box;
  Vec3d size{0, 0, 0};      // box: extents [m]
  double radius = 0;        // sphere, cylinder [m] (a circle in 2D)
  double length = 0;        // cylinder: length along its axis (z before rotation) [m]; unused in 2D
  std::string file;         // mesh: STL, OBJ or PLY, as given in the scene
  std::string resolved_file;  // mesh: the path to open (relative paths are relative to the scene file)
  Vec3d position{0, 0, 0};  // translation of the shape's centre (mesh: of its own origin) [m]
  Vec3d rotation_deg{0, 0, 0};  // about x, then y, then z [deg]; 2D: about z only
  double scale = 1.0;       // multiplies the shape's dimensions (mesh: its coordinates)
  int layers = 0;           // particle layers inside the surface; 0 = enough for the kernel support
  Vec3d reference_point{0, 0, 0};  // torques are taken about this point [m] (default: position)
  // Drag and lift coefficients, when `has_coefficients`: drag along flow_direction, lift along
  // lift_direction; C = 2 F / (rho U^2 A) with A = reference_length in 2D (per metre of depth) and
  // reference_area in 3D.
  bool has_coefficients = false;
  Vec3d flow_direction{1, 0, 0};  // unit vector
  Vec3d lift_direction{0, 1, 0};  // unit vector, perpendicular to flow_direction
  double reference_velocity = 0;  // [m/s]
  double reference_density = 0;   // [kg/m^3]
  double reference_length = 0;    // [m]
  double reference_area = 0;      // [m^2] (3D)
  // motion: free. Mass properties from the solid's filled sampling at the scene's spacing and
  // `density`, or from `mass` (then a uniform density mass / volume for the defaults); an explicit
  // centre of mass and inertia tensor replace the sampled ones. A free body's torques (forces.csv)
  // are about its moving centre of mass.
  Motion motion = Motion::fixed;
  double density = 0;              // [kg/m^3]; 0 = not given
  double mass = 0;                 // [kg] (2D: kg/m); 0 = not given
  bool has_centre_of_mass = false;
  Vec3d centre_of_mass{0, 0, 0};   // [m]
  bool has_inertia = false;
  // About the centre of mass, world axes at t = 0, row-major [kg m^2] (2D: only I_zz, [kg m^2/m])
  std::array<double, 9> inertia{0, 0, 0, 0, 0, 0, 0, 0, 0};
  std::array<bool, 3> lock_translation{false, false, false};  // x, y, z locked
  std::array<bool, 3> lock_rotation{false, false, false};     // rx, ry, rz locked
  ContactMaterialSpec contact;     // moving structures: DEM contacts with walls and other structures
  PrescribedPathSpec path;         // motion: prescribed; torques about the moving reference point
  SourceLocation where;
};

// A constraint on moving structures (motion: free or bullet), from the scene's `constraints:` list.
// Each end is a point of a structure or a fixed anchor, given in world coordinates at t = 0 (a
// structure's point then moves rigidly with it).
struct ConstraintEndSpec {
  int structure = -1;        // index in Scene::structures; -1 = a fixed anchor
  Vec3d point{0, 0, 0};      // world position at t = 0 [m]
};
struct ConstraintSpec {
  enum class Type {
    spring,  // linear spring and dashpot between the two ends (fsi/spring_damper.hpp)
    hinge,   // the two ends' points stay together; relative rotation only about `axis`
  };
  Type type = Type::spring;
  std::string name;
  ConstraintEndSpec a;
  ConstraintEndSpec b;
  double stiffness = 0;        // spring: k [N/m] (2D: N/m per metre of depth)
  double damping = 0;          // spring: c [N s/m] (2D: per metre of depth)
  double rest_length = -1;     // spring: L0 [m]; < 0 = the ends' distance at t = 0
  Vec3d axis{0, 0, 1};         // hinge: unit axis, world frame at t = 0
  SourceLocation where;
};

struct ProbeSpec {
  enum class Type {
    front_position,  // largest coordinate along `axis` reached by fluid of `material` [m]
    pressure,        // kernel (Shepard) interpolated fluid pressure at `point` [Pa]
    max_speed,       // largest fluid particle speed [m/s]
    kinetic_energy,  // total fluid kinetic energy [J] (per metre of depth in 2D)
    fluid_particles, // number of fluid particles [-]
    // free-surface elevation at a station [m], as a wave gauge reads it: the lowest height above the
    // bed at which the interpolated fluid fraction along the vertical `axis` through `point` drops
    // below one half (a splash above the water column does not count), see fsi/probes.cpp
    surface_elevation,
    material_mass,   // total mass of the fluid of `material` [kg] (per metre of depth in 2D: kg/m)
    // the highest fluid particle (of `material`) horizontally within dx of the station plus dx/2 [m]:
    // surface_elevation's definition before issue #25 (a splash or jet reads as water level)
    highest_particle,
    // pressure as a load cell behind a wall reads it [Pa]: the fluid's force on the wall and
    // structure particles behind a face on the wall surface (centred on `point`, normal
    // `sensor_normal` into the fluid, diameter `sensor_diameter`: a segment in 2D, a disc in 3D),
    // pair forces and the impermeable-wall pass's impulse, normal to the face, over its area
    wall_load,
  };
  std::string name;
  Type type = Type::max_speed;
  std::string material;  // front_position, surface_elevation: empty = any fluid; material_mass: required
  int axis = 0;          // front_position: 0 = x, 1 = y, 2 = z; surface_elevation: the vertical
                         // (up is +axis; the reader sets the last axis, y in 2D, z in 3D)
  Vec3d point{0, 0, 0};  // pressure: the point; surface_elevation: the station (its `axis` component unused)
  // pressure: the least kernel sum sum_j W_ij V_j of fluid at the point (1 inside the fluid, about
  // 0.5 on a flat wall, 0.25 in a corner) for a reading; below it the probe writes nan. One stray
  // particle at the point gives 0.14 (2D) or 0.05 (3D) with h = 2 dx.
  double min_kernel_sum = 0.2;
  // pressure as a wall sensor reads it: the average over a face of this diameter [m] centred on
  // `point` and normal to `sensor_normal` (a segment in 2D, a disc in 3D), air counted at ambient 0
  // (fsi/probes.cpp); min_kernel_sum does not apply. 0: the pressure at the point. wall_load: its
  // face (required).
  double sensor_diameter = 0;
  Vec3d sensor_normal{1, 0, 0};
  SourceLocation where;
};

// The debris-flow -> turbidity-current transition (seed paper sect. II.C): a particle of material
// `from` whose effective shear stress sqrt(J2(tau)) passes the threshold splits into 2^D
// daughters of material `to` (sph/splitting.hpp).
struct TransitionSpec {
  std::string from;
  std::string to;                     // same reference density as `from` (splitting conserves density)
  double shear_stress_threshold = 0;  // [Pa]
  bool interface_only = true;         // where: interface (a fluid neighbour of another material) | anywhere
  int levels = 1;                     // how many times a particle may split (daughters of level < levels split again)
  SourceLocation where;
};

// Room reserved before the run for the particles splitting creates.
struct CapacitySpec {
  std::size_t max_particles = 0;  // > 0: this many particles in all
  double factor = 2.0;            // else: factor x the initial particle count
  bool error_when_full = false;   // on_full: error (stop the run) | warn (refuse the splits, go on)
  SourceLocation where;
};

struct OutputSpec {
  double every = 0.0;           // output interval [s]; 0 = only the initial and final state
  bool vtk = true;              // write particles_NNNN.vtp and particles.pvd
  double checkpoint_every = 0;  // [s]; 0 = no checkpoints
  double forces_every = 0;      // forces.csv interval [s]; 0 = at every output (every step if every = 0)
  bool forces_each_step = false;  // forces_every: step (a row after every time step)
  double probes_every = 0;      // probes.csv interval [s]; 0 = at every output
  bool probes_each_step = false;  // probes_every: step (a row after every time step)
};

struct NumericsSpec {
  sph::KernelKind kernel = sph::KernelKind::wendland_c2;
  DiffusionKind diffusion = DiffusionKind::fourtakas;
  double diffusion_delta = 0.1;            // delta of the density diffusion term [-]
  ViscosityKind viscosity = ViscosityKind::artificial;
  double artificial_viscosity = 0.01;      // Monaghan alpha [-]
  // Artificial viscosity with boundary particles acts on the approach along the wall's normal only
  // (sph::PhysicsParams::wall_viscosity_normal); false: on the pair's approach, as between fluid.
  // Unset: along the normal with mDBC walls, the pair's with DBC (docs/choices.md, "Artificial
  // viscosity at walls").
  std::optional<bool> artificial_wall_normal;
  ViscousIntegration viscous_integration = ViscousIntegration::automatic;
  ViscousStress viscous_stress = ViscousStress::automatic;
  double cfl = 0.2;                        // Courant number for the acoustic and force limits [-]
  double viscous_dt_factor = 0.125;        // dt <= factor h^2 / nu_max (Morris et al. 1997)
  double min_time_step = 1.0e-9;           // a smaller dt stops the run as collapsed [s]
  double density_ratio_limit = 0.5;        // |rho/rho0 - 1| above this stops the run [-]
  // More fluid particles than this behind a wall or structure surface at an output stops the run
  // (fsi/wall_penetration.hpp); unset: counted and reported only.
  std::optional<std::uint64_t> max_fluid_behind_walls;
  SourceLocation max_fluid_behind_walls_where;
  BoundaryKind boundary = BoundaryKind::dbc;  // wall treatment for walls and structures
  // Walls and structures show the viscous terms the fluid's velocity mirrored at their ghost nodes
  // (no-slip at the wall surface); unset: yes where a material has the full viscous stress.
  std::optional<bool> no_slip;
  // Wall function (sph::PhysicsParams::wall_function): the log law's wall shear for fluid sliding
  // along walls and structures, with the walls' equivalent sand roughness k_s [m] (0: smooth).
  bool wall_function = false;
  double wall_roughness = 0;
  SourceLocation wall_function_where;
  // Fluid that crossed a wall or structure surface is put back on it after each drift
  // (sph::WallConstraintPass); `boundary: {impermeable: false}` leaves walls to their pressure alone.
  bool impermeable = true;
  bool interface_correction = true;        // ghost-density correction across material interfaces (paper eq. 3)
  int split_relaxation = 10;               // relaxation steps after each split (sph/splitting.hpp); 0 = off
  double shifting_coefficient = 0;         // particle shifting A [-]; 0 = off
  double shifting_surface_threshold = -1;  // div r below this: free surface, not shifted; < 0: D - 0.5
};

struct Scene {
  std::string name;
  std::string source_file;  // the YAML file, for messages; empty when built in code
  std::string base_directory;  // relative file names (meshes) are relative to this directory
  int dimensions = 2;
  double particle_spacing = 0.01;  // dx [m]
  double smoothing_ratio = 2.0;    // h = smoothing_ratio * dx; Wendland C2 needs h/dx near 2 on a lattice (docs/validation.md)
  double end_time = 1.0;           // [s]
  Vec3d gravity{0, -9.81, 0};      // [m/s^2]
  NumericsSpec numerics;
  std::vector<MaterialSpec> materials;
  std::vector<FluidBlock> fluids;
  std::vector<WallSpec> walls;
  std::vector<StructureSpec> structures;
  std::vector<ConstraintSpec> constraints;
  std::vector<OpenBoundarySpec> open_boundaries;
  std::vector<ProbeSpec> probes;
  std::vector<TransitionSpec> transitions;
  CapacitySpec capacity;  // used when the scene has transitions
  OutputSpec output;
  // Particles leaving this box are removed and counted. Default: the bounding box of all
  // initial particles, grown by 10% of its size on every side.
  std::optional<Box> domain;
  // Axes along which the domain is periodic (needs `domain`; its extent is the period).
  std::array<bool, 3> periodic{false, false, false};
};

// Index of the material named `name` in scene.materials, or -1.
inline int material_index(const Scene& scene, const std::string& name) {
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    if (scene.materials[m].name == name) return int(m);
  return -1;
}

}  // namespace turbid::fsi
