// DEM contact law between two structures, or a structure and a wall, at the level of one contact
// point: Hertz normal force with Tsuji's restitution damping, Coulomb friction through a Mindlin
// tangential spring, and the contact time step. Finding contacts (which surfaces touch, where) is the
// caller's; sphere_plane / sphere_sphere give the geometry for the simple cases.
//
// Pair parameters (end 2 may be a wall: radius, mass, Young's modulus = infinity):
//   1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2                    effective modulus (Hertz)
//   1/G* = 2 (2 - nu1)(1 + nu1)/E1 + 2 (2 - nu2)(1 + nu2)/E2  i.e. (2 - nu)/G per side (Mindlin)
//   1/R* = 1/R1 + 1/R2,  1/m* = 1/m1 + 1/m2
// Normal force along the normal n (pointing from 2 to 1) for overlap delta > 0 and overlap rate
// delta' = -(v1 - v2) . n:
//   F_n = max(0, k_n delta^(3/2) + eta_n delta^(1/4) delta'),  k_n = 4/3 E* sqrt(R*),
//   eta_n = alpha sqrt(m* k_n)                                   (Tsuji, Tanaka & Ishida 1992)
// The delta^(1/4) factor makes the damping scale with the Hertz stiffness, so the coefficient of
// restitution depends on alpha alone, not on the impact speed: with delta = s X, t = (s / v0) tau and
// s = (5 m* v0^2 / (4 k_n))^(2/5) the contact becomes
//   X'' = -max(0, 5/4 X^(3/2) + alpha sqrt(5/4) X^(1/4) X'),  X(0) = 0, X'(0) = 1,  e = -X'(exit).
// restitution_of_damping integrates exactly this (clamped) law (RK4, dtau = 1e-3; e is settled to
// ~1e-6), and damping_of_restitution inverts it by bisection, so alpha gives the chosen e for the
// force this file computes, clamp included (Tsuji et al. tabulated the same relation). The clamp
// keeps the contact from pulling: near the end of a damped rebound the dashpot outweighs the spring.
// Tangential force (Mindlin-like spring with Coulomb's cap), from the tangential relative velocity
// v_t at the contact point and the spring's elongation xi kept per contact:
//   xi <- (xi projected onto the current tangent plane, length kept) + dt v_t
//   F_t = -k_t xi - eta_t v_t,  k_t = 8 G* sqrt(R* delta),  eta_t = alpha sqrt(m* 8 G* sqrt(R*)) delta^(1/4)
//   |F_t| > mu F_n: F_t scaled to length mu F_n (sliding) and xi reset to -(F_t + eta_t v_t) / k_t, so
//   the spring holds just what friction allows and the body sticks again as soon as it can.
// Time step. The undamped Hertz collision lasts
//   t_c = tau_c (5 m* / (4 k_n))^(2/5) v0^(-1/5),  tau_c = 2 int_0^1 (1 - X^(5/2))^(-1/2) dX
//       = (4/5) B(2/5, 1/2) = 2.9432...,   i.e. t_c = 2.868 (m*^2 / (E*^2 R* v0))^(1/5) (Johnson 1985),
// and damping shortens the time the force acts (to 0.8 t_c at e = 0.3; the overlap lasts a little
// longer, the clamped contact coasting out force-free). contact_time_step returns t_c /
// steps_per_contact for the largest expected approach speed; 50 steps give the restitution within 2%
// for e >= 0.3 whatever the phase of the first touch within a step (the unit tests; at e = 0.1 the
// steep delta^(1/4) onset of the dashpot makes that 6%, 100 steps bring it back to 3%). A resting
// contact has no approach speed: pass a floor such as the speed the body would gain falling through
// its own static overlap, or the largest relative speed of the bodies in the scene.
#pragma once
#include <Eigen/Core>

#include "fsi/rigid_body.hpp"

namespace turbid::fsi {

// One side of a contact. A wall or a fixed structure: radius and mass infinite (as is the Young's
// modulus of a rigid wall).
struct ContactSide {
  double youngs_modulus = 0;  // E [Pa]
  double poisson_ratio = 0;   // nu [-], in [0, 0.5]
  double radius = 0;          // local radius of curvature at the contact [m] (infinity: flat)
  double mass = 0;            // [kg] (infinity: fixed)
};

struct ContactLaw {
  double effective_modulus = 0;        // E* [Pa]
  double effective_shear_modulus = 0;  // G* [Pa]
  double effective_radius = 0;         // R* [m]
  double effective_mass = 0;           // m* [kg]
  double damping_factor = 0;           // Tsuji's alpha [-], giving the restitution
  double restitution = 1;              // e [-]
  double friction = 0;                 // Coulomb mu [-]
};

// How the scene combines two structures' restitution and friction into the pair's is the caller's
// choice; this takes the pair's values. Throws std::invalid_argument for a restitution outside
// (0, 1], negative friction, moduli not positive, Poisson ratios outside [0, 0.5], radii or masses
// not positive, or two infinite radii or masses.
ContactLaw make_contact_law(const ContactSide& side_1, const ContactSide& side_2, double restitution, double friction);

double effective_modulus(double youngs_1, double poisson_1, double youngs_2, double poisson_2);        // E*
double effective_shear_modulus(double youngs_1, double poisson_1, double youngs_2, double poisson_2);  // G*

// (4/3) E* sqrt(R*) delta^(3/2) [N]; 0 for delta <= 0.
double hertz_normal_force(double effective_modulus, double effective_radius, double overlap);

// e(alpha) and its inverse for the clamped Tsuji law (see above).
double restitution_of_damping(double damping_factor);
double damping_of_restitution(double restitution);

// The elongation of a contact's tangential spring [m]; kept by the caller for as long as the
// contact lasts and reset when it ends.
struct TangentialSpring {
  Eigen::Vector3d elongation = Eigen::Vector3d::Zero();
};

struct ContactForce {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // on side 1 [N]; side 2 gets -force
  double normal_force = 0;                          // F_n >= 0 [N]
  bool sliding = false;                             // Coulomb's cap is active
};

// Force on side 1 at one contact: overlap [m] (> 0 in contact; otherwise zero force and the spring
// is reset), unit normal from 2 to 1, relative velocity v1 - v2 of the contact point [m/s], and dt
// the time since this contact's previous evaluation [s] (the elongation grows by dt v_t).
ContactForce contact_force(const ContactLaw& law, double overlap, const Eigen::Vector3d& normal,
                           const Eigen::Vector3d& relative_velocity, TangentialSpring& spring, double dt);

// Undamped Hertz contact duration t_c [s] at approach speed v0 [m/s] (see above).
double hertz_contact_duration(const ContactLaw& law, double approach_speed);
// t_c / steps_per_contact.
double contact_time_step(const ContactLaw& law, double approach_speed, double steps_per_contact = 50);

// Where a sphere (centre, radius) meets a plane (a point on it, unit outward normal) or another
// sphere: overlap (<= 0: apart), normal from the second to the first, and the contact point (the
// middle of the overlap).
struct ContactGeometry {
  double overlap = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};
ContactGeometry sphere_plane(const Eigen::Vector3d& centre, double radius, const Eigen::Vector3d& plane_point,
                             const Eigen::Vector3d& plane_normal);
ContactGeometry sphere_sphere(const Eigen::Vector3d& centre_1, double radius_1, const Eigen::Vector3d& centre_2,
                              double radius_2);

// The force on side 1 applied at `point`, as wrenches on both sides' bodies (nullptr: a wall).
PairWrench contact_wrench(const Eigen::Vector3d& force_on_1, const Eigen::Vector3d& point, const RigidBody* body_1,
                          const RigidBody* body_2);

}  // namespace turbid::fsi
