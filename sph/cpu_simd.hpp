// CPU helpers for the neighbour search (host code only, never compiled for the device): which
// entries of a small array of squared distances lie inside the kernel support, as a bit mask.
#pragma once
#include <cstdint>

#include "sph/config.hpp"

#if defined(__AVX__) && !defined(__CUDA_ARCH__)
#include <immintrin.h>
#endif

namespace turbid::sph {

// Bit k of the result is set iff r2[k] < limit, for k < len <= 64. With AVX, eight comparisons
// per instruction; the plain loop gives the same bits elsewhere.
TURBID_INLINE std::uint64_t below_mask(const Real* r2, std::uint32_t len, Real limit) {
  std::uint64_t mask = 0;
  std::uint32_t k = 0;
#if defined(__AVX__) && !defined(__CUDA_ARCH__)
  static_assert(sizeof(Real) == 4, "the AVX path compares floats");
  const __m256 lim = _mm256_set1_ps(limit);
  for (; k + 8 <= len; k += 8) {
    const __m256 v = _mm256_loadu_ps(r2 + k);
    const auto bits = std::uint32_t(_mm256_movemask_ps(_mm256_cmp_ps(v, lim, _CMP_LT_OQ)));
    mask |= std::uint64_t(bits) << k;
  }
#endif
  for (; k < len; ++k) mask |= std::uint64_t(r2[k] < limit ? 1u : 0u) << k;
  return mask;
}

}  // namespace turbid::sph
