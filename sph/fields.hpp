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
};

// Registers what `params` needs (a water-only run with Fourtakas diffusion gets no gradient field).
FieldIds register_fields(ParticleStore& store, const PhysicsParams& params);

}  // namespace turbid::sph
