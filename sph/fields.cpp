// Registration of the engine's particle fields; see fields.hpp.
#include "sph/fields.hpp"

namespace turbid::sph {

FieldIds register_fields(ParticleStore& s, const PhysicsParams& p, bool structures, bool moving_bodies) {
  const int d = p.dimensions;
  // 2D runs are per metre of depth: mass is then kg/m and volumes m^2.
  const char* mass_unit = d == 2 ? "kg/m" : "kg";
  FieldIds f;
  //                   name                unit          type              comp vtk    ckpt   sorted carry
  f.position = s.add_field({"position", "m", ScalarType::f32, d, true, true, true, Carry::recompute});
  f.velocity = s.add_field({"velocity", "m/s", ScalarType::f32, d, true, true, true, Carry::copy});
  // Accelerations are recomputed right after every sort, but the first half-kick of a step uses
  // the previous step's values, so they are checkpointed (bit-identical resume).
  f.acceleration = s.add_field({"acceleration", "m/s^2", ScalarType::f32, d, false, true, false, Carry::copy});
  f.density = s.add_field({"density", "kg/m^3", ScalarType::f32, 1, true, true, true, Carry::copy});
  f.density_rate = s.add_field({"density_rate", "kg/m^3/s", ScalarType::f32, 1, false, false, false, Carry::recompute});
  f.pressure = s.add_field({"pressure", "Pa", ScalarType::f32, 1, true, false, false, Carry::recompute});
  f.mass = s.add_field({"mass", mass_unit, ScalarType::f32, 1, false, true, true, Carry::divide});
  f.smoothing_length = s.add_field({"smoothing_length", "m", ScalarType::f32, 1, false, true, true, Carry::recompute});
  f.material = s.add_field({"material", "", ScalarType::u8, 1, true, true, true, Carry::recompute});
  f.kind = s.add_field({"kind", "", ScalarType::u8, 1, true, true, true, Carry::copy});
  f.id = s.add_field({"id", "", ScalarType::u32, 1, true, true, true, Carry::recompute});
  if (p.diffusion == Diffusion::antuono)
    f.density_gradient = s.add_field({"density_gradient", "kg/m^4", ScalarType::f32, d, false, false, false, Carry::recompute});
  // Ghost node offset x_g - x_b: twice the particle's depth below the wall surface, along the
  // outward normal (zero for fluid).
  // Also for no-slip DBC walls (wall_no_slip), whose mirrored velocity comes from their ghost nodes.
  if (p.boundary == Boundary::mdbc || p.wall_no_slip || p.wall_constraint || p.wall_function || p.wall_viscosity_normal)
    f.boundary_normal = s.add_field({"boundary_normal", "m", ScalarType::f32, d, true, true, true, Carry::copy});
  // Recomputed by the mDBC pass after every sort, before the momentum pass reads it; the implicit
  // viscous update at the start of the next step reads it too, so with implicit viscosity it is
  // checkpointed (bit-identical resume), like the acceleration.
  if (p.wall_no_slip)
    f.viscous_velocity = s.add_field(
        {"viscous_velocity", "m/s", ScalarType::f32, d, false, p.implicit_viscosity, false, Carry::recompute});
  if (structures) {
    f.body = s.add_field({"body", "", ScalarType::u8, 1, true, true, true, Carry::copy});
  }
  // The fluid's force on each structure particle, and on each wall particle with load sensors on walls.
  if (structures || p.wall_loads) {
    const char* force_unit = d == 2 ? "N/m" : "N";
    f.structure_force = s.add_field({"structure_force", force_unit, ScalarType::f32, d, true, false, false, Carry::recompute});
  }
  // Set once when the world is built; the placement reads them, so they follow the sort and are
  // checkpointed (they cannot be recomputed from rounded positions bit for bit).
  if (structures && moving_bodies) {
    f.body_offset = s.add_field({"body_offset", "m", ScalarType::f32, d, false, true, true, Carry::copy});
    if (p.boundary == Boundary::mdbc || p.wall_no_slip || p.wall_constraint || p.wall_function || p.wall_viscosity_normal)
      f.body_normal = s.add_field({"body_normal", "m", ScalarType::f32, d, false, true, true, Carry::copy});
  }
  // Computed by the momentum pass after each sort and used by the next drift, like the
  // acceleration by the next half-kick: checkpointed for a bit-identical resume.
  if (p.shifting_coefficient > 0)
    f.shifting_velocity = s.add_field({"shifting_velocity", "m/s", ScalarType::f32, d, false, true, false, Carry::recompute});
  // Recomputed by the rheology pass after every sort, before the momentum pass reads them; the
  // implicit viscous update of the next step reads mu_eff too (checkpointed then).
  if (p.rheology) {
    f.shear_rate = s.add_field({"shear_rate", "1/s", ScalarType::f32, 1, true, false, false, Carry::recompute});
    f.effective_viscosity = s.add_field(
        {"effective_viscosity", "Pa s", ScalarType::f32, 1, true, p.implicit_viscosity, false, Carry::recompute});
    f.shear_stress = s.add_field({"shear_stress", "Pa", ScalarType::f32, 1, true, false, false, Carry::recompute});
  }
  if (structures && p.implicit_viscosity) {
    const char* force_unit = d == 2 ? "N/m" : "N";
    // The implicit viscous updates' reaction on structure particles (sph/implicit_viscosity.hpp):
    // the step's load, and the second half-step's share waiting for the next step.
    f.viscous_load = s.add_field({"viscous_load", force_unit, ScalarType::f32, d, false, true, true, Carry::recompute});
    f.viscous_pending =
        s.add_field({"viscous_pending", force_unit, ScalarType::f32, d, false, true, true, Carry::recompute});
  }
  if (p.wall_constraint) {
    const char* momentum_unit = d == 2 ? "N s/m" : "N s";
    const char* force_unit = d == 2 ? "N/m" : "N";
    const char* power_unit = d == 2 ? "W/m" : "W";
    // Written for every fluid particle by each drift's WallConstraintPass and read by the booking
    // right after it, before the sort: scratch, not sorted.
    f.put_back_impulse =
        s.add_field({"put_back_impulse", momentum_unit, ScalarType::f32, d, false, false, false, Carry::recompute});
    f.put_back_from = s.add_field({"put_back_from", "", ScalarType::u32, 1, false, false, false, Carry::recompute});
    // Booked on walls and structures after the drift, read by the force pass after the sort.
    f.constraint_force =
        s.add_field({"constraint_force", force_unit, ScalarType::f32, d, false, false, true, Carry::recompute});
    f.constraint_power =
        s.add_field({"constraint_power", power_unit, ScalarType::f32, 1, false, false, true, Carry::recompute});
  }
  if (p.zone_count > 0) f.zone = s.add_field({"zone", "", ScalarType::u8, 1, true, true, true, Carry::copy});
  // Set by a split for its daughters and cleared by the next one; between steps it is read only by
  // the relaxation right after the split, so it is neither written out nor checkpointed.
  if (p.splitting)
    f.split_fresh = s.add_field({"split_fresh", "", ScalarType::u8, 1, false, false, true, Carry::copy});
  if (p.free_slip_walls)
    f.free_slip = s.add_field({"free_slip", "", ScalarType::u8, 1, false, true, true, Carry::copy});
  return f;
}

}  // namespace turbid::sph
