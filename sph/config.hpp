// Build-wide numeric type and the host/device marker shared by the CPU and CUDA backends.
#pragma once

#if defined(__CUDACC__)
#define TURBID_HD __host__ __device__
#else
#define TURBID_HD
#endif

namespace turbid::sph {

// Particle fields are single precision on both backends (memory bandwidth bound on the GPU);
// reductions that must conserve (mass, momentum, energy) accumulate in double.
using Real = float;

}  // namespace turbid::sph
