// From the Scene to the built-in bodies' fast forces (fsi/body_constraints.hpp, fsi/body_contacts.hpp):
// the walls and fixed structures as contact obstacles, each moving structure's contact shape and the
// scene's constraints in body frames. No I/O here.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "fsi/body_constraints.hpp"
#include "fsi/body_contacts.hpp"
#include "fsi/rigid_body.hpp"
#include "fsi/scene.hpp"

namespace turbid::fsi {

// The surface layer (layer 0) of each structure's sampled particles, world positions at t = 0.
using SurfaceLayers = std::vector<std::vector<Eigen::Vector3d>>;

// Whether a structure contacts as its exact sphere (a 3D sphere; a 2D sphere or cylinder, a circle).
bool contacts_as_sphere(const Scene& scene, const StructureSpec& st);

// Walls (container faces, polyline segments, solid boxes) and fixed and prescribed structures as
// obstacles (the prescribed ones at t = 0, with their structure index and reference point).
ContactWorld contact_world(const Scene& scene, const SurfaceLayers& surface);

// Contacts of the free bodies, or nullptr when no moving structure has a contact material.
// `bodies`: one per structure, at t = 0 (for the centres of mass and masses).
std::unique_ptr<BodyContacts> body_contacts(const Scene& scene, const SurfaceLayers& surface,
                                            const std::vector<std::optional<RigidBody>>& bodies);

// The scene's constraints with their points in body frames, rest lengths resolved and hinges as
// pivots (body_constraints.hpp). Throws std::invalid_argument (located) for an end that is not a
// free structure.
std::vector<BodyConstraint> body_constraints(const Scene& scene, const std::vector<std::optional<RigidBody>>& bodies);

// 3D hinges to an anchor about a world axis lock the body's other two rotations (2D: nothing to lock).
void add_hinge_locks(const Scene& scene, std::size_t structure, DofMask& mask);

}  // namespace turbid::fsi
