// Build-wide numeric type and the host/device marker shared by the CPU and CUDA backends.
#pragma once

#if defined(__CUDACC__)
#define TURBID_HD __host__ __device__
#else
#define TURBID_HD
#endif

// For the small functions inside the pair loops (neighbour walk, image shifts, masks): GCC's
// inliner gives up on them once the loop bodies around them grow, and a call per pair or per cell
// range cost the CPU backend 40% of a step (measured A/B on the 3D benchmark).
#if defined(__CUDACC__)
#define TURBID_INLINE __forceinline__
#elif defined(__GNUC__)
#define TURBID_INLINE inline __attribute__((always_inline))
#else
#define TURBID_INLINE inline
#endif

namespace turbid::sph {

// Particle fields are single precision on both backends (memory bandwidth bound on the GPU);
// reductions that must conserve (mass, momentum, energy) accumulate in double.
using Real = float;

// Adds one to a counter shared by every thread of a pass (a tally of rare events, not a sum on
// which results depend: its order does not matter).
TURBID_HD inline void count_one(unsigned long long* counter) {
#if defined(__CUDA_ARCH__)
  atomicAdd(counter, 1ull);
#else
  __atomic_fetch_add(counter, 1ull, __ATOMIC_RELAXED);
#endif
}

}  // namespace turbid::sph
