// Validation S (docs/validation.md): creeping flow through a square array of circular cylinders
// (scenes/stokes_array_2d.yaml: one fixed no-slip cylinder, D = 0.1 m, in a doubly periodic cell
// of side L = 6 D, Newtonian fluid driven by a body force g along x, Re = 0.01).
//
// Reference: Sangani & Acrivos (1982), Int. J. Multiphase Flow 8, square array, the dimensionless
// drag F / (mu U) = 4 pi / (-1/2 ln c - 0.738 + c - 0.887 c^2 + 2.039 c^3) = 10.51 at the solid
// fraction c = pi R^2 / L^2 = 0.0218. There F is the force per cylinder of a flow driven by a mean
// pressure gradient G, so F = G L^2 (it includes the mean gradient's push on the cylinder itself),
// and U is the superficial velocity, the flux per unit cell width: U = U_fluid (1 - c). The same
// relation is the array's Darcy permeability, L^2 / K = F / (mu U). A body force on the fluid
// alone drives the same velocity field as G = rho g, so the comparable figure is
//   F / (mu U) = rho g L^2 / (mu U_fluid (1 - c)) = F_cyl / (mu U_fluid (1 - c)^2),
// with F_cyl the measured force on the cylinder (= the body force on the fluid at steady state).
//
// Measured (docs/validation.md S): -3.6% at D/dx = 10 (11 s on 2 cores, 2026-12-07), -2.1% at D/dx = 20
// (an earlier session; to be rerun with D/dx = 40 for the observed order, issue #50 item 1).
// Tolerances earned by those: 5% in quick mode (CI, D/dx = 10), 3% in full mode (D/dx = 20). Also
// asserted, from the momentum balance at steady state: the force on the cylinder equals the body
// force on the fluid within 1%.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>

#include "tests/validation/validation_support.hpp"

namespace fs = std::filesystem;
using turbid::validation::full_mode;
using turbid::validation::read_csv;

TEST(ValidationStokesArray, DragMatchesSanganiAcrivosSquareArray) {
  const double dx = full_mode() ? 0.005 : 0.01;
  const double tolerance = full_mode() ? 0.03 : 0.05;
  const double pi = 3.14159265358979323846;
  const double L = 0.6, R = 0.05, mu = 100.0, rho = 1000.0, g = 0.0298;  // as in the scene
  const double c = pi * R * R / (L * L);
  const double reference = 4 * pi / (-0.5 * std::log(c) - 0.738 + c - 0.887 * c * c + 2.039 * c * c * c);
  ASSERT_NEAR(reference, 10.51, 0.01);

  const auto run = turbid::validation::run_scene_file("stokes_array_2d", dx);
  const auto& report = run.report;
  ASSERT_EQ(report.at("status").get<std::string>(), "completed") << report.dump(2);
  const double mass = report.at("fluid_mass_end").get<double>();
  const double u_fluid = report.at("fluid_momentum_end").at(0).get<double>() / mass;  // mean fluid u_x
  ASSERT_GT(u_fluid, 0);

  // The force on the cylinder, averaged over the last 0.2 s (steady after about 1 s).
  auto forces = read_csv(run.out / "forces.csv");
  const auto& t = forces["time [s]"];
  const auto& fx = forces["cyl.Fx [N/m]"];
  ASSERT_EQ(fx.size(), t.size());
  const double end = t.back();
  double sum = 0;
  int n = 0;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= end - 0.2) {
      sum += fx[k];
      ++n;
    }
  ASSERT_GT(n, 10);
  const double f_cyl = sum / n;
  const double body = mass * g;  // the body force on the fluid [N/m]
  EXPECT_NEAR(f_cyl / body, 1.0, 0.01) << "steady state: the cylinder carries the body force on the fluid";

  const double measured = f_cyl / (mu * u_fluid * (1 - c) * (1 - c));
  const double from_body = rho * g * L * L / (mu * u_fluid * (1 - c));
  const double rel = (measured - reference) / reference;
  std::cout << "[stokes array D/dx=" << 2 * R / dx << "] F/(mu U) = " << measured << " (from the body force "
            << from_body << "; Sangani & Acrivos " << reference << "), error " << 100 * rel << "%, "
            << report.at("wall_seconds").get<double>() << " s wall\n";
  RecordProperty("F_over_mu_U", std::to_string(measured));
  EXPECT_LT(std::abs(rel), tolerance);
  fs::remove_all(run.out);
}
