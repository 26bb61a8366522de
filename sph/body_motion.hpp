// Rigid placement of the particles of moving structures: after every drift (and kick) of the bodies
// each body particle is put where its body carries it and given its body's velocity there,
//   x = x_c + R r0,   v = v_c + w x (R r0),   (mDBC) ghost offset n = R n0,
// r0 and n0 the particle's offset and ghost offset in the body frame (fields body_offset and
// body_normal, set when the world is built). The body state is in double (fsi/rigid_body.hpp); the
// products are taken in double and rounded once to the particle's single-precision fields, so a
// particle never accumulates rounding from step to step. Shared by the backends (TURBID_HD).
#pragma once
#include <cstdint>

#include "sph/config.hpp"
#include "sph/physics_params.hpp"
#include "sph/vec.hpp"

namespace turbid::sph {

// The state of one structure as its particles see it; `moving` false leaves them alone (fixed).
struct BodyPlacement {
  bool moving = false;
  double centre[3] = {0, 0, 0};        // x_c [m]
  double rotation[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  // R, body frame -> world
  double velocity[3] = {0, 0, 0};      // v_c [m/s]
  double angular_velocity[3] = {0, 0, 0};  // w [rad/s], world frame
};

template <int D>
struct PlaceBodiesPass {
  Vec<D>* position = nullptr;
  Vec<D>* velocity = nullptr;
  Vec<D>* boundary_normal = nullptr;  // mDBC only
  const std::uint8_t* kind = nullptr;
  const std::uint8_t* body = nullptr;
  const Vec<D>* offset = nullptr;
  const Vec<D>* normal0 = nullptr;    // mDBC only
  const BodyPlacement* bodies = nullptr;
  int body_count = 0;
  bool move = true;  // false: velocities only (after a kick: the bodies have not moved)

  TURBID_HD void operator()(std::uint32_t i) const {
    if (kind[i] != std::uint8_t(Kind::structure)) return;
    const int k = body[i];
    if (k >= body_count || !bodies[k].moving) return;
    const BodyPlacement& B = bodies[k];
    double r0[3] = {0, 0, 0}, r[3] = {0, 0, 0};
    for (int a = 0; a < D; ++a) r0[a] = double(offset[i][a]);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < D; ++b) r[a] += B.rotation[a][b] * r0[b];
    const double* w = B.angular_velocity;
    const double wxr[3] = {w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]};
    for (int a = 0; a < D; ++a) velocity[i][a] = Real(B.velocity[a] + wxr[a]);
    if (!move) return;
    for (int a = 0; a < D; ++a) position[i][a] = Real(B.centre[a] + r[a]);
    if (boundary_normal && normal0) {
      for (int a = 0; a < D; ++a) {
        double n = 0;
        for (int b = 0; b < D; ++b) n += B.rotation[a][b] * double(normal0[i][b]);
        boundary_normal[i][a] = Real(n);
      }
    }
  }
};

}  // namespace turbid::sph
