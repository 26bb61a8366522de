// Probe evaluation on the particle state (fronts, surface elevations, point pressures, maxima, energies).
#pragma once
#include <vector>

#include "fsi/scene.hpp"
#include "sph/fields.hpp"
#include "sph/particle_store.hpp"
#include "sph/physics_params.hpp"

namespace turbid::fsi {

// Material indices follow the order of Scene::materials.
std::vector<double> evaluate_probes(const Scene& scene, const sph::ParticleStore& store, const sph::FieldIds& ids,
                                    const sph::PhysicsParams& params);

// Unit of each probe type (probes.csv headers): SI, per metre of depth in 2D for the extensive ones.
const char* probe_unit(ProbeSpec::Type t, int dimensions);

}  // namespace turbid::fsi
