// Mass, centre of mass and inertia tensor from filled particle samplings (fsi/mass_properties.hpp)
// against the analytic values of a homogeneous box, cylinder and sphere (3D) and rectangle and disc
// (2D), each placed off the origin and rotated so that the tensor has off-diagonal terms:
//   box a x b x c:          I = M/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)
//   cylinder R, L along z:  I = M diag((3R^2 + L^2)/12, (3R^2 + L^2)/12, R^2/2)
//   sphere R:               I = 2/5 M R^2
//   rectangle a x b:        I_zz = M (a^2 + b^2)/12;   disc R: I_zz = M R^2/2
// in world axes R I R^T about the placed centre. The error measure is the largest of: |M - M_exact| /
// M_exact, |centre - centre_exact| / (size of the body), and max |I_ij - I_ij,exact| / max I_kk,exact.
// Tolerance: 1% at a coarse spacing (ten to twelve spacings across the body), and the error falling
// as the spacing halves (each halving must cut it to at most 0.6 of the previous: O(dx^2) would
// give 0.25). The samplers' volumes tile the solid, so the mass alone is exact to rounding (1e-12).
// A box whose cells are cubes is exact to rounding (1e-12): the cells' self-inertia is then exact.
// The sphere's error is the largest: its shells' particles sit at the mid-radius of the shell, inside
// the shell's centroid (the mean of r^2 over a shell of thickness h exceeds the mid-radius squared by
// 5 h^2 / 12), so at R = 5 dx it is 1.1%; the test's coarse spacing is R / 6.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include <Eigen/Geometry>

#include "fsi/mass_properties.hpp"
#include "geometry/primitives.hpp"

namespace {

using namespace turbid;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDensity = 2700;  // [kg/m^3]

geometry::Placement placement(int dims) {
  geometry::Placement p;
  p.translation = {1.3, -0.7, dims == 3 ? 2.1 : 0.0};
  p.rotation_deg = dims == 3 ? geometry::Point{20, -35, 50} : geometry::Point{0, 0, 35};
  return p;
}

// The placement's rotation Rz Ry Rx (geometry/placement.hpp), built independently with Eigen.
Eigen::Matrix3d rotation_of(const geometry::Placement& p) {
  const double d = kPi / 180;
  return (Eigen::AngleAxisd(p.rotation_deg[2] * d, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(p.rotation_deg[1] * d, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(p.rotation_deg[0] * d, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

struct Exact {
  double mass;
  Eigen::Matrix3d inertia_body;  // principal, body axes
  double size;                   // for the centre error
};

double error_of(const fsi::MassProperties& mp, const Exact& ex, const geometry::Placement& p, int dims) {
  const Eigen::Matrix3d R = rotation_of(p);
  const Eigen::Matrix3d I = R * ex.inertia_body * R.transpose();
  const Eigen::Vector3d c(p.translation[0], p.translation[1], p.translation[2]);
  double err = std::abs(mp.mass - ex.mass) / ex.mass;
  err = std::max(err, (mp.centre_of_mass - c).norm() / ex.size);
  const double scale = dims == 3 ? I.diagonal().maxCoeff() : I(2, 2);
  if (dims == 3) {
    err = std::max(err, (mp.inertia - I).cwiseAbs().maxCoeff() / scale);
  } else {
    err = std::max(err, std::abs(mp.inertia(2, 2) - I(2, 2)) / scale);
  }
  return err;
}

// Errors at dx, dx/2, dx/4; checks the coarse one against 1% and the decrease.
void check_convergence(const char* name, double dx, int dims, const Exact& ex,
                       const std::function<geometry::SampledBody(double)>& sample) {
  std::vector<double> errors;
  for (int level = 0; level < 3; ++level) {
    const double h = dx / double(1 << level);
    const geometry::SampledBody body = sample(h);
    const double err = error_of(fsi::mass_properties(body, kDensity, dims), ex, placement(dims), dims);
    const double mass_error = std::abs(fsi::mass_properties(body, kDensity, dims).mass - ex.mass) / ex.mass;
    std::printf("  %-9s %dD dx = %-8g particles %7zu  error %.3e (mass %.1e)\n", name, dims, h, body.points.size(), err,
                mass_error);
    EXPECT_LT(mass_error, 1e-12) << name;
    errors.push_back(err);
  }
  EXPECT_LT(errors[0], 0.01) << name << " at the coarse spacing";
  for (std::size_t k = 1; k < errors.size(); ++k)
    EXPECT_LE(errors[k], 0.6 * errors[k - 1]) << name << ": the error must fall as the spacing halves";
}

TEST(MassProperties, BoxAgainstAnalytic) {
  const double a = 1.0, b = 0.73, c = 0.47;  // not multiples of the spacings: cells are not cubes
  const double M = kDensity * a * b * c;
  const Exact ex{M, M / 12 * Eigen::Vector3d(b * b + c * c, a * a + c * c, a * a + b * b).asDiagonal(), a};
  check_convergence("box", 0.1, 3, ex, [&](double h) { return geometry::sample_box({a, b, c}, h, 0, 3, placement(3)); });
}

TEST(MassProperties, CylinderAgainstAnalytic) {
  const double R = 0.3, L = 1.0;
  const double M = kDensity * kPi * R * R * L;
  const double Ixx = M * (3 * R * R + L * L) / 12;
  const Exact ex{M, Eigen::Vector3d(Ixx, Ixx, M * R * R / 2).asDiagonal(), L};
  check_convergence("cylinder", 0.06, 3, ex,
                    [&](double h) { return geometry::sample_cylinder(R, L, h, 0, 3, placement(3)); });
}

TEST(MassProperties, SphereAgainstAnalytic) {
  const double R = 0.5;
  const double M = kDensity * 4.0 / 3.0 * kPi * R * R * R;
  const Exact ex{M, (0.4 * M * R * R) * Eigen::Matrix3d::Identity(), 2 * R};
  check_convergence("sphere", R / 6, 3, ex, [&](double h) { return geometry::sample_sphere(R, h, 0, 3, placement(3)); });
}

TEST(MassProperties, RectangleAgainstAnalytic2D) {
  const double a = 1.0, b = 0.73;
  const double M = kDensity * a * b;
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
  I(2, 2) = M * (a * a + b * b) / 12;
  check_convergence("rectangle", 0.1, 2, {M, I, a},
                    [&](double h) { return geometry::sample_box({a, b, 0}, h, 0, 2, placement(2)); });
}

TEST(MassProperties, DiscAgainstAnalytic2D) {
  const double R = 0.5;
  const double M = kDensity * kPi * R * R;
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
  I(2, 2) = M * R * R / 2;
  check_convergence("disc", 0.1, 2, {M, I, 2 * R}, [&](double h) { return geometry::sample_sphere(R, h, 0, 2, placement(2)); });
}

TEST(MassProperties, BoxOfCubicCellsIsExact) {
  const double a = 1.0, b = 0.7, c = 0.45, h = 0.05;  // multiples of h
  const double M = kDensity * a * b * c;
  const Exact ex{M, M / 12 * Eigen::Vector3d(b * b + c * c, a * a + c * c, a * a + b * b).asDiagonal(), a};
  const double err = error_of(fsi::mass_properties(geometry::sample_box({a, b, c}, h, 0, 3, placement(3)), kDensity, 3),
                              ex, placement(3), 3);
  std::printf("  box of cubic cells: error %.2e\n", err);
  EXPECT_LT(err, 1e-12);
}

// The lamina's tensor is that of a plane figure: I_zz = I_xx + I_yy and no coupling to z
// (exact identities of the sums, so to rounding).
TEST(MassProperties, LaminaTensorIn2D) {
  const auto mp = fsi::mass_properties(geometry::sample_box({1.0, 0.7, 0}, 0.05, 0, 2, placement(2)), kDensity, 2);
  const double scale = mp.inertia_zz();
  EXPECT_NEAR(mp.inertia(2, 2), mp.inertia(0, 0) + mp.inertia(1, 1), 1e-12 * scale);
  EXPECT_EQ(mp.inertia(0, 2), 0.0);
  EXPECT_EQ(mp.inertia(1, 2), 0.0);
  EXPECT_EQ(mp.centre_of_mass.z(), 0.0);
}

TEST(MassProperties, RejectsBadInput) {
  const auto body = geometry::sample_box({1, 1, 1}, 0.25, 0, 3);
  EXPECT_THROW(fsi::mass_properties(body, 0, 3), std::invalid_argument);
  EXPECT_THROW(fsi::mass_properties(body, kDensity, 4), std::invalid_argument);
  EXPECT_THROW(fsi::mass_properties(geometry::SampledBody{}, kDensity, 3), std::invalid_argument);
}

}  // namespace
