// Prescribed structures in the fluid's time step; see prescribed_coupling.hpp.
#include "fsi/prescribed_coupling.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace turbid::fsi {

bool has_prescribed_structures(const Scene& scene) {
  for (const auto& st : scene.structures)
    if (st.motion == StructureSpec::Motion::prescribed) return true;
  return false;
}

double first_exit_time(const PrescribedBody& body, const std::vector<Eigen::Vector3d>& offsets, int dims,
                       const sph::Domain& domain, double end, int count) {
  std::vector<double> times;
  for (int j = 0; j <= count; ++j) times.push_back(end * double(j) / double(count));
  for (double t : body.path.spec().times)
    if (t > 0 && t < end) times.push_back(t);
  std::sort(times.begin(), times.end());
  for (double t : times) {
    const PathState s = body.path.at(t);
    const Eigen::Vector3d centre = body.reference + s.displacement;
    for (const Eigen::Vector3d& r0 : offsets) {
      const Eigen::Vector3d x = centre + s.rotation * r0;
      for (int a = 0; a < dims; ++a)
        if (!domain.periodic[a] && (x[a] < domain.min[a] || x[a] > domain.max[a])) return t;
    }
  }
  return -1;
}

std::unique_ptr<PrescribedCoupling> make_prescribed_coupling(const Scene& scene, const sph::ParticleStore& store,
                                                             const sph::FieldIds& ids, const sph::Domain& domain,
                                                             std::function<double()> clock) {
  const auto fail = [](const StructureSpec& st, const std::string& what) {
    std::ostringstream os;
    os << st.path.where.file << ":" << st.path.where.line << ":" << st.path.where.column << ": error: structure '"
       << st.name << "': " << what;
    throw std::invalid_argument(os.str());
  };
  std::vector<std::optional<PrescribedBody>> paths(scene.structures.size());
  for (std::size_t k = 0; k < paths.size(); ++k) {
    const StructureSpec& st = scene.structures[k];
    if (st.motion != StructureSpec::Motion::prescribed) continue;
    try {
      paths[k].emplace(PrescribedBody{PrescribedPath(st.path),
                                      Eigen::Vector3d(st.reference_point[0], st.reference_point[1], st.reference_point[2])});
    } catch (const std::exception& e) {
      fail(st, e.what());
    }
  }
  // A path that carries the structure out of the domain would lose its particles there.
  const int d = scene.dimensions;
  const auto* r0 = static_cast<const sph::Real*>(store.raw(ids.body_offset));
  const auto* body = store.data<std::uint8_t>(ids.body);
  const auto* kind = store.data<std::uint8_t>(ids.kind);
  std::vector<std::vector<Eigen::Vector3d>> offsets(paths.size());
  for (std::size_t i = 0; i < store.size(); ++i)
    if (kind[i] == std::uint8_t(sph::Kind::structure) && body[i] < paths.size() && paths[body[i]]) {
      Eigen::Vector3d r = Eigen::Vector3d::Zero();
      for (int a = 0; a < d; ++a) r[a] = double(r0[i * std::size_t(d) + std::size_t(a)]);
      offsets[body[i]].push_back(r);
    }
  for (std::size_t k = 0; k < paths.size(); ++k) {
    if (!paths[k]) continue;
    const double t = first_exit_time(*paths[k], offsets[k], d, domain, scene.end_time);
    if (t < 0) continue;
    std::ostringstream os;
    os << "its path carries it out of the domain at t = " << t
       << " s (particles that leave the domain are removed); give a larger 'domain' or a shorter path";
    fail(scene.structures[k], os.str());
  }
  return std::make_unique<PrescribedCoupling>(std::move(paths), std::move(clock));
}

PrescribedCoupling::PrescribedCoupling(std::vector<std::optional<PrescribedBody>> bodies, std::function<double()> clock)
    : bodies_(std::move(bodies)), clock_(std::move(clock)), placement_(bodies_.size()) {}

void PrescribedCoupling::place(sph::Backend& backend, double t_position, double t_velocity, bool move) const {
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    sph::BodyPlacement& p = placement_[k];
    p.moving = bodies_[k].has_value();
    if (!p.moving) continue;
    const PrescribedBody& b = *bodies_[k];
    const PathState at_v = b.path.at(t_velocity);
    const PathState at_x = t_position == t_velocity ? at_v : b.path.at(t_position);
    const Eigen::Vector3d centre = b.reference + at_x.displacement;
    for (int a = 0; a < 3; ++a) {
      p.centre[a] = centre[a];
      p.velocity[a] = at_v.velocity[a];
      p.angular_velocity[a] = at_v.angular_velocity[a];
      for (int c = 0; c < 3; ++c) p.rotation[a][c] = at_x.rotation(a, c);
    }
  }
  backend.place_bodies(placement_, move);
}

void PrescribedCoupling::after_kick(sph::Backend& backend, double half_dt) {
  if (drifted_) {
    // Second half-kick: the velocity at t(n+1), at the positions already placed.
    drifted_ = false;
    place(backend, new_time_, new_time_, false);
    return;
  }
  // First half-kick: the velocity at t(n) + dt/2 at the particles as they are, R(t(n)) r0 from the
  // reference point (a free body's kick leaves its orientation too).
  const double now = clock_();
  half_time_ = now + half_dt;
  place(backend, now, half_time_, false);
}

void PrescribedCoupling::after_drift(sph::Backend& backend, double dt) {
  // The solver adds dt to its time after the step: the same sum, the same bits.
  new_time_ = clock_() + dt;
  drifted_ = true;
  place(backend, new_time_, half_time_, true);
}

Eigen::Vector3d PrescribedCoupling::reference_point(std::size_t k, double t) const {
  return bodies_[k]->reference + bodies_[k]->path.at(t).displacement;
}

BodyKinematics PrescribedCoupling::kinematics(std::size_t k, double t) const {
  BodyKinematics out;
  const PathState s = bodies_[k]->path.at(t);
  const Eigen::Vector3d x = bodies_[k]->reference + s.displacement;
  const Eigen::Quaterniond& q = s.orientation;
  out.orientation = {q.w(), q.x(), q.y(), q.z()};
  for (std::size_t a = 0; a < 3; ++a) {
    out.position[a] = x[int(a)];
    out.velocity[a] = s.velocity[int(a)];
    out.angular_velocity[a] = s.angular_velocity[int(a)];
  }
  return out;
}

}  // namespace turbid::fsi
