// DEM contacts of moving structures; see body_contacts.hpp.
#include "fsi/body_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace turbid::fsi {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

ContactSide side_of(const ContactMaterial& m, double radius, double mass) {
  return ContactSide{m.youngs_modulus, m.poisson_ratio, radius, mass};
}

ContactSide rigid_side(double radius) { return ContactSide{kInfinity, 0.0, radius, kInfinity}; }

// The smallest principal moment of the rotations the body may make (2D: I_zz), for the effective
// mass of an off-centre contact.
double smallest_moment(const RigidBody& b) {
  if (b.dims() == 2) return b.body_inertia()(2, 2);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(b.body_inertia(), Eigen::EigenvaluesOnly);
  return eig.eigenvalues().minCoeff();
}

}  // namespace

BodyContacts::BodyContacts(std::vector<BodyContactShape> shapes, const std::vector<double>& masses, ContactWorld world)
    : shapes_(std::move(shapes)), masses_(masses), world_(std::move(world)) {
  const std::size_t n = shapes_.size();
  if (masses_.size() != n) throw std::invalid_argument("BodyContacts: one mass per structure expected");
  bounding_.assign(n, 0.0);
  wall_law_.resize(n);
  fixed_law_.assign(n, std::vector<Law>(world_.fixed.size()));
  body_law_.assign(n, std::vector<Law>(n));
  const std::size_t obstacles = world_.fixed.size();
  fixed_lo_.resize(obstacles);
  fixed_hi_.resize(obstacles);
  fixed_now_.resize(obstacles);
  motion_.resize(obstacles);
  obstacle_speed_.assign(obstacles, 0.0);
  for (std::size_t j = 0; j < obstacles; ++j) {
    ObstacleMotion at_rest;
    at_rest.reference = world_.fixed[j].reference;
    move_obstacle(j, at_rest);
  }
  for (std::size_t k = 0; k < n; ++k) {
    const BodyContactShape& s = shapes_[k];
    if (!s.active) continue;
    ++active_count_;
    for (const auto& c : s.centres) bounding_[k] = std::max(bounding_[k], c.norm() + s.radius);
    const ContactSide me = side_of(s.material, s.radius, masses_[k]);
    wall_law_[k] = {make_contact_law(me, rigid_side(kInfinity), s.material.restitution, s.material.friction), true};
    for (std::size_t f = 0; f < world_.fixed.size(); ++f) {
      const FixedContactShape& o = world_.fixed[f];
      if (o.centres.empty()) continue;
      ContactSide other = rigid_side(o.radius);
      double e = s.material.restitution, mu = s.material.friction;
      if (o.material) {
        other.youngs_modulus = o.material->youngs_modulus;
        other.poisson_ratio = o.material->poisson_ratio;
        e = std::min(e, o.material->restitution);
        mu = std::min(mu, o.material->friction);
      }
      fixed_law_[k][f] = {make_contact_law(me, other, e, mu), true};
    }
    for (std::size_t l = 0; l < k; ++l) {
      const BodyContactShape& o = shapes_[l];
      if (!o.active) continue;
      const double e = std::min(s.material.restitution, o.material.restitution);
      const double mu = std::min(s.material.friction, o.material.friction);
      body_law_[l][k] = {make_contact_law(side_of(o.material, o.radius, masses_[l]), me, e, mu), true};
    }
  }
}

void BodyContacts::move_obstacle(std::size_t j, const ObstacleMotion& m) {
  const FixedContactShape& f = world_.fixed[j];
  std::vector<Eigen::Vector3d>& now = fixed_now_[j];
  now.resize(f.centres.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInfinity), hi = Eigen::Vector3d::Constant(-kInfinity);
  double reach = 0;
  for (std::size_t i = 0; i < f.centres.size(); ++i) {
    const Eigen::Vector3d arm = m.rotation * (f.centres[i] - f.reference);
    now[i] = f.prescribed >= 0 ? Eigen::Vector3d(m.reference + arm) : f.centres[i];
    lo = lo.cwiseMin(now[i]);
    hi = hi.cwiseMax(now[i]);
    reach = std::max(reach, arm.norm() + f.radius);
  }
  fixed_lo_[j] = lo.array() - f.radius;
  fixed_hi_[j] = hi.array() + f.radius;
  motion_[j] = m;
  obstacle_speed_[j] = m.velocity.norm() + m.angular_velocity.norm() * reach;
}

void BodyContacts::move_prescribed(const std::function<ObstacleMotion(std::size_t structure)>& where) {
  for (std::size_t j = 0; j < world_.fixed.size(); ++j)
    if (world_.fixed[j].prescribed >= 0) move_obstacle(j, where(std::size_t(world_.fixed[j].prescribed)));
}

void BodyContacts::add(const ContactLaw& law, const ContactGeometry& g, const ContactKey& key, const RigidBody& body,
                       const Eigen::Vector3d& velocity_2, const RigidBody* body_2, std::size_t k, std::size_t l,
                       double, std::vector<Wrench>&, std::map<ContactKey, TangentialSpring>&) {
  if (!(g.overlap > 0)) return;
  pending_.push_back({&law, g, key, &body, body_2, velocity_2, k, l});
}

void BodyContacts::evaluate(const std::vector<std::optional<RigidBody>>& bodies, double dt, std::vector<Wrench>& out) {
  const std::size_t n = shapes_.size();
  const int d = world_.dims;
  std::map<ContactKey, TangentialSpring> next;
  last_max_overlap_ = 0;
  // World positions of every active body's spheres.
  std::vector<std::vector<Eigen::Vector3d>> centres(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!shapes_[k].active || !bodies[k]) continue;
    const RigidBody& b = *bodies[k];
    const Eigen::Matrix3d R = b.orientation().toRotationMatrix();
    centres[k].reserve(shapes_[k].centres.size());
    for (const auto& p : shapes_[k].centres) centres[k].push_back(b.position() + R * p);
  }
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    if (centres[k].empty()) continue;
    const RigidBody& b = *bodies[k];
    const double r = shapes_[k].radius;
    for (std::size_t i = 0; i < centres[k].size(); ++i) {
      const Eigen::Vector3d& c = centres[k][i];
      // (a) planar faces, wall by wall.
      std::size_t f = 0;
      while (f < world_.faces.size()) {
        const int wall = world_.faces[f].wall;
        bool face_contact = false;
        ContactGeometry best;
        int best_face = -1;
        for (; f < world_.faces.size() && world_.faces[f].wall == wall; ++f) {
          const ContactFace& face = world_.faces[f];
          const Eigen::Vector3d rel = c - face.origin;
          const double s = rel.dot(face.normal);
          if (s > r || s < -r) continue;
          const double l1 = face.edge_1.squaredNorm(), l2 = face.edge_2.squaredNorm();
          const double u = rel.dot(face.edge_1) / l1;
          const double w = l2 > 0 ? rel.dot(face.edge_2) / l2 : 0.5;
          const bool inside = u > 0 && u < 1 && w > 0 && w < 1;
          ContactGeometry g;
          if (inside) {
            g = sphere_plane(c, r, face.origin, face.normal);
            face_contact = true;
            add(wall_law_[k].law, g, {int(k), int(i), 0, int(f), 0}, b, zero, nullptr, k, k, dt, out, next);
            continue;
          }
          const Eigen::Vector3d q =
              face.origin + std::clamp(u, 0.0, 1.0) * face.edge_1 + (l2 > 0 ? std::clamp(w, 0.0, 1.0) : 0.0) * face.edge_2;
          const Eigen::Vector3d dq = c - q;
          const double dist = dq.norm();
          g.overlap = r - dist;
          g.normal = dist > 0 ? Eigen::Vector3d(dq / dist) : face.normal;
          g.point = c - (r - 0.5 * g.overlap) * g.normal;
          if (g.overlap > 0 && (best_face < 0 || g.overlap > best.overlap)) {
            best = g;
            best_face = int(f);
          }
        }
        if (!face_contact && best_face >= 0)
          add(wall_law_[k].law, best, {int(k), int(i), 0, best_face, 0}, b, zero, nullptr, k, k, dt, out, next);
      }
      // (b) solid boxes.
      for (std::size_t j = 0; j < world_.boxes.size(); ++j) {
        const ContactBox& box = world_.boxes[j];
        Eigen::Vector3d q = c;
        bool outside = false;
        for (int a = 0; a < d; ++a) {
          q[a] = std::clamp(c[a], box.min[a], box.max[a]);
          outside = outside || q[a] != c[a];
        }
        ContactGeometry g;
        if (outside) {
          const Eigen::Vector3d dq = c - q;
          const double dist = dq.norm();
          if (dist >= r) continue;
          g.overlap = r - dist;
          g.normal = dq / dist;
        } else {
          // Centre inside: out through the nearest face.
          double best = kInfinity;
          for (int a = 0; a < d; ++a)
            for (int sgn : {-1, 1}) {
              const double depth = sgn < 0 ? c[a] - box.min[a] : box.max[a] - c[a];
              if (depth < best) {
                best = depth;
                g.normal = Eigen::Vector3d::Zero();
                g.normal[a] = sgn;
              }
            }
          g.overlap = r + best;
        }
        g.point = c - (r - 0.5 * g.overlap) * g.normal;
        add(wall_law_[k].law, g, {int(k), int(i), 1, int(j), 0}, b, zero, nullptr, k, k, dt, out, next);
      }
      // (c) fixed and prescribed structures.
      for (std::size_t j = 0; j < world_.fixed.size(); ++j) {
        const FixedContactShape& o = world_.fixed[j];
        const std::vector<Eigen::Vector3d>& at = fixed_now_[j];
        if (at.empty()) continue;
        if (((c.array() + r) < fixed_lo_[j].array()).head(d).any() || ((c.array() - r) > fixed_hi_[j].array()).head(d).any())
          continue;
        const ObstacleMotion& mo = motion_[j];
        for (std::size_t m = 0; m < at.size(); ++m) {
          if ((c - at[m]).squaredNorm() >= (r + o.radius) * (r + o.radius)) continue;
          const ContactGeometry g = sphere_sphere(c, r, at[m], o.radius);
          const Eigen::Vector3d v2 = mo.velocity + mo.angular_velocity.cross(g.point - mo.reference);
          add(fixed_law_[k][j].law, g, {int(k), int(i), 2, int(j), int(m)}, b, v2, nullptr, k, k, dt, out, next);
        }
      }
    }
    // (d) other bodies (each pair once, k < l).
    for (std::size_t l = k + 1; l < n; ++l) {
      if (centres[l].empty()) continue;
      const RigidBody& o = *bodies[l];
      const double reach = bounding_[k] + bounding_[l];
      if ((b.position() - o.position()).squaredNorm() >= reach * reach) continue;
      const double r2 = shapes_[l].radius;
      for (std::size_t i = 0; i < centres[k].size(); ++i) {
        const Eigen::Vector3d& c = centres[k][i];
        if ((c - o.position()).norm() >= bounding_[l] + r) continue;
        for (std::size_t m = 0; m < centres[l].size(); ++m) {
          if ((c - centres[l][m]).squaredNorm() >= (r + r2) * (r + r2)) continue;
          const ContactGeometry g = sphere_sphere(c, r, centres[l][m], r2);
          add(body_law_[k][l].law, g, {int(k), int(i), 3, int(l), int(m)}, b, zero, &o, k, l, dt, out, next);
        }
      }
    }
  }
  // Several contacts of one body with one obstacle (a clump's face on a wall, a disc between two
  // particles of a fixed structure) act in parallel: each takes the share of the body's mass that its
  // stiffness k_n sqrt(delta) has of the group's, so the group's damping is that of one contact of the
  // summed stiffness and the restitution stays the law's (contact.hpp). One contact: the whole mass.
  std::map<std::array<int, 3>, double> group_stiffness;
  const auto stiffness_of = [](const Pending& c) {
    return c.law->effective_modulus * std::sqrt(c.law->effective_radius) * std::sqrt(c.geometry.overlap);
  };
  const auto group_of = [](const Pending& c) { return std::array<int, 3>{c.key[0], c.key[2], c.key[3]}; };
  for (const Pending& c : pending_) group_stiffness[group_of(c)] += stiffness_of(c);
  for (const Pending& c : pending_) {
    last_max_overlap_ = std::max(last_max_overlap_, c.geometry.overlap);
    ContactLaw law = *c.law;
    law.effective_mass *= stiffness_of(c) / group_stiffness[group_of(c)];
    TangentialSpring spring;
    if (const auto it = springs_.find(c.key); it != springs_.end()) spring = it->second;
    const RigidBody& body = *c.body;
    const Eigen::Vector3d v1 = body.velocity() + body.angular_velocity().cross(c.geometry.point - body.position());
    Eigen::Vector3d v2 = c.velocity_2;
    if (c.body_2) v2 = c.body_2->velocity() + c.body_2->angular_velocity().cross(c.geometry.point - c.body_2->position());
    const ContactForce f = contact_force(law, c.geometry.overlap, c.geometry.normal, v1 - v2, spring, dt);
    next.emplace(c.key, spring);
    const PairWrench w = contact_wrench(f.force, c.geometry.point, &body, c.body_2);
    out[c.k] += w.on_a;
    if (c.body_2) out[c.l] += w.on_b;
  }
  pending_.clear();
  springs_ = std::move(next);
}

double BodyContacts::max_substep(const std::vector<std::optional<RigidBody>>& bodies, const std::vector<Wrench>& loads,
                                 double gravity, std::size_t* limiting) const {
  const std::size_t n = shapes_.size();
  double h = kInfinity;
  std::vector<double> m_eff(n, 0.0), speed(n, 0.0), load(n, 0.0);
  for (std::size_t k = 0; k < n; ++k) {
    if (!shapes_[k].active || !bodies[k]) continue;
    const RigidBody& b = *bodies[k];
    const double Rb = bounding_[k];
    // An off-centre contact moves a lighter effective mass; a flat face lands on face_count spheres
    // at once, whose stiffnesses add: both shorten the contact.
    m_eff[k] = 1.0 / (1.0 / b.mass() + Rb * Rb / smallest_moment(b)) / double(std::max(1, shapes_[k].face_count));
    speed[k] = b.velocity().norm() + b.angular_velocity().norm() * Rb;
    load[k] = std::max(loads[k].force.norm(), b.mass() * gravity) / double(std::max(1, shapes_[k].face_count));
    if (!(load[k] > 0)) load[k] = b.mass() * 9.81 / double(std::max(1, shapes_[k].face_count));
  }
  const auto step = [&](ContactLaw law, double mass, double approach, double force, double body_mass) {
    law.effective_mass = mass;
    const double k_n = 4.0 / 3.0 * law.effective_modulus * std::sqrt(law.effective_radius);
    const double static_overlap = std::pow(force / k_n, 2.0 / 3.0);
    const double floor = std::sqrt(2.0 * force / body_mass * static_overlap);
    return contact_time_step(law, std::max({approach, floor, 1e-6}), 50);
  };
  const auto take = [&](double candidate, std::size_t k) {
    if (candidate < h) {
      h = candidate;
      if (limiting) *limiting = k;
    }
  };
  for (std::size_t k = 0; k < n; ++k) {
    if (m_eff[k] == 0) continue;
    const double per_sphere_mass = m_eff[k];
    const double body_mass = bodies[k]->mass() / double(std::max(1, shapes_[k].face_count));
    if (!world_.faces.empty() || !world_.boxes.empty())
      take(step(wall_law_[k].law, per_sphere_mass, speed[k], load[k], body_mass), k);
    for (std::size_t j = 0; j < world_.fixed.size(); ++j)
      if (fixed_law_[k][j].valid)
        take(step(fixed_law_[k][j].law, per_sphere_mass, speed[k] + obstacle_speed_[j], load[k], body_mass), k);
    for (std::size_t l = k + 1; l < n; ++l) {
      if (m_eff[l] == 0 || !body_law_[k][l].valid) continue;
      const double reduced = 1.0 / (1.0 / m_eff[k] + 1.0 / m_eff[l]);
      take(step(body_law_[k][l].law, reduced, speed[k] + speed[l], std::max(load[k], load[l]),
                std::min(body_mass, bodies[l]->mass() / double(std::max(1, shapes_[l].face_count)))),
           k);
    }
  }
  return h;
}

}  // namespace turbid::fsi
