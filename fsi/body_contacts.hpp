// DEM contacts of moving structures (issue #8): which surfaces touch, where, and with which law
// (fsi/contact.hpp: Hertz + Tsuji damping for the restitution, Mindlin tangential spring with
// Coulomb's cap). Deterministic: every sum runs in a fixed order (bodies, then their spheres, then
// the obstacles in scene order). No I/O here. docs/choices.md, "Constraints and contacts", says why.
//
// Representation
//  - A moving structure with a contact material contacts through spheres fixed in its body frame:
//    a sphere structure (and a 2D sphere or cylinder, a circle) as its own sphere, exact Hertz
//    geometry; any other shape as a clump of spheres of radius dx/2 centred on its surface layer's
//    particles (multi-sphere DEM), so the clump's envelope is the sampled surface.
//  - Obstacles that never move: planar faces (container faces and polyline segments; 3D: the
//    segment extruded across y), one-sided, with the wall's fluid side as normal; solid boxes as
//    boxes; fixed structures by their surface-layer particles as spheres of radius dx/2 (a fixed
//    sphere structure, and a fixed 2D cylinder, by its exact sphere).
//  - Prescribed structures (motion: prescribed) as the fixed ones, their spheres carried along the
//    path: the coupling moves them to each substep's time (move_obstacle) and a contact sees the
//    path's velocity at its point. They take no reaction (the path is imposed), like a wall.
//  - Body-body: sphere pairs of two bodies whose bounding spheres overlap, all pairs tested.
// Faces of one wall share their vertices and edges: a sphere takes every face contact of a wall
// whose foot lies inside the face, and only when it has none, the single deepest edge or vertex
// contact of that wall, so a sphere above the joint of two collinear segments is not pushed twice.
//
// Contacts of one body with one obstacle act in parallel; each takes the share of the body's mass
// that its stiffness has of theirs, so together they damp as one contact and keep the restitution.
//
// Pair parameters: E* and G* from both sides' Young's modulus and Poisson ratio (walls and fixed
// structures without a material are rigid, E = infinity); restitution and friction of a pair are the
// smaller of the two sides' (a wall without material takes the body's). m* and R* per contact from
// the sphere radii and body masses (a clump's whole mass).
//
// Tangential springs are kept per contact, keyed by (body, sphere, obstacle kind, obstacle index,
// obstacle sphere), from one evaluation to the next, and dropped when the contact ends.
#pragma once
#include <array>
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "fsi/contact.hpp"
#include "fsi/rigid_body.hpp"

namespace turbid::fsi {

struct ContactMaterial {
  double youngs_modulus = 0;  // [Pa]
  double poisson_ratio = 0.3;
  double restitution = 0.5;
  double friction = 0.5;
};

// A moving structure's contact shape, body frame (relative to the centre of mass, the world's axes
// at t = 0).
struct BodyContactShape {
  bool active = false;  // false: the structure takes part in no contact
  ContactMaterial material;
  std::vector<Eigen::Vector3d> centres;
  double radius = 0;       // of every sphere [m]
  int face_count = 1;      // spheres that can touch one plane at once (the time step's estimate)
};

// A one-sided planar face: origin + u edge_1 + w edge_2 (u, w in [0, 1]; 2D: edge_2 = 0), unit
// normal to the side where bodies are.
struct ContactFace {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d edge_1 = Eigen::Vector3d::Zero();
  Eigen::Vector3d edge_2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  int wall = 0;  // faces of one wall share edges (see above)
};

struct ContactBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();
};

// A fixed or prescribed structure as obstacle: spheres in world coordinates (a prescribed one's at
// t = 0, moved by BodyContacts::move_obstacle).
struct FixedContactShape {
  std::vector<Eigen::Vector3d> centres;
  double radius = 0;
  std::optional<ContactMaterial> material;  // none: rigid, the body's restitution and friction
  int prescribed = -1;                      // the structure of a prescribed obstacle; -1: fixed
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // a prescribed obstacle's reference point at t = 0 [m]
};

// Where a prescribed obstacle is at some time: its reference point, its rotation from t = 0 (about
// the reference point), the reference point's velocity and the angular velocity (world).
struct ObstacleMotion {
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
};

struct ContactWorld {
  int dims = 2;
  double spacing = 0;                     // the scene's particle spacing dx [m] (0: unknown)
  std::vector<ContactFace> faces;         // grouped by wall, walls in scene order
  std::vector<ContactBox> boxes;
  std::vector<FixedContactShape> fixed;   // one per fixed or prescribed structure (any order, kept)
};

// Contact key: body, its sphere, obstacle kind (0 face, 1 box, 2 fixed structure, 3 body), obstacle
// index, obstacle sphere.
using ContactKey = std::array<int, 5>;

class BodyContacts {
 public:
  // shapes: one per structure in scene order (inactive for fixed structures and bodies without a
  // material); masses: the bodies' masses (0 where inactive). Throws std::invalid_argument.
  BodyContacts(std::vector<BodyContactShape> shapes, const std::vector<double>& masses, ContactWorld world);

  bool any() const { return active_count_ > 0; }
  const BodyContactShape& shape(std::size_t k) const { return shapes_[k]; }
  // Puts the prescribed obstacle fixed[j] of the ContactWorld where `m` says, for the evaluations that follow
  // (its spheres x_ref + R (c0 - x_ref0), the velocity at a contact point v + w x (p - x_ref)).
  void move_obstacle(std::size_t j, const ObstacleMotion& m);
  // Moves every prescribed obstacle to where(structure).
  void move_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where);

  // Adds the contact wrench on every body to `out` (one per structure, about its centre of mass).
  // `dt` advances the tangential springs (0: evaluate only, as at the start of a step's substeps).
  void evaluate(const std::vector<std::optional<RigidBody>>& bodies, double dt, std::vector<Wrench>& out);

  // The largest stable body substep [s]: t_c / 50 of the stiffest contact each body may meet (see
  // docs/choices.md), at the larger of the bodies' present approach speed and the speed a body
  // gains falling through its static overlap under `loads` (the slow load: fluid + gravity).
  // `limiting` (optional) gets the structure whose contact sets it.
  double max_substep(const std::vector<std::optional<RigidBody>>& bodies, const std::vector<Wrench>& loads,
                     double gravity, std::size_t* limiting = nullptr) const;

  // Checkpoints: the tangential springs of the contacts open now.
  const std::map<ContactKey, TangentialSpring>& springs() const { return springs_; }
  void restore_springs(std::map<ContactKey, TangentialSpring> s) { springs_ = std::move(s); }

  // The deepest overlap of the last evaluation [m] (diagnostics, tests).
  double last_max_overlap() const { return last_max_overlap_; }

 private:
  struct Law {
    ContactLaw law;
    bool valid = false;
  };
  void add(const ContactLaw& law, const ContactGeometry& g, const ContactKey& key, const RigidBody& body,
           const Eigen::Vector3d& velocity_2, const RigidBody* body_2, std::size_t k, std::size_t l, double dt,
           std::vector<Wrench>& out, std::map<ContactKey, TangentialSpring>& next);

  struct Pending {  // a contact found, before its force (see evaluate)
    const ContactLaw* law = nullptr;
    ContactGeometry geometry;
    ContactKey key{};
    const RigidBody* body = nullptr;
    const RigidBody* body_2 = nullptr;  // nullptr: a wall or fixed structure
    Eigen::Vector3d velocity_2 = Eigen::Vector3d::Zero();
    std::size_t k = 0, l = 0;
  };
  std::vector<Pending> pending_;
  std::vector<BodyContactShape> shapes_;
  std::vector<double> masses_;
  std::vector<double> bounding_;      // bounding radius of each shape about the centre of mass
  ContactWorld world_;
  std::vector<Eigen::Vector3d> fixed_lo_, fixed_hi_;  // bounding boxes of the fixed shapes (now)
  std::vector<std::vector<Eigen::Vector3d>> fixed_now_;  // their spheres' centres now
  std::vector<ObstacleMotion> motion_;                   // their motion now (fixed: at rest)
  std::vector<double> obstacle_speed_;                   // the fastest point of each now [m/s]
  int active_count_ = 0;
  std::vector<Law> wall_law_;                    // per body: faces and boxes
  std::vector<std::vector<Law>> fixed_law_;      // per body, per fixed shape
  std::vector<std::vector<Law>> body_law_;       // per body pair (k < l)
  std::map<ContactKey, TangentialSpring> springs_;
  double last_max_overlap_ = 0;
};

}  // namespace turbid::fsi
