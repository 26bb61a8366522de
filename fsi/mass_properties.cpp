// Mass properties of a sampled rigid structure; see mass_properties.hpp.
#include "fsi/mass_properties.hpp"

#include <cmath>
#include <stdexcept>

namespace turbid::fsi {

MassProperties mass_properties(const geometry::SampledBody& filled, double density, int dims) {
  if (dims != 2 && dims != 3) throw std::invalid_argument("mass_properties: dims must be 2 or 3");
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument("mass_properties: density must be positive and finite");
  const std::size_t n = filled.points.size();
  if (filled.volumes.size() != n) throw std::invalid_argument("mass_properties: one volume per point expected");

  MassProperties mp;
  mp.dims = dims;
  // Volumes first, the density once: the mass then equals rho times the sampled volume to rounding.
  double volume = 0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d x(filled.points[i][0], filled.points[i][1], dims == 3 ? filled.points[i][2] : 0.0);
    volume += filled.volumes[i];
    first_moment += filled.volumes[i] * x;
  }
  if (!(volume > 0)) throw std::invalid_argument("mass_properties: the sampling has no volume");
  mp.mass = density * volume;
  mp.centre_of_mass = first_moment / volume;

  // Second moments about the centre (not about the origin and shifted afterwards, which would
  // subtract two large numbers for a body far from the origin).
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double v = filled.volumes[i];
    const Eigen::Vector3d x(filled.points[i][0], filled.points[i][1], dims == 3 ? filled.points[i][2] : 0.0);
    const Eigen::Vector3d r = x - mp.centre_of_mass;
    inertia += v * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    if (dims == 3) {
      inertia.diagonal().array() += v * std::cbrt(v * v) / 6.0;
    } else {
      inertia(0, 0) += v * v / 12.0;
      inertia(1, 1) += v * v / 12.0;
      inertia(2, 2) += v * v / 6.0;
    }
  }
  mp.inertia = density * inertia;
  return mp;
}

}  // namespace turbid::fsi
