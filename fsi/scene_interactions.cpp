// Scene -> contact obstacles, contact shapes and constraints; see scene_interactions.hpp.
#include "fsi/scene_interactions.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace turbid::fsi {

namespace {

Eigen::Vector3d vec(const Vec3d& v) { return {v[0], v[1], v[2]}; }

[[noreturn]] void located(const SourceLocation& where, const std::string& message) {
  std::ostringstream os;
  os << where.file << ":" << where.line << ":" << where.column << ": error: " << message;
  throw std::invalid_argument(os.str());
}

ContactMaterial material_of(const ContactMaterialSpec& c) {
  return ContactMaterial{c.youngs_modulus, c.poisson_ratio, c.restitution, c.friction};
}

// Gravity's magnitude for the pivots' stiffness, at least that of the Earth.
double reference_gravity(const Scene& scene) {
  const double g = std::sqrt(scene.gravity[0] * scene.gravity[0] + scene.gravity[1] * scene.gravity[1] +
                             (scene.dimensions == 3 ? scene.gravity[2] * scene.gravity[2] : 0.0));
  return std::max(g, 9.81);
}

}  // namespace

bool contacts_as_sphere(const Scene& scene, const StructureSpec& st) {
  return st.shape == StructureSpec::Shape::sphere || (scene.dimensions == 2 && st.shape == StructureSpec::Shape::cylinder);
}

ContactWorld contact_world(const Scene& scene, const SurfaceLayers& surface) {
  const int d = scene.dimensions;
  ContactWorld w;
  w.dims = d;
  w.spacing = scene.particle_spacing;
  int wall_id = 0;
  for (const auto& wall : scene.walls) {
    switch (wall.kind) {
      case WallSpec::Kind::container: {
        const Eigen::Vector3d lo = vec(wall.box.min), hi = vec(wall.box.max);
        for (int a = 0; a < d; ++a)
          for (int side = 0; side < 2; ++side) {
            if (wall.open[std::size_t(2 * a + side)]) continue;
            ContactFace f;
            f.wall = wall_id;
            f.origin = lo;
            if (side == 1) f.origin[a] = hi[a];
            f.normal = Eigen::Vector3d::Zero();
            f.normal[a] = side == 0 ? 1.0 : -1.0;
            const int b = (a + 1) % d, c = (a + 2) % d;
            f.edge_1 = Eigen::Vector3d::Zero();
            f.edge_1[b] = hi[b] - lo[b];
            f.edge_2 = Eigen::Vector3d::Zero();
            if (d == 3) f.edge_2[c] = hi[c] - lo[c];
            w.faces.push_back(f);
          }
        break;
      }
      case WallSpec::Kind::solid_box: {
        ContactBox b;
        b.min = vec(wall.box.min);
        b.max = vec(wall.box.max);
        w.boxes.push_back(b);
        break;
      }
      case WallSpec::Kind::polyline: {
        const std::size_t n = wall.points.size();
        const std::size_t segments = wall.closed ? n : n - 1;
        for (std::size_t s = 0; s < segments; ++s) {
          const Vec3d& a = wall.points[s];
          const Vec3d& b = wall.points[(s + 1) % n];
          // The section's coordinates (2D: x, y; 3D: x, z) and its fluid-side normal: the layers lie
          // on the right of the travel direction for side = -1, so the fluid is on the left.
          const double tx = b[0] - a[0], ty = b[1] - a[1];
          const double len = std::hypot(tx, ty);
          const double nx = wall.side * ty / len, ny = -wall.side * tx / len;
          ContactFace f;
          f.wall = wall_id;
          if (d == 2) {
            f.origin = {a[0], a[1], 0.0};
            f.edge_1 = {tx, ty, 0.0};
            f.normal = {nx, ny, 0.0};
          } else {
            f.origin = {a[0], wall.span[0], a[1]};
            f.edge_1 = {tx, 0.0, ty};
            f.edge_2 = {0.0, wall.span[1] - wall.span[0], 0.0};
            f.normal = {nx, 0.0, ny};
          }
          w.faces.push_back(f);
        }
        break;
      }
    }
    ++wall_id;
  }
  const double dx = scene.particle_spacing;
  for (std::size_t k = 0; k < scene.structures.size(); ++k) {
    const StructureSpec& st = scene.structures[k];
    const bool prescribed = st.motion == StructureSpec::Motion::prescribed;
    if (st.motion != StructureSpec::Motion::fixed && !prescribed) continue;
    FixedContactShape f;
    if (prescribed) {
      f.prescribed = int(k);
      f.reference = vec(st.reference_point);
    }
    if (st.contact.given) f.material = material_of(st.contact);
    if (contacts_as_sphere(scene, st)) {
      f.centres = {vec(st.position)};
      f.radius = st.radius * st.scale;
    } else {
      f.centres = surface[k];
      f.radius = 0.5 * dx;
    }
    w.fixed.push_back(std::move(f));
  }
  return w;
}

std::unique_ptr<BodyContacts> body_contacts(const Scene& scene, const SurfaceLayers& surface,
                                            const std::vector<std::optional<RigidBody>>& bodies) {
  const double dx = scene.particle_spacing;
  const int d = scene.dimensions;
  std::vector<BodyContactShape> shapes(scene.structures.size());
  std::vector<double> masses(scene.structures.size(), 0.0);
  bool any = false;
  for (std::size_t k = 0; k < scene.structures.size(); ++k) {
    const StructureSpec& st = scene.structures[k];
    // A bullet body's contacts are Bullet's (bullet_world.hpp).
    if (!bodies[k] || !st.contact.given || st.motion == StructureSpec::Motion::bullet) continue;
    const RigidBody& b = *bodies[k];
    BodyContactShape& s = shapes[k];
    s.active = true;
    s.material = material_of(st.contact);
    masses[k] = b.mass();
    if (contacts_as_sphere(scene, st)) {
      s.centres = {vec(st.position) - b.position()};
      s.radius = st.radius * st.scale;
      s.face_count = 1;
    } else {
      for (const auto& p : surface[k]) s.centres.push_back(p - b.position());
      s.radius = 0.5 * dx;
      // The most spheres one plane can meet at once: those within dx/2 of the extreme along an axis.
      int most = 1;
      for (int a = 0; a < d; ++a)
        for (double sgn : {-1.0, 1.0}) {
          double extreme = -1e300;
          for (const auto& c : s.centres) extreme = std::max(extreme, sgn * c[a]);
          int count = 0;
          for (const auto& c : s.centres) count += sgn * c[a] >= extreme - 0.5 * dx ? 1 : 0;
          most = std::max(most, count);
        }
      s.face_count = most;
    }
    any = true;
  }
  if (!any) return nullptr;
  try {
    return std::make_unique<BodyContacts>(std::move(shapes), masses, contact_world(scene, surface));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("contacts: ") + e.what());
  }
}

std::vector<BodyConstraint> body_constraints(const Scene& scene, const std::vector<std::optional<RigidBody>>& bodies) {
  std::vector<BodyConstraint> out;
  const double dx = scene.particle_spacing;
  const auto bullet = [&](int s) {
    return s >= 0 && scene.structures[std::size_t(s)].motion == StructureSpec::Motion::bullet;
  };
  for (const auto& cs : scene.constraints) {
    // A constraint on a bullet body is Bullet's (bullet_world.hpp), which refuses one that also
    // ties a free body.
    if (bullet(cs.a.structure) || bullet(cs.b.structure)) continue;
    BodyConstraint c;
    c.scene_index = int(&cs - scene.constraints.data());
    c.structure_a = cs.a.structure;
    c.structure_b = cs.b.structure;
    double inverse_mass = 0;
    for (const auto* end : {&cs.a, &cs.b}) {
      if (end->structure < 0) continue;
      if (std::size_t(end->structure) >= bodies.size() || !bodies[std::size_t(end->structure)])
        located(cs.where, "constraint '" + cs.name + "': structure '" +
                              (std::size_t(end->structure) < scene.structures.size()
                                   ? scene.structures[std::size_t(end->structure)].name
                                   : std::string("?")) +
                              "' is not a free structure (motion: free)");
      inverse_mass += 1.0 / bodies[std::size_t(end->structure)]->mass();
    }
    if (inverse_mass == 0) located(cs.where, "constraint '" + cs.name + "' ties two fixed anchors");
    // Body frame at t = 0: the world's axes about the centre of mass.
    c.point_a = cs.a.structure >= 0 ? Eigen::Vector3d(vec(cs.a.point) - bodies[std::size_t(cs.a.structure)]->position())
                                    : vec(cs.a.point);
    c.point_b = cs.b.structure >= 0 ? Eigen::Vector3d(vec(cs.b.point) - bodies[std::size_t(cs.b.structure)]->position())
                                    : vec(cs.b.point);
    if (cs.type == ConstraintSpec::Type::spring) {
      c.kind = BodyConstraint::Kind::spring;
      c.stiffness = cs.stiffness;
      c.damping = cs.damping;
      c.rest_length = cs.rest_length >= 0 ? cs.rest_length : (vec(cs.a.point) - vec(cs.b.point)).norm();
    } else {
      c.kind = BodyConstraint::Kind::pivot;
      const double m = 1.0 / inverse_mass;
      c.stiffness = 1000.0 * m * reference_gravity(scene) / dx;
      c.damping = 2.0 * std::sqrt(c.stiffness * m);
    }
    out.push_back(c);
  }
  return out;
}

void add_hinge_locks(const Scene& scene, std::size_t structure, DofMask& mask) {
  if (scene.dimensions != 3) return;
  for (const auto& cs : scene.constraints) {
    if (cs.type != ConstraintSpec::Type::hinge) continue;
    if (cs.a.structure != int(structure) && cs.b.structure != int(structure)) continue;
    for (int a = 0; a < 3; ++a)
      if (std::abs(cs.axis[std::size_t(a)]) < 0.5) mask.rotation[std::size_t(a)] = false;
  }
}

}  // namespace turbid::fsi
