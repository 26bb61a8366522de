// motion: bullet. Rigid bodies integrated by the Bullet physics library (double precision, pkg-config
// bullet-float64) inside the fluid's kick-drift-kick step; the rest of the engine sees them as the
// built-in bodies do, through a RigidBody that mirrors Bullet's state (body_coupling.hpp).
//
// Bullet is optional: without it (TURBID_ENABLE_BULLET=OFF or no libbullet-dev) this header is the
// same, bullet_available() is false and constructing a BulletWorld throws kNoBulletMessage.
//
// The world: one btDiscreteDynamicsWorld (btDbvtBroadphase, btSequentialImpulseConstraintSolver),
// one btRigidBody per bullet structure, never deactivated (a settling floating body would otherwise
// be put to sleep by Bullet's sleeping thresholds and stop responding to the fluid).
//
// Frames. turbid's body frame is the world's axes at t = 0 with its origin at the centre of mass
// (rigid_body.hpp); Bullet wants a diagonal inertia, so the Bullet body's frame is the principal
// frame at the centre of mass: its basis is R_t P, P the principal axes (columns, turbid body frame,
// det +1), and its local inertia the principal moments. P = 1 (the moments the diagonal of I) when I
// is diagonal to 1e-12 of its trace, so an axis-aligned body keeps its axes, and always in 2D, where
// only I_zz enters planar motion. The collision shape sits in a btCompoundShape at its own offset
// from that frame (a primitive's centre need not be the centre of mass).
//
// Shapes: box (btBoxShape), sphere (btSphereShape), cylinder (btCylinderShapeZ, the axis along the
// primitive's z), meshes a convex hull of the surface points (btConvexHullShape). 2D shapes are the
// 3D ones extruded over one metre of depth, z in [-0.5, 0.5] m (2D masses are per metre of depth):
// a box's third half extent 0.5 m, a circle a cylinder along z. The collision margin is Bullet's
// 0.04 m or a tenth of the body's smallest extent if smaller.
//
// Contacts are Bullet's (collision detection, impulse-based contact with restitution and Coulomb
// friction, solved with the step). A body takes part in contacts when its structure has a contact
// material (`contact:`), as a free body does: it then touches the other bullet bodies with one and
// the scene's obstacles, the same ContactWorld the DEM contacts use (scene_interactions.hpp): a
// container face or polyline segment as a slab behind the face (a box 2 dx thick: a body moves far
// less than dx in a step, so nothing tunnels through it), a solid box as its box, a fixed structure as the spheres of its
// surface layer (dx/2, as in the DEM contacts; its exact sphere for a sphere or 2D cylinder), a
// prescribed structure likewise as a kinematic body that follows its path. In 2D
// every obstacle spans z in [-1, 1] m. Bullet's contacts are rigid: a material's restitution and
// friction are used, its Young's modulus and Poisson ratio are not (they set the DEM contacts'
// stiffness). A pair takes the smaller restitution and the smaller friction of its two sides (the
// DEM rule; an obstacle without a material takes the body's); Bullet gives no restitution below an
// approach speed of 0.2 m/s (its m_restitutionVelocityThreshold). Bullet bodies do not touch free
// (built-in) bodies. The contact force on a body (its impulses over the
// step / dt) goes to forces.csv as a free body's does.
//
// Locks: Bullet's linear and angular factors (world axes), 2D adds z translation and x, y rotation
// locked, as for free bodies. A linear factor 0 is exact (force and constraint impulses are
// multiplied by it). An angular factor 0 is exact only about a principal axis (Bullet multiplies the
// torque, then applies the world inverse inertia), so a 3D body with some rotations locked must have
// the locked axes principal (refused otherwise, std::invalid_argument); its gyroscopic term is then
// switched off, which is exact for that constrained motion (the locks take the gyroscopic torque).
//
// Stepping: one stepSimulation(dt, 0) per fluid step. maxSubSteps = 0 makes Bullet take exactly one
// internal step of length dt (fixedTimeStep = dt, no sub-stepping, no interpolation, no time left
// over in m_localTime: with maxSubSteps >= 1 and fixedTimeStep = dt, the fluid's varying dt would
// leave or borrow remainders and sometimes take 0 or 2 steps). One internal step is symplectic
// Euler: the constraint solver integrates the velocities first, v += dt (F/m + g_body), w += dt
// I_w^-1 T (+ the implicit gyroscopic impulse, + constraint and contact impulses), then the
// positions with the new velocities, x += dt v, q = exp(dt w / 2) q. Then Bullet clears the forces.
//
// Loads are impulses: kick(duration, loads) adds duration x (load + springs evaluated now) to each
// body's accumulator, and step(dt) passes accumulator / dt as the external force and torque
// (applyCentralForce / applyTorque, torque about the centre of mass). How this lines up with the
// fluid's kick-drift-kick step (body_coupling.hpp, docs/choices.md):
//   - the coupling kicks with the fluid's two half-kicks, (dt_{n-1}/2) F(n) and (dt_n/2) F(n), and
//     steps Bullet right after the second of them (the step's first half-kick, before the fluid's
//     continuity pass); Bullet's velocity is then the half-step velocity
//     v(n+1/2) = v(n-1/2) + (dt_{n-1} + dt_n)/2 F(n)/m and x(n+1) = x(n) + dt_n v(n+1/2): symplectic
//     Euler read on a staggered grid is the leapfrog, the same translation as the built-in KDK step
//     (to rounding) and second order; weight_by_bullet = false puts m g into the same kicks;
//   - used alone (weight_by_bullet = true, one kick of dt then a step of dt), it is Bullet's own
//     symplectic Euler with the velocity on the integer steps, whose free fall lies dt g t / 2 below
//     the exact parabola.
// Rotation is Bullet's (exponential map of the new angular velocity, implicit gyroscopic term in the
// body frame): first order in 3D for a tumbling body; in 2D (one axis, no gyroscopic term) it is the
// built-in step.
//
// Constraints (ConstraintSpec, world coordinates at t = 0): an end is a bullet body's point, or a
// fixed anchor (end.structure = -1 or a structure that does not move). Springs are our own linear
// spring and dashpot (spring_damper.hpp) applied as external forces: evaluated from Bullet's state
// at each kick (positions x(n), the damper at Bullet's velocity) and added to the impulses, so a
// spring is kicked as the fluid load is. Hinges are btHingeConstraint (pivot and axis in the Bullet
// frames), solved by Bullet's impulse solver with its default error reduction; 2D hinges must turn
// about z. A constraint with no bullet end is left to the caller; one between a bullet and a
// motion: free body is refused (std::invalid_argument): the two integrators cannot share it.
//
// Physics only: no I/O. Not thread-safe; one world per Simulation.
#pragma once
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fsi/body_contacts.hpp"
#include "fsi/mass_properties.hpp"
#include "fsi/rigid_body.hpp"
#include "fsi/scene.hpp"
#include "geometry/mesh.hpp"

namespace turbid::fsi {

inline constexpr const char* kNoBulletMessage =
    "this turbid was built without Bullet; install libbullet-dev and rebuild (or use 'motion: free')";

// True when this build links Bullet (double precision).
bool bullet_available();

// A bullet body's collision shape, as placed at t = 0 (world frame).
struct BulletShape {
  enum class Kind { box, sphere, cylinder, hull };
  Kind kind = Kind::box;
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  // box [m] (2D: the third is ignored)
  double radius = 0;                                        // sphere, cylinder [m]
  double half_length = 0;                                   // cylinder, along its own z [m] (2D: ignored)
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();         // the primitive's centre [m]
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();       // the primitive's axes (columns)
  std::vector<Eigen::Vector3d> points;                      // hull: surface points [m]
};

struct BulletBodySpec {
  std::size_t structure = 0;        // index in Scene::structures (constraints name bodies by it)
  MassProperties mass_properties;   // turbid's, about the centre of mass, world axes at t = 0
  DofMask mask;                     // free degrees of freedom, world axes (2D: planar locks added)
  BulletShape shape;
  std::optional<ContactMaterial> contact;  // none: the body touches nothing
};

// A body's state in turbid's conventions: centre of mass, orientation body frame -> world (the body
// frame being the world's axes at t = 0), velocity and angular velocity (world).
struct BulletBodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
};

class BulletWorld {
 public:
  // dims 2 or 3; gravity [m/s^2]. weight_by_bullet: Bullet applies m g every step (Bullet's own
  // integrator); false: the bodies have no Bullet gravity and the caller's loads carry the weight
  // (the coupling, which kicks with fluid + m g). Bodies start at rest at their centres of mass.
  // other_moving[structure]: a structure moved by someone else (motion free or prescribed); a
  // constraint tying one to a bullet body is refused. Missing entries: fixed.
  // Throws std::invalid_argument (a bad mass, inertia, lock or constraint) or std::runtime_error
  // (kNoBulletMessage) when built without Bullet.
  // obstacles: what bodies with a contact material touch besides each other (nullptr: nothing).
  BulletWorld(int dims, const Eigen::Vector3d& gravity, const std::vector<BulletBodySpec>& bodies,
              const std::vector<ConstraintSpec>& constraints, bool weight_by_bullet,
              const std::vector<bool>& other_moving = {}, const ContactWorld* obstacles = nullptr);
  ~BulletWorld();
  BulletWorld(const BulletWorld&) = delete;
  BulletWorld& operator=(const BulletWorld&) = delete;

  std::size_t body_count() const;
  // The body of structure `structure`, or -1.
  int body_of(std::size_t structure) const;
  bool has(std::size_t structure) const { return body_of(structure) >= 0; }
  // Constraints this world took (those with at least one bullet end): springs, hinges.
  std::size_t spring_count() const;
  std::size_t hinge_count() const;

  // Adds duration x (loads[structure] + spring forces at the current state) to each body's impulse.
  // loads is indexed by structure (entries of non-bullet structures ignored); wrenches about the
  // centre of mass, world frame [N], [N m].
  void kick(double duration, const std::vector<Wrench>& loads);
  // One Bullet step of dt with force = impulse / dt, torque = angular impulse / dt; clears the impulses.
  void step(double dt);

  // The contact wrench on a body in the last step (its contact and friction impulses / dt, about
  // the centre of mass the solver used, world frame) [N], [N m], and the deepest penetration
  // Bullet's collision detection found in that step, before its correction [m] (0 when none).
  Wrench contact_load(std::size_t structure) const;
  // Prescribed structures among the obstacles are kinematic bodies: move_prescribed puts each where
  // where(structure) says for the next step (Bullet gives it the velocity of that move over the
  // step: the path's mean velocity); place_prescribed puts it there at rest in the path (a resumed
  // run, so that the next step's move starts from there).
  void move_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where);
  void place_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where);
  double last_max_penetration() const;

  BulletBodyState state(std::size_t structure) const;
  // Puts a body in this state (velocities projected on its free axes) and clears its impulse.
  void set_state(std::size_t structure, const BulletBodyState& s);

  // The mirror a RigidBody keeps of a Bullet body (same mass properties): x, q, v exactly as Bullet
  // has them (q converted to turbid's frame), L = R I0 R^T w.
  void write_mirror(std::size_t structure, RigidBody& mirror) const;
  // Only the velocities (v, L = R I0 R^T w with the mirror's own R), the mirror keeping x and q.
  void write_mirror_velocity(std::size_t structure, RigidBody& mirror) const;
  // The reverse (a resumed run): Bullet takes the mirror's x, q, v and w = I^-1 L.
  void read_mirror(std::size_t structure, const RigidBody& mirror);

  // The exact state Bullet keeps for a body, for checkpoints: its transform's basis (row-major) and
  // origin, velocity, angular velocity and the impulses gathered since the last step (24 numbers).
  // Restoring it gives a resumed run the same bits as an uninterrupted one as long as Bullet holds
  // nothing else for the body: true without hinges and contacts, whose solver caches (warm-start
  // impulses) are not saved.
  std::vector<double> exact_state(std::size_t structure) const;
  void restore_exact_state(std::size_t structure, const std::vector<double>& state);  // 24 numbers, else invalid_argument

  // The principal frame Bullet uses for a body: the axes P (columns, turbid's body frame) and moments.
  Eigen::Matrix3d principal_axes(std::size_t structure) const;
  Eigen::Vector3d principal_moments(std::size_t structure) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The collision shape of a structure as the scene places it; `mesh`: its loaded mesh (mesh shapes).
BulletShape bullet_shape(const StructureSpec& st, int dims, const geometry::TriangleMesh* mesh);

// The coupled world of a scene's bullet structures (weight through the kicks): mass[k] the mass
// properties of structure k as the run uses them (given for every bullet structure), meshes[k] its
// mesh (mesh shapes; may be empty otherwise), surface[k] the surface layer of structure k (fixed
// structures as obstacles; scene_interactions.hpp). Errors name the structure's or constraint's
// file:line:column (std::invalid_argument), or say kNoBulletMessage there when built without Bullet.
std::unique_ptr<BulletWorld> make_bullet_world(const Scene& scene, const std::vector<std::optional<MassProperties>>& mass,
                                               const std::vector<geometry::TriangleMesh>& meshes,
                                               const std::vector<std::vector<Eigen::Vector3d>>& surface = {});

}  // namespace turbid::fsi
