// Turns run-time choices of a scene (kernel, diffusion, uniform h) into compile-time template
// arguments of the passes, so that one binary runs any scene without branches in the pair loop.
#pragma once
#include <type_traits>

#include "sph/kernels.hpp"
#include "sph/physics_params.hpp"

namespace turbid::sph {

template <class T>
struct TypeTag {
  using type = T;
};

// f(TypeTag<Kernel>, std::bool_constant<uniform_h>)
template <int D, class F>
void dispatch_kernel(const PhysicsParams& p, F&& f) {
  if (p.kernel == KernelKind::wendland_c2) {
    if (p.uniform_h) f(TypeTag<WendlandC2<D>>{}, std::true_type{});
    else f(TypeTag<WendlandC2<D>>{}, std::false_type{});
  } else {
    if (p.uniform_h) f(TypeTag<CubicSpline<D>>{}, std::true_type{});
    else f(TypeTag<CubicSpline<D>>{}, std::false_type{});
  }
}

// f(std::integral_constant<Diffusion, d>)
template <class F>
void dispatch_diffusion(Diffusion d, F&& f) {
  switch (d) {
    case Diffusion::none: f(std::integral_constant<Diffusion, Diffusion::none>{}); break;
    case Diffusion::molteni: f(std::integral_constant<Diffusion, Diffusion::molteni>{}); break;
    case Diffusion::antuono: f(std::integral_constant<Diffusion, Diffusion::antuono>{}); break;
    case Diffusion::fourtakas: f(std::integral_constant<Diffusion, Diffusion::fourtakas>{}); break;
  }
}

}  // namespace turbid::sph
