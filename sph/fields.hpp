// The particle fields the fluid engine registers, with their units and carry rules.
#pragma once
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

struct FieldIds {
  FieldId position = -1, velocity = -1, acceleration = -1;
  FieldId density = -1, density_rate = -1, pressure = -1;
  FieldId mass = -1, smoothing_length = -1, material = -1, kind = -1, id = -1;
  FieldId density_gradient = -1;  // registered only for Antuono diffusion
  FieldId boundary_normal = -1;   // registered only for mDBC
  FieldId viscous_velocity = -1;  // registered only for no-slip mDBC
  FieldId body = -1, structure_force = -1;  // registered only when the scene has structures
  // Only when the scene has moving bodies: each body particle's position relative to its body's
  // centre of mass in the body frame, and (mDBC) its ghost offset in the body frame; the placement
  // after each drift rotates them into the world (sph/body_motion.hpp).
  FieldId body_offset = -1, body_normal = -1;
  FieldId zone = -1;                        // registered only with open boundaries
  FieldId free_slip = -1;                   // registered only with free-slip walls (1: the particle's wall slips)
  FieldId shifting_velocity = -1;           // registered only with particle shifting
  FieldId split_fresh = -1;                 // registered only with transitions (1: daughter of the last split)
  FieldId shear_rate = -1, effective_viscosity = -1, shear_stress = -1;  // only with a non-Newtonian material
  // Only with structures and implicit viscosity: the implicit viscous updates' reaction on each
  // structure particle, summed until the next force pass reads and clears it.
  FieldId viscous_load = -1, viscous_pending = -1;
  // Only with impermeable walls (sph::WallConstraintPass): each fluid particle's momentum change
  // by the put-back of the last drift and the boundary particle it is booked to (scratch between
  // the pass and the booking, both before the sort), and each boundary particle's share of that
  // drift's constraint, as a force and a power over the step (WallConstraintLoadPass).
  FieldId put_back_impulse = -1, put_back_from = -1;
  FieldId constraint_force = -1, constraint_power = -1;
};

// Registers what `params` needs (a water-only run with Fourtakas diffusion gets no gradient field).
// `structures`: the scene has structures (body index and per-particle force fields).
// `moving_bodies`: some structure moves (body_offset, and body_normal with mDBC).
FieldIds register_fields(ParticleStore& store, const PhysicsParams& params, bool structures = false,
                         bool moving_bodies = false);

}  // namespace turbid::sph
