// motion: bullet: see bullet_world.hpp. Bullet's headers (and BT_USE_DOUBLE_PRECISION) stay in this file.
#include "fsi/bullet_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "fsi/scene_interactions.hpp"
#include "fsi/spring_damper.hpp"
#include "geometry/placement.hpp"

#ifdef TURBID_HAVE_BULLET
#include <btBulletDynamicsCommon.h>
#endif

namespace turbid::fsi {

// --- shared by both builds: conversions between the mirror and a state -------------------------

void BulletWorld::write_mirror(std::size_t structure, RigidBody& mirror) const {
  const BulletBodyState s = state(structure);
  const Eigen::Matrix3d R = s.orientation.toRotationMatrix();
  mirror.restore_state(s.position, s.orientation, s.velocity, R * mirror.body_inertia() * R.transpose() * s.angular_velocity);
}

void BulletWorld::write_mirror_velocity(std::size_t structure, RigidBody& mirror) const {
  const BulletBodyState s = state(structure);
  const Eigen::Matrix3d R = mirror.orientation().toRotationMatrix();
  mirror.restore_state(mirror.position(), mirror.orientation(), s.velocity,
                       R * mirror.body_inertia() * R.transpose() * s.angular_velocity);
}

void BulletWorld::read_mirror(std::size_t structure, const RigidBody& mirror) {
  BulletBodyState s;
  s.position = mirror.position();
  s.orientation = mirror.orientation();
  s.velocity = mirror.velocity();
  s.angular_velocity = mirror.angular_velocity();
  set_state(structure, s);
}

namespace {
std::string located_structure(const StructureSpec& st, const std::string& what) {
  std::string where;
  if (!st.where.file.empty())
    where = st.where.file + ":" + std::to_string(st.where.line) + ":" + std::to_string(st.where.column) + ": error: ";
  return where + "structure '" + st.name + "': " + what;
}
}  // namespace

BulletShape bullet_shape(const StructureSpec& st, int dims, const geometry::TriangleMesh* mesh) {
  geometry::Placement place;
  place.translation = st.position;
  place.rotation_deg = st.rotation_deg;
  place.scale = st.scale;
  const geometry::PlacementMap map(place);
  BulletShape sh;
  sh.centre = Eigen::Vector3d(st.position[0], st.position[1], dims == 3 ? st.position[2] : 0.0);
  for (int c = 0; c < 3; ++c) {
    geometry::Point e{0, 0, 0};
    e[std::size_t(c)] = 1;
    const geometry::Point r = map.rotate(e);
    sh.axes.col(c) = Eigen::Vector3d(r[0], r[1], r[2]);
  }
  switch (st.shape) {
    case StructureSpec::Shape::box:
      sh.kind = BulletShape::Kind::box;
      sh.half_extents = 0.5 * st.scale * Eigen::Vector3d(st.size[0], st.size[1], st.size[2]);
      break;
    case StructureSpec::Shape::sphere:
      sh.kind = BulletShape::Kind::sphere;
      sh.radius = st.scale * st.radius;
      break;
    case StructureSpec::Shape::cylinder:
      sh.kind = BulletShape::Kind::cylinder;
      sh.radius = st.scale * st.radius;
      sh.half_length = 0.5 * st.scale * st.length;
      break;
    case StructureSpec::Shape::mesh:
      sh.kind = BulletShape::Kind::hull;
      if (!mesh) throw std::invalid_argument("a bullet mesh body needs its mesh");
      for (const auto& v : mesh->vertices) {
        const geometry::Point p = map.apply(v);
        sh.points.emplace_back(p[0], p[1], dims == 3 ? p[2] : 0.0);
      }
      break;
  }
  return sh;
}

std::unique_ptr<BulletWorld> make_bullet_world(const Scene& scene, const std::vector<std::optional<MassProperties>>& mass,
                                               const std::vector<geometry::TriangleMesh>& meshes,
                                               const std::vector<std::vector<Eigen::Vector3d>>& surface) {
  const int d = scene.dimensions;
  std::vector<BulletBodySpec> specs;
  std::vector<bool> other_moving(scene.structures.size(), false);
  const StructureSpec* first = nullptr;
  for (std::size_t k = 0; k < scene.structures.size(); ++k) {
    const StructureSpec& st = scene.structures[k];
    if (st.motion != StructureSpec::Motion::bullet) {
      other_moving[k] = st.motion != StructureSpec::Motion::fixed;
      continue;
    }
    if (!first) first = &st;
    if (!bullet_available()) throw std::invalid_argument(located_structure(st, std::string("'motion: bullet': ") + kNoBulletMessage));
    if (k >= mass.size() || !mass[k]) throw std::invalid_argument(located_structure(st, "no mass properties"));
    BulletBodySpec spec;
    spec.structure = k;
    spec.mass_properties = *mass[k];
    for (std::size_t a = 0; a < 3; ++a) {
      spec.mask.translation[a] = !st.lock_translation[a];
      spec.mask.rotation[a] = !st.lock_rotation[a];
    }
    if (st.contact.given)
      spec.contact = ContactMaterial{st.contact.youngs_modulus, st.contact.poisson_ratio, st.contact.restitution,
                                     st.contact.friction};
    try {
      spec.shape = bullet_shape(st, d, k < meshes.size() ? &meshes[k] : nullptr);
      // Each body alone first, so that an error names its structure.
      BulletWorld single(d, Eigen::Vector3d::Zero(), {spec}, {}, false);
    } catch (const std::exception& e) {
      throw std::invalid_argument(located_structure(st, e.what()));
    }
    specs.push_back(std::move(spec));
  }
  if (!first) return nullptr;
  const Eigen::Vector3d g(scene.gravity[0], scene.gravity[1], d == 3 ? scene.gravity[2] : 0.0);
  // The obstacles of the bodies that touch (the DEM contacts' description, scene_interactions.hpp).
  std::optional<ContactWorld> obstacles;
  if (std::any_of(specs.begin(), specs.end(), [](const BulletBodySpec& b) { return b.contact.has_value(); })) {
    SurfaceLayers layers = surface;
    layers.resize(scene.structures.size());
    obstacles = contact_world(scene, layers);
  }
  return std::make_unique<BulletWorld>(d, g, specs, scene.constraints, false, other_moving,
                                       obstacles ? &*obstacles : nullptr);
}

#ifdef TURBID_HAVE_BULLET

static_assert(sizeof(btScalar) == sizeof(double), "turbid links Bullet in double precision (pkg-config bullet-float64)");

bool bullet_available() { return true; }

namespace {

btVector3 to_bt(const Eigen::Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }
Eigen::Vector3d from_bt(const btVector3& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
btQuaternion to_bt(const Eigen::Quaterniond& q) { return btQuaternion(q.x(), q.y(), q.z(), q.w()); }
Eigen::Quaterniond from_bt(const btQuaternion& q) { return Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()); }
btMatrix3x3 to_bt_matrix(const Eigen::Matrix3d& m) {
  return btMatrix3x3(m(0, 0), m(0, 1), m(0, 2), m(1, 0), m(1, 1), m(1, 2), m(2, 0), m(2, 1), m(2, 2));
}

constexpr double kHalfDepth2d = 0.5;  // 2D shapes span one metre of depth
constexpr double kObstacleHalfDepth2d = 1.0;  // 2D obstacles reach beyond the bodies' depth
constexpr double kBulletMargin = 0.04;
constexpr double kTouchDistance = 1e-6;  // [m] contact processing threshold, see the constructor
// Friction of an obstacle without a material: above any body's, so that the pair takes the body's.
constexpr double kRigidFriction = 1e30;

// Collision groups: bodies with a contact material touch each other and the obstacles; bodies
// without one touch nothing.
constexpr int kContactGroup = 1 << 6;
constexpr int kObstacleGroup = 1 << 7;
constexpr int kSilentGroup = 1 << 8;

// A pair's restitution and friction: the smaller of its two sides' (the DEM rule, body_contacts.hpp).
btScalar smaller_restitution(const btCollisionObject* a, const btCollisionObject* b) {
  return std::min(a->getRestitution(), b->getRestitution());
}
btScalar smaller_friction(const btCollisionObject* a, const btCollisionObject* b) {
  return std::min(a->getFriction(), b->getFriction());
}

double margin_for(double smallest_extent) { return std::min(kBulletMargin, 0.1 * smallest_extent); }

struct Body {
  std::size_t structure = 0;
  MassProperties mp;
  DofMask mask;
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity();  // principal axes, columns, turbid body frame
  Eigen::Quaterniond qP = Eigen::Quaterniond::Identity();
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  std::unique_ptr<btCollisionShape> child;
  std::unique_ptr<btCompoundShape> compound;
  std::unique_ptr<btRigidBody> rigid;
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_impulse = Eigen::Vector3d::Zero();
  Wrench contact;  // of the last step
  Eigen::Vector3d com_before = Eigen::Vector3d::Zero();  // the centre of mass the last step's solver used
};

// A spring end: a body (its point relative to the centre, turbid's body frame) or a world anchor.
struct SpringEnd {
  int body = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};
struct Spring {
  SpringEnd a, b;
  SpringDamper law;
};

std::string located(const ConstraintSpec& c, const std::string& what) {
  std::string where;
  if (!c.where.file.empty())
    where = c.where.file + ":" + std::to_string(c.where.line) + ":" + std::to_string(c.where.column) + ": ";
  if (!where.empty()) where += "error: ";
  return where + "constraint" + (c.name.empty() ? std::string() : " '" + c.name + "'") + ": " + what;
}

}  // namespace

struct BulletWorld::Impl {
  int dims = 3;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  bool weight_by_bullet = true;
  std::unique_ptr<btDefaultCollisionConfiguration> config;
  std::unique_ptr<btCollisionDispatcher> dispatcher;
  std::unique_ptr<btDbvtBroadphase> broadphase;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver;
  std::unique_ptr<btDiscreteDynamicsWorld> world;
  std::vector<std::unique_ptr<Body>> bodies;
  std::vector<int> by_structure;
  std::vector<Spring> springs;
  std::vector<std::unique_ptr<btTypedConstraint>> hinges;
  std::vector<std::unique_ptr<btCollisionShape>> obstacle_shapes;  // children first, then their compounds
  std::vector<std::unique_ptr<btRigidBody>> obstacles;
  std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;         // of the kinematic obstacles
  std::vector<std::pair<std::size_t, btRigidBody*>> kinematic;             // (structure, body)
  double max_penetration = 0;

  ~Impl() {
    if (!world) return;
    for (auto& h : hinges) world->removeConstraint(h.get());
    for (auto& b : bodies)
      if (b->rigid) world->removeRigidBody(b->rigid.get());
    for (auto& o : obstacles) world->removeRigidBody(o.get());
  }

  const Body& body_of(std::size_t structure) const {
    if (structure >= by_structure.size() || by_structure[structure] < 0)
      throw std::out_of_range("structure " + std::to_string(structure) + " is not a bullet body");
    return *bodies[std::size_t(by_structure[structure])];
  }
  Body& body_of(std::size_t structure) {
    return const_cast<Body&>(static_cast<const Impl&>(*this).body_of(structure));
  }

  BulletBodyState state(const Body& b) const {
    const btRigidBody& r = *b.rigid;
    BulletBodyState s;
    s.position = from_bt(r.getCenterOfMassPosition());
    s.orientation = (from_bt(r.getOrientation()) * b.qP.conjugate()).normalized();
    s.velocity = from_bt(r.getLinearVelocity());
    s.angular_velocity = from_bt(r.getAngularVelocity());
    return s;
  }

  void add_body(const BulletBodySpec& spec);
  void add_constraint(const ConstraintSpec& c, const std::vector<bool>& other_moving);
  void spring_impulses(double duration);
  void add_obstacles(const ContactWorld& w);
  btRigidBody& add_obstacle(std::unique_ptr<btCollisionShape> shape, const btTransform& where,
                            const std::optional<ContactMaterial>& material, bool kinematic = false);
  void collect_contacts(double dt);
};

btRigidBody& BulletWorld::Impl::add_obstacle(std::unique_ptr<btCollisionShape> shape, const btTransform& where,
                                             const std::optional<ContactMaterial>& material, bool kinematic) {
  btDefaultMotionState* state = nullptr;
  if (kinematic) {
    motion_states.push_back(std::make_unique<btDefaultMotionState>(where));
    state = motion_states.back().get();
  }
  btRigidBody::btRigidBodyConstructionInfo info(0.0, state, shape.get(), btVector3(0, 0, 0));
  info.m_startWorldTransform = where;
  auto r = std::make_unique<btRigidBody>(info);  // mass 0: static, or kinematic
  r->setContactProcessingThreshold(kTouchDistance);
  r->setRestitution(material ? material->restitution : 1.0);
  r->setFriction(material ? material->friction : kRigidFriction);
  if (kinematic) {
    r->setCollisionFlags(r->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    r->setActivationState(DISABLE_DEACTIVATION);
  }
  world->addRigidBody(r.get(), kObstacleGroup, kContactGroup);
  obstacle_shapes.push_back(std::move(shape));
  obstacles.push_back(std::move(r));
  return *obstacles.back();
}

void BulletWorld::Impl::add_obstacles(const ContactWorld& w) {
  for (const ContactFace& f : w.faces) {
    // A slab behind the face, 2 dx thick (as thick as the face is long when dx is not known): a
    // body moves far less than dx in a step, so it cannot tunnel, and a thin wall's slab stays
    // within the wall's own particle layers instead of standing out on its far side.
    const double l1 = f.edge_1.norm(), l2 = f.edge_2.norm();
    if (!(l1 > 0)) continue;
    const Eigen::Vector3d u1 = f.edge_1 / l1;
    Eigen::Vector3d u2 = dims == 2 || !(l2 > 0) ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(f.edge_2 / l2);
    Eigen::Matrix3d axes;
    axes << u1, u2, f.normal;
    if (axes.determinant() < 0) axes.col(1) = -axes.col(1);
    const double half_thick = 0.5 * (w.spacing > 0 ? std::min(std::max(l1, l2), 2 * w.spacing) : std::max(l1, l2));
    const Eigen::Vector3d half(0.5 * l1, dims == 2 ? kObstacleHalfDepth2d : 0.5 * l2, half_thick);
    Eigen::Vector3d centre = f.origin + 0.5 * f.edge_1 + (dims == 2 ? Eigen::Vector3d::Zero() : Eigen::Vector3d(0.5 * f.edge_2)) -
                             half_thick * f.normal;
    if (dims == 2) centre.z() = 0;
    auto box = std::make_unique<btBoxShape>(to_bt(half));
    box->setMargin(margin_for(2 * std::min(half.x(), half.y())));
    add_obstacle(std::move(box), btTransform(to_bt_matrix(axes), to_bt(centre)), std::nullopt);
  }
  for (const ContactBox& b : w.boxes) {
    Eigen::Vector3d half = 0.5 * (b.max - b.min);
    Eigen::Vector3d centre = 0.5 * (b.max + b.min);
    if (dims == 2) {
      half.z() = kObstacleHalfDepth2d;
      centre.z() = 0;
    }
    auto box = std::make_unique<btBoxShape>(to_bt(half));
    box->setMargin(margin_for(2 * (dims == 2 ? std::min(half.x(), half.y()) : half.minCoeff())));
    add_obstacle(std::move(box), btTransform(btMatrix3x3::getIdentity(), to_bt(centre)), std::nullopt);
  }
  for (const FixedContactShape& f : w.fixed) {
    if (f.centres.empty() || !(f.radius > 0)) continue;
    // One shared sphere (2D: a cylinder along z) at every centre.
    std::unique_ptr<btCollisionShape> child;
    if (dims == 2) {
      child = std::make_unique<btCylinderShapeZ>(btVector3(f.radius, f.radius, kObstacleHalfDepth2d));
      child->setMargin(margin_for(2 * f.radius));
    } else {
      child = std::make_unique<btSphereShape>(f.radius);
    }
    // A prescribed obstacle's spheres sit about its reference point, its body's origin.
    const bool moving = f.prescribed >= 0;
    Eigen::Vector3d origin = moving ? f.reference : Eigen::Vector3d::Zero();
    if (dims == 2) origin.z() = 0;
    auto compound = std::make_unique<btCompoundShape>(true, int(f.centres.size()));
    for (const auto& c : f.centres) {
      Eigen::Vector3d local = c - origin;
      if (dims == 2) local.z() = 0;
      compound->addChildShape(btTransform(btMatrix3x3::getIdentity(), to_bt(local)), child.get());
    }
    obstacle_shapes.push_back(std::move(child));
    btRigidBody& r = add_obstacle(std::move(compound), btTransform(btMatrix3x3::getIdentity(), to_bt(origin)), f.material, moving);
    if (moving) kinematic.emplace_back(std::size_t(f.prescribed), &r);
  }
}

void BulletWorld::Impl::collect_contacts(double dt) {
  for (auto& b : bodies) b->contact = Wrench{};
  max_penetration = 0;
  btDispatcher& d = *world->getDispatcher();
  auto add = [&](int index, const btVector3& at, const Eigen::Vector3d& J) {
    if (index < 0) return;
    Body& b = *bodies[std::size_t(index)];
    const Eigen::Vector3d r = from_bt(at) - b.com_before;
    b.contact.force += J / dt;
    b.contact.torque += r.cross(J) / dt;
  };
  for (int m = 0; m < d.getNumManifolds(); ++m) {
    const btPersistentManifold& pm = *d.getManifoldByIndexInternal(m);
    const int ia = pm.getBody0()->getUserIndex(), ib = pm.getBody1()->getUserIndex();
    for (int c = 0; c < pm.getNumContacts(); ++c) {
      const btManifoldPoint& pt = pm.getContactPoint(c);
      max_penetration = std::max(max_penetration, double(-pt.getDistance()));
      // The impulses the solver applied to body 0 (its normal points from body 1 to body 0).
      const Eigen::Vector3d J = from_bt(pt.m_normalWorldOnB * pt.getAppliedImpulse() +
                                        pt.m_lateralFrictionDir1 * pt.m_appliedImpulseLateral1 +
                                        pt.m_lateralFrictionDir2 * pt.m_appliedImpulseLateral2);
      add(ia, pt.getPositionWorldOnA(), J);
      add(ib, pt.getPositionWorldOnB(), -J);
    }
  }
}

void BulletWorld::Impl::add_body(const BulletBodySpec& spec) {
  auto b = std::make_unique<Body>();
  b->structure = spec.structure;
  b->mp = spec.mass_properties;
  b->mask = spec.mask;
  if (dims == 2) {
    b->mask.translation[2] = false;
    b->mask.rotation[0] = b->mask.rotation[1] = false;
  }
  const MassProperties& mp = b->mp;
  if (!(mp.mass > 0) || !std::isfinite(mp.mass))
    throw std::invalid_argument("the mass of a bullet body must be positive and finite, got " + std::to_string(mp.mass));
  const Eigen::Matrix3d& I = mp.inertia;
  if (!I.allFinite() || (I - I.transpose()).norm() > 1e-12 * I.norm())
    throw std::invalid_argument("the inertia tensor of a bullet body must be finite and symmetric");
  const double trace = I.trace();
  const double off = std::abs(I(0, 1)) + std::abs(I(0, 2)) + std::abs(I(1, 2));
  if (dims == 2 || off <= 1e-12 * std::abs(trace)) {
    // Diagonal (or 2D, where only I_zz enters planar motion): the body keeps turbid's axes.
    b->P.setIdentity();
    b->moments = I.diagonal();
  } else {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
    b->P = eig.eigenvectors();
    if (b->P.determinant() < 0) b->P.col(2) = -b->P.col(2);
    b->moments = eig.eigenvalues();
  }
  b->qP = Eigen::Quaterniond(b->P).normalized();
  if (!(b->moments.minCoeff() > 0))
    throw std::invalid_argument("the principal moments of inertia of a bullet body must be positive");
  const bool any_rotation_locked = !(b->mask.rotation[0] && b->mask.rotation[1] && b->mask.rotation[2]);
  if (dims == 3 && any_rotation_locked) {
    for (int a = 0; a < 3; ++a) {
      if (b->mask.rotation[std::size_t(a)]) continue;
      for (int c = 0; c < 3; ++c)
        if (c != a && std::abs(I(a, c)) > 1e-9 * std::abs(trace))
          throw std::invalid_argument(std::string("a bullet body can lock a rotation only about a principal axis of its "
                                                  "inertia; the ") + "xyz"[a] +
                                      " axis is not (use 'motion: free', whose integrator handles any locked axis)");
    }
  }

  // Collision shape in the Bullet body's frame (principal axes at the centre of mass).
  const BulletShape& sh = spec.shape;
  const Eigen::Matrix3d Pt = b->P.transpose();
  double smallest = 0;
  switch (sh.kind) {
    case BulletShape::Kind::box: {
      Eigen::Vector3d h = sh.half_extents;
      if (dims == 2) h.z() = kHalfDepth2d;
      smallest = 2 * (dims == 2 ? std::min(h.x(), h.y()) : h.minCoeff());
      b->child = std::make_unique<btBoxShape>(to_bt(h));
      break;
    }
    case BulletShape::Kind::sphere:
    case BulletShape::Kind::cylinder: {
      if (dims == 2) {
        b->child = std::make_unique<btCylinderShapeZ>(btVector3(sh.radius, sh.radius, kHalfDepth2d));
        smallest = 2 * sh.radius;
      } else if (sh.kind == BulletShape::Kind::sphere) {
        b->child = std::make_unique<btSphereShape>(sh.radius);
        smallest = 0;  // a sphere's margin is its radius
      } else {
        b->child = std::make_unique<btCylinderShapeZ>(btVector3(sh.radius, sh.radius, sh.half_length));
        smallest = 2 * std::min(sh.radius, sh.half_length);
      }
      break;
    }
    case BulletShape::Kind::hull: {
      if (sh.points.size() < 3) throw std::invalid_argument("a bullet mesh body needs surface points for its hull");
      auto hull = std::make_unique<btConvexHullShape>();
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
      for (const auto& p : sh.points) {
        Eigen::Vector3d q = Pt * (p - mp.centre_of_mass);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
        if (dims == 2) {
          q.z() = -kHalfDepth2d;
          hull->addPoint(to_bt(q), false);
          q.z() = kHalfDepth2d;
        }
        hull->addPoint(to_bt(q), false);
      }
      hull->recalcLocalAabb();
      hull->optimizeConvexHull();
      const Eigen::Vector3d ext = hi - lo;
      smallest = dims == 2 ? std::min(ext.x(), ext.y()) : ext.minCoeff();
      b->child = std::move(hull);
      break;
    }
  }
  // A box's or cylinder's margin lies inside its extents; a convex hull's lies outside its vertices,
  // so a hull body would rest a margin above what it touches (5 mm for a 5 cm block with the usual
  // tenth): its margin is 1e-4 of its smallest extent, which Bullet's double-precision GJK/EPA takes.
  if (smallest > 0)
    b->child->setMargin(sh.kind == BulletShape::Kind::hull ? 1e-4 * smallest : std::min(kBulletMargin, 0.1 * smallest));
  b->compound = std::make_unique<btCompoundShape>(false, 1);
  if (sh.kind == BulletShape::Kind::hull) {
    b->compound->addChildShape(btTransform::getIdentity(), b->child.get());
  } else {
    const Eigen::Matrix3d local_axes = Pt * sh.axes;
    const Eigen::Vector3d local_centre = Pt * (sh.centre - mp.centre_of_mass);
    b->compound->addChildShape(btTransform(to_bt_matrix(local_axes), to_bt(local_centre)), b->child.get());
  }

  btRigidBody::btRigidBodyConstructionInfo info(mp.mass, nullptr, b->compound.get(), to_bt(b->moments));
  info.m_startWorldTransform = btTransform(to_bt(b->qP), to_bt(mp.centre_of_mass));
  b->rigid = std::make_unique<btRigidBody>(info);
  btRigidBody& r = *b->rigid;
  btVector3 linear, angular;
  for (int a = 0; a < 3; ++a) {
    linear[a] = b->mask.translation[std::size_t(a)] ? 1.0 : 0.0;
    angular[a] = b->mask.rotation[std::size_t(a)] ? 1.0 : 0.0;
  }
  r.setLinearFactor(linear);
  r.setAngularFactor(angular);
  r.setDamping(0, 0);
  r.setActivationState(DISABLE_DEACTIVATION);
  int flags = r.getFlags();
  if (any_rotation_locked) flags &= ~int(BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
  if (!weight_by_bullet) flags |= int(BT_DISABLE_WORLD_GRAVITY);
  r.setFlags(flags);
  if (!weight_by_bullet) r.setGravity(btVector3(0, 0, 0));
  if (spec.structure < by_structure.size() && by_structure[spec.structure] >= 0)
    throw std::invalid_argument("structure " + std::to_string(spec.structure) + " is given twice as a bullet body");
  r.setUserIndex(int(bodies.size()));  // contacts find their body by it
  r.setContactProcessingThreshold(kTouchDistance);
  if (spec.contact) {
    r.setRestitution(spec.contact->restitution);
    r.setFriction(spec.contact->friction);
    world->addRigidBody(&r, kContactGroup, kContactGroup | kObstacleGroup);
  } else {
    world->addRigidBody(&r, kSilentGroup, 0);
  }
  // (Each takes the world's gravity unless BT_DISABLE_WORLD_GRAVITY.)

  if (spec.structure >= by_structure.size()) by_structure.resize(spec.structure + 1, -1);
  by_structure[spec.structure] = int(bodies.size());
  bodies.push_back(std::move(b));
}

void BulletWorld::Impl::add_constraint(const ConstraintSpec& c, const std::vector<bool>& other_moving) {
  auto bullet_index = [&](const ConstraintEndSpec& e) -> int {
    if (e.structure < 0) return -1;
    const std::size_t s = std::size_t(e.structure);
    if (s < by_structure.size() && by_structure[s] >= 0) return by_structure[s];
    return -1;
  };
  auto moved_elsewhere = [&](const ConstraintEndSpec& e) {
    return e.structure >= 0 && bullet_index(e) < 0 && std::size_t(e.structure) < other_moving.size() &&
           other_moving[std::size_t(e.structure)];
  };
  const int ia = bullet_index(c.a), ib = bullet_index(c.b);
  if (ia < 0 && ib < 0) return;  // not ours
  if (moved_elsewhere(c.a) || moved_elsewhere(c.b))
    throw std::invalid_argument(located(c, "ties a bullet structure to a structure that Bullet does not move (motion: "
                                           "free or prescribed); give both ends 'motion: bullet' or anchor it"));
  const Eigen::Vector3d pa(c.a.point[0], c.a.point[1], dims == 3 ? c.a.point[2] : 0.0);
  const Eigen::Vector3d pb(c.b.point[0], c.b.point[1], dims == 3 ? c.b.point[2] : 0.0);
  if (c.type == ConstraintSpec::Type::spring) {
    Spring s;
    s.a = {ia, ia >= 0 ? Eigen::Vector3d(pa - bodies[std::size_t(ia)]->mp.centre_of_mass) : pa};
    s.b = {ib, ib >= 0 ? Eigen::Vector3d(pb - bodies[std::size_t(ib)]->mp.centre_of_mass) : pb};
    if (!(c.stiffness >= 0) || !(c.damping >= 0))
      throw std::invalid_argument(located(c, "a spring needs stiffness >= 0 and damping >= 0"));
    s.law.stiffness = c.stiffness;
    s.law.damping = c.damping;
    s.law.rest_length = c.rest_length >= 0 ? c.rest_length : (pb - pa).norm();
    springs.push_back(s);
    return;
  }
  // Hinge: the two ends' points coincide (pa is used; pb is taken as the same point).
  Eigen::Vector3d axis(c.axis[0], c.axis[1], c.axis[2]);
  if (!(axis.norm() > 0)) throw std::invalid_argument(located(c, "a hinge needs a non-zero axis"));
  axis.normalize();
  if (dims == 2 && std::abs(std::abs(axis.z()) - 1.0) > 1e-9)
    throw std::invalid_argument(located(c, "a 2D hinge turns about z (axis [0, 0, 1])"));
  const Body* A = ia >= 0 ? bodies[std::size_t(ia)].get() : nullptr;
  const Body* B = ib >= 0 ? bodies[std::size_t(ib)].get() : nullptr;
  if (!A) std::swap(A, B);  // Bullet's one-body hinge ties body A to the world
  auto local_point = [&](const Body& b) { return to_bt(Eigen::Vector3d(b.P.transpose() * (pa - b.mp.centre_of_mass))); };
  auto local_axis = [&](const Body& b) { return to_bt(Eigen::Vector3d(b.P.transpose() * axis)); };
  std::unique_ptr<btTypedConstraint> h;
  if (!B)
    h = std::make_unique<btHingeConstraint>(*A->rigid, local_point(*A), local_axis(*A));
  else
    h = std::make_unique<btHingeConstraint>(*A->rigid, *B->rigid, local_point(*A), local_point(*B), local_axis(*A),
                                            local_axis(*B));
  world->addConstraint(h.get(), true);  // the hinged bodies do not collide with each other
  hinges.push_back(std::move(h));
}

void BulletWorld::Impl::spring_impulses(double duration) {
  for (const Spring& s : springs) {
    auto end = [&](const SpringEnd& e, Eigen::Vector3d& p, Eigen::Vector3d& v, Eigen::Vector3d& x) {
      if (e.body < 0) {
        p = e.point;
        v.setZero();
        x = p;
        return;
      }
      const BulletBodyState st = state(*bodies[std::size_t(e.body)]);
      x = st.position;
      p = st.position + st.orientation * e.point;
      v = st.velocity + st.angular_velocity.cross(p - st.position);
    };
    Eigen::Vector3d pa, va, xa, pb, vb, xb;
    end(s.a, pa, va, xa);
    end(s.b, pb, vb, xb);
    const Eigen::Vector3d F = spring_damper_force(s.law, pa, va, pb, vb);
    if (s.a.body >= 0) {
      Body& b = *bodies[std::size_t(s.a.body)];
      b.impulse += duration * F;
      b.angular_impulse += duration * (pa - xa).cross(F);
    }
    if (s.b.body >= 0) {
      Body& b = *bodies[std::size_t(s.b.body)];
      b.impulse -= duration * F;
      b.angular_impulse -= duration * (pb - xb).cross(F);
    }
  }
}

BulletWorld::BulletWorld(int dims, const Eigen::Vector3d& gravity, const std::vector<BulletBodySpec>& bodies,
                         const std::vector<ConstraintSpec>& constraints, bool weight_by_bullet,
                         const std::vector<bool>& other_moving, const ContactWorld* obstacles)
    : impl_(std::make_unique<Impl>()) {
  if (dims != 2 && dims != 3) throw std::invalid_argument("a bullet world is 2D or 3D");
  Impl& w = *impl_;
  w.dims = dims;
  w.gravity = gravity;
  if (dims == 2) w.gravity.z() = 0;
  w.weight_by_bullet = weight_by_bullet;
  w.config = std::make_unique<btDefaultCollisionConfiguration>();
  w.dispatcher = std::make_unique<btCollisionDispatcher>(w.config.get());
  w.broadphase = std::make_unique<btDbvtBroadphase>();
  w.solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  w.world = std::make_unique<btDiscreteDynamicsWorld>(w.dispatcher.get(), w.broadphase.get(), w.solver.get(),
                                                      w.config.get());
  w.world->setGravity(to_bt(w.gravity));
  // Penetration is always corrected by split impulses (positions only): Bullet's default folds a
  // shallow penetration (above -0.04 m) into the contact velocity, which adds energy to a bounce.
  btContactSolverInfo& info = w.world->getSolverInfo();
  info.m_splitImpulse = 1;
  info.m_splitImpulsePenetrationThreshold = std::numeric_limits<btScalar>::infinity();
  // Only contacts where objects touch or overlap reach the solver (each object's contact processing
  // threshold is 0, set where it is made): Bullet keeps contact points up to a fraction of a shape's
  // size apart in its manifolds (so a resting face builds up several points over a few steps, which
  // torsional friction and a steady support need) and by default solves them speculatively, letting
  // a body close such a gap in one step and taking gap / dt off its rebound speed (a bounce's
  // restitution then depended on where in a step the touch fell). The overlap a step leaves, at
  // most the approach speed x dt, is removed by the split impulses.
  gCalculateCombinedRestitutionCallback = &smaller_restitution;
  gCalculateCombinedFrictionCallback = &smaller_friction;
  for (const auto& b : bodies) w.add_body(b);
  if (obstacles) w.add_obstacles(*obstacles);
  for (const auto& c : constraints) w.add_constraint(c, other_moving);
}

BulletWorld::~BulletWorld() = default;

std::size_t BulletWorld::body_count() const { return impl_->bodies.size(); }
int BulletWorld::body_of(std::size_t structure) const {
  return structure < impl_->by_structure.size() ? impl_->by_structure[structure] : -1;
}
std::size_t BulletWorld::spring_count() const { return impl_->springs.size(); }
std::size_t BulletWorld::hinge_count() const { return impl_->hinges.size(); }

void BulletWorld::kick(double duration, const std::vector<Wrench>& loads) {
  for (auto& b : impl_->bodies) {
    if (b->structure >= loads.size()) continue;
    b->impulse += duration * loads[b->structure].force;
    b->angular_impulse += duration * loads[b->structure].torque;
  }
  impl_->spring_impulses(duration);
}

void BulletWorld::step(double dt) {
  if (!(dt > 0)) throw std::invalid_argument("a bullet step needs dt > 0");
  for (auto& b : impl_->bodies) {
    b->com_before = from_bt(b->rigid->getCenterOfMassPosition());
    b->rigid->applyCentralForce(to_bt(Eigen::Vector3d(b->impulse / dt)));
    b->rigid->applyTorque(to_bt(Eigen::Vector3d(b->angular_impulse / dt)));
    b->impulse.setZero();
    b->angular_impulse.setZero();
  }
  // maxSubSteps = 0: exactly one internal step of length dt (see the header); Bullet clears the
  // applied forces at its end.
  impl_->world->stepSimulation(btScalar(dt), 0);
  impl_->collect_contacts(dt);
}

Wrench BulletWorld::contact_load(std::size_t structure) const { return impl_->body_of(structure).contact; }

namespace {
btTransform pose_of(const ObstacleMotion& m, int dims) {
  Eigen::Vector3d x = m.reference;
  if (dims == 2) x.z() = 0;
  return btTransform(to_bt_matrix(m.rotation), to_bt(x));
}
}  // namespace

void BulletWorld::move_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where) {
  for (auto& [structure, body] : impl_->kinematic)
    body->getMotionState()->setWorldTransform(pose_of(where(structure), impl_->dims));
}

void BulletWorld::place_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where) {
  for (auto& [structure, body] : impl_->kinematic) {
    const btTransform T = pose_of(where(structure), impl_->dims);
    body->getMotionState()->setWorldTransform(T);
    body->setWorldTransform(T);
    body->setInterpolationWorldTransform(T);
  }
}
double BulletWorld::last_max_penetration() const { return impl_->max_penetration; }

BulletBodyState BulletWorld::state(std::size_t structure) const { return impl_->state(impl_->body_of(structure)); }

void BulletWorld::set_state(std::size_t structure, const BulletBodyState& s) {
  Body& b = impl_->body_of(structure);
  btRigidBody& r = *b.rigid;
  const btVector3 v = to_bt(s.velocity) * r.getLinearFactor();
  const btVector3 w = to_bt(s.angular_velocity) * r.getAngularFactor();
  r.setLinearVelocity(v);
  r.setAngularVelocity(w);
  r.setCenterOfMassTransform(btTransform(to_bt((s.orientation * b.qP).normalized()), to_bt(s.position)));
  r.clearForces();
  b.impulse.setZero();
  b.angular_impulse.setZero();
}

std::vector<double> BulletWorld::exact_state(std::size_t structure) const {
  const Body& b = impl_->body_of(structure);
  const btTransform& T = b.rigid->getCenterOfMassTransform();
  std::vector<double> s;
  s.reserve(24);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s.push_back(T.getBasis()[i][j]);
  for (const btVector3& v : {T.getOrigin(), b.rigid->getLinearVelocity(), b.rigid->getAngularVelocity()})
    for (int i = 0; i < 3; ++i) s.push_back(v[i]);
  for (const Eigen::Vector3d& v : {b.impulse, b.angular_impulse})
    for (int i = 0; i < 3; ++i) s.push_back(v[i]);
  return s;
}

void BulletWorld::restore_exact_state(std::size_t structure, const std::vector<double>& s) {
  if (s.size() != 24) throw std::invalid_argument("a bullet body's exact state has 24 numbers, got " + std::to_string(s.size()));
  Body& b = impl_->body_of(structure);
  btRigidBody& r = *b.rigid;
  const btMatrix3x3 basis(s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8]);
  r.setLinearVelocity(btVector3(s[12], s[13], s[14]));
  r.setAngularVelocity(btVector3(s[15], s[16], s[17]));
  r.setCenterOfMassTransform(btTransform(basis, btVector3(s[9], s[10], s[11])));
  r.clearForces();
  b.impulse = Eigen::Vector3d(s[18], s[19], s[20]);
  b.angular_impulse = Eigen::Vector3d(s[21], s[22], s[23]);
}

Eigen::Matrix3d BulletWorld::principal_axes(std::size_t structure) const { return impl_->body_of(structure).P; }
Eigen::Vector3d BulletWorld::principal_moments(std::size_t structure) const {
  return impl_->body_of(structure).moments;
}

#else  // no Bullet in this build

bool bullet_available() { return false; }

struct BulletWorld::Impl {};

BulletWorld::BulletWorld(int, const Eigen::Vector3d&, const std::vector<BulletBodySpec>&,
                         const std::vector<ConstraintSpec>&, bool, const std::vector<bool>&, const ContactWorld*) {
  throw std::runtime_error(kNoBulletMessage);
}
Wrench BulletWorld::contact_load(std::size_t) const { throw std::runtime_error(kNoBulletMessage); }
void BulletWorld::move_prescribed(const std::function<ObstacleMotion(std::size_t)>&) {}
void BulletWorld::place_prescribed(const std::function<ObstacleMotion(std::size_t)>&) {}
double BulletWorld::last_max_penetration() const { return 0; }
BulletWorld::~BulletWorld() = default;
std::size_t BulletWorld::body_count() const { return 0; }
int BulletWorld::body_of(std::size_t) const { return -1; }
std::size_t BulletWorld::spring_count() const { return 0; }
std::size_t BulletWorld::hinge_count() const { return 0; }
void BulletWorld::kick(double, const std::vector<Wrench>&) { throw std::runtime_error(kNoBulletMessage); }
void BulletWorld::step(double) { throw std::runtime_error(kNoBulletMessage); }
BulletBodyState BulletWorld::state(std::size_t) const { throw std::runtime_error(kNoBulletMessage); }
void BulletWorld::set_state(std::size_t, const BulletBodyState&) { throw std::runtime_error(kNoBulletMessage); }
std::vector<double> BulletWorld::exact_state(std::size_t) const { throw std::runtime_error(kNoBulletMessage); }
void BulletWorld::restore_exact_state(std::size_t, const std::vector<double>&) {
  throw std::runtime_error(kNoBulletMessage);
}
Eigen::Matrix3d BulletWorld::principal_axes(std::size_t) const { throw std::runtime_error(kNoBulletMessage); }
Eigen::Vector3d BulletWorld::principal_moments(std::size_t) const { throw std::runtime_error(kNoBulletMessage); }

#endif

}  // namespace turbid::fsi
