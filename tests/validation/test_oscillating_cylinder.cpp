// A cylinder oscillated in still water (motion: prescribed, issue #8):
// scenes/oscillating_cylinder_2d.yaml, R = 0.1 m at the centre of a closed 1 m x 1 m tank,
// x = x0 + A (cos wt - 1), A = 0.02 m, T = 1 s, no gravity.
//
// Reference: potential flow, F = -C_a rho pi R^2 a(t). C_a = 1 for a circle in unbounded fluid
// (the circle's added mass rho pi R^2, e.g. Newman, Marine Hydrodynamics, 1977); in this square
// tank C_a = 1.0712 (tools/added_mass_square_tank.py 0.1 0.5: a multipole solution, between the
// concentric circular tanks' 1.041 and 1.083). The fit: least squares of forces.csv's Fx over t in [T/4, end] against
// a(t), v(t) (from the path) and a constant.
// Tolerance: C_a within 5% of 1.0712. Budget: the Stokes layer adds 4 (pi beta)^-1/2 = 1.1% at
// beta = D^2 / (nu T) = 4e4 (Wang, J. Fluid Mech. 32, 1968), the water's compressibility about
// (f / f_acoustic)^2 = 1% (the tank's lowest mode c0 / 2L = 10 Hz against 1 Hz), the wall's position
// on a radius of 8 particles a few %. (First planned: 10% about 1.06, the middle of the circular
// tanks' bracket; set to 5% about the square tank's value once it was computed, with the measured
// +2.8% in hand; docs/validation.md.) The fit must explain the force: its rms residual below 15% of
// the force amplitude. Quick mode (CI): the scene's dx = 0.0125 m (R/dx = 8, 30 s of one core),
// to 1.5 s; full mode (TURBID_FULL=1): dx = 0.00625 m (R/dx = 16, about 10 min).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <string>

#include <Eigen/Dense>

#include "tests/validation/validation_support.hpp"

using turbid::validation::full_mode;
using turbid::validation::read_csv;

TEST(OscillatingCylinder2d, AddedMassCoefficientMatchesPotentialFlow) {
  const double dx = full_mode() ? 0.00625 : 0.0125;
  const auto run = turbid::validation::run_scene_file("oscillating_cylinder_2d", dx);
  ASSERT_EQ(run.report.at("status").get<std::string>(), "completed") << run.report.dump(2);
  auto csv = read_csv(run.out / "forces.csv");
  const auto& t = csv["time [s]"];
  const auto& fx = csv["cylinder.Fx [N/m]"];
  const auto& x = csv["cylinder.x [m]"];
  ASSERT_EQ(t.size(), fx.size());
  const double A = 0.02, T = 1.0, R = 0.1, rho = 1000, w = 2 * std::numbers::pi / T;
  std::vector<int> rows;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= 0.25 * T) rows.push_back(int(i));
  ASSERT_GT(rows.size(), 100u);
  Eigen::MatrixXd M(rows.size(), 3);
  Eigen::VectorXd f(rows.size());
  double f_max = 0, x_dev = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const double ti = t[std::size_t(rows[r])];
    M(Eigen::Index(r), 0) = -A * w * w * std::cos(w * ti);  // a(t)
    M(Eigen::Index(r), 1) = -A * w * std::sin(w * ti);      // v(t)
    M(Eigen::Index(r), 2) = 1;
    f[Eigen::Index(r)] = fx[std::size_t(rows[r])];
    f_max = std::max(f_max, std::abs(f[Eigen::Index(r)]));
    x_dev = std::max(x_dev, std::abs(x[std::size_t(rows[r])] - (0.5 + A * (std::cos(w * ti) - 1))));
  }
  const Eigen::Vector3d c = M.colPivHouseholderQr().solve(f);
  const double rms = std::sqrt((M * c - f).squaredNorm() / double(rows.size()));
  const double mass = rho * std::numbers::pi * R * R;
  const double Ca = -c[0] / mass, amplitude = std::abs(c[0]) * A * w * w;
  std::printf("[ measured ] dx = %.5f m: C_a = %.4f (reference 1.0712), in-phase drag term "
              "%.4g N s/m^2, offset %.4g N/m; force amplitude %.4g N/m, fit residual rms %.4g N/m (%.1f%%), max |Fx| "
              "%.4g N/m; path x within %.2g m of the formula\n",
              dx, Ca, c[1], c[2], amplitude, rms, 100 * rms / amplitude, f_max, x_dev);
  EXPECT_LT(x_dev, 1e-12) << "forces.csv's x is the path's";
  EXPECT_NEAR(Ca, 1.0712, 0.05 * 1.0712);
  EXPECT_LT(rms, 0.15 * amplitude);
  std::filesystem::remove_all(run.out);
}
