// Prescribed paths; see prescribed_path.hpp.
#include "fsi/prescribed_path.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace turbid::fsi {

namespace {

// Second derivatives M of the clamped cubic spline through (t_i, y_i) with s'(t_0) = s'(t_n) = 0:
// the tridiagonal system h_{i-1}/6 M_{i-1} + (h_{i-1} + h_i)/3 M_i + h_i/6 M_{i+1} = slope_i - slope_{i-1}
// with the end rows h_0/3 M_0 + h_0/6 M_1 = slope_0 and h/6 M_{n-1} + h/3 M_n = -slope_{n-1}
// (diagonally dominant: the Thomas algorithm needs no pivoting).
std::vector<double> clamped_spline(const std::vector<double>& t, const std::vector<double>& y) {
  const std::size_t n = t.size();
  std::vector<double> a(n, 0), b(n, 0), c(n, 0), r(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const double h = t[i] - t[i - 1];
      a[i] = h / 6;
      b[i] += h / 3;
      r[i] -= (y[i] - y[i - 1]) / h;
    }
    if (i + 1 < n) {
      const double h = t[i + 1] - t[i];
      c[i] = h / 6;
      b[i] += h / 3;
      r[i] += (y[i + 1] - y[i]) / h;
    }
  }
  for (std::size_t i = 1; i < n; ++i) {
    const double w = a[i] / b[i - 1];
    b[i] -= w * c[i - 1];
    r[i] -= w * r[i - 1];
  }
  std::vector<double> m(n, 0);
  m[n - 1] = r[n - 1] / b[n - 1];
  for (std::size_t i = n - 1; i-- > 0;) m[i] = (r[i] - c[i] * m[i + 1]) / b[i];
  return m;
}

}  // namespace

Eigen::Quaterniond rotation_from_angles(const Eigen::Vector3d& a) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(a[2], Eigen::Vector3d::UnitZ())) *
         Eigen::Quaterniond(Eigen::AngleAxisd(a[1], Eigen::Vector3d::UnitY())) *
         Eigen::Quaterniond(Eigen::AngleAxisd(a[0], Eigen::Vector3d::UnitX()));
}

Eigen::Vector3d angular_velocity_from_angle_rates(const Eigen::Vector3d& a, const Eigen::Vector3d& rate) {
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(a[2], Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(a[1], Eigen::Vector3d::UnitY()).toRotationMatrix();
  return rate[2] * Eigen::Vector3d::UnitZ() + rate[1] * (Rz * Eigen::Vector3d::UnitY()) +
         rate[0] * (Rz * Ry * Eigen::Vector3d::UnitX());
}

PrescribedPath::PrescribedPath(const PrescribedPathSpec& spec) : spec_(spec) {
  if (spec_.kind == PrescribedPathSpec::Kind::oscillation && !(spec_.period > 0 && std::isfinite(spec_.period)))
    throw std::invalid_argument("a prescribed oscillation needs a positive period, got " + std::to_string(spec_.period));
  if (spec_.kind != PrescribedPathSpec::Kind::samples) return;
  const auto& t = spec_.times;
  if (t.size() < 2) throw std::invalid_argument("a prescribed path needs at least 2 samples");
  if (spec_.displacement.size() != t.size() || spec_.angles.size() != t.size())
    throw std::invalid_argument("a prescribed path needs a displacement and angles at every sample time");
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i])) throw std::invalid_argument("a prescribed path's sample times must be finite");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw std::invalid_argument("a prescribed path's sample times must increase strictly: sample " +
                                  std::to_string(i + 1) + " at t = " + std::to_string(t[i]) + " s");
  }
  for (int c = 0; c < 6; ++c) {
    y_[c].resize(t.size());
    for (std::size_t i = 0; i < t.size(); ++i)
      y_[c][i] = c < 3 ? spec_.displacement[i][std::size_t(c)] : spec_.angles[i][std::size_t(c - 3)];
    if (spec_.interpolation == PrescribedPathSpec::Interpolation::spline) m_[c] = clamped_spline(t, y_[c]);
  }
}

void PrescribedPath::sample(int c, double t, double& value, double& rate) const {
  const auto& ts = spec_.times;
  const auto& y = y_[c];
  if (t <= ts.front()) {
    value = y.front();
    rate = 0;
    return;
  }
  if (t >= ts.back()) {
    value = y.back();
    rate = 0;
    return;
  }
  // The interval [t_i, t_i+1) holding t: at a sample time, the one that starts there.
  const std::size_t i = std::size_t(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
  const double h = ts[i + 1] - ts[i];
  const double slope = (y[i + 1] - y[i]) / h;
  if (spec_.interpolation == PrescribedPathSpec::Interpolation::linear) {
    value = y[i] + slope * (t - ts[i]);
    rate = slope;
    return;
  }
  const double A = (ts[i + 1] - t) / h, B = (t - ts[i]) / h;
  const double* M = m_[c].data();
  value = A * y[i] + B * y[i + 1] + ((A * A * A - A) * M[i] + (B * B * B - B) * M[i + 1]) * h * h / 6;
  rate = slope - (3 * A * A - 1) / 6 * h * M[i] + (3 * B * B - 1) / 6 * h * M[i + 1];
}

PathState PrescribedPath::at(double t) const {
  PathState s;
  const auto vec = [](const Vec3d& v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
  switch (spec_.kind) {
    case PrescribedPathSpec::Kind::velocity: {
      s.velocity = vec(spec_.velocity);
      s.displacement = s.velocity * t;
      s.angular_velocity = vec(spec_.angular_velocity);
      const double w = s.angular_velocity.norm();
      if (w > 0) s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(w * t, s.angular_velocity / w));
      break;
    }
    case PrescribedPathSpec::Kind::oscillation: {
      const double omega = 2 * std::numbers::pi / spec_.period;
      const double phase = omega * t + spec_.phase;
      const double shape = std::sin(phase) - std::sin(spec_.phase), rate = omega * std::cos(phase);
      s.displacement = vec(spec_.amplitude) * shape;
      s.velocity = vec(spec_.amplitude) * rate;
      const Eigen::Vector3d a = vec(spec_.angular_amplitude) * shape;
      s.orientation = rotation_from_angles(a);
      s.angular_velocity = angular_velocity_from_angle_rates(a, vec(spec_.angular_amplitude) * rate);
      break;
    }
    case PrescribedPathSpec::Kind::samples: {
      Eigen::Vector3d a, a_rate;
      for (int c = 0; c < 3; ++c) sample(c, t, s.displacement[c], s.velocity[c]);
      for (int c = 0; c < 3; ++c) sample(c + 3, t, a[c], a_rate[c]);
      s.orientation = rotation_from_angles(a);
      s.angular_velocity = angular_velocity_from_angle_rates(a, a_rate);
      break;
    }
  }
  s.rotation = s.orientation.toRotationMatrix();
  return s;
}

}  // namespace turbid::fsi
