// The device backends a test of the GPU code path can run here: "cuda" where a usable GPU is, and
// "device-omp" (the same device code built for Thrust's OpenMP system) where it is compiled, so
// that CI runs these tests without a GPU. TURBID_DEVICE_BACKEND=cuda or =device-omp picks one;
// TURBID_REQUIRE_DEVICE_TESTS=1 (set by .ci/run) makes a missing backend a failure, not a skip.
#pragma once
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "sph/backend.hpp"

namespace turbid::testing {

// The names, or none with the reason in `why_none`.
inline std::vector<std::string> device_backends(std::string* why_none) {
  std::vector<std::string> names;
  std::string no_gpu;
  if (sph::cuda_device_count(&no_gpu) > 0) names.push_back("cuda");
  if (sph::omp_device_backend_compiled()) names.push_back("device-omp");
  if (const char* only = std::getenv("TURBID_DEVICE_BACKEND"); only != nullptr && *only != '\0') {
    std::vector<std::string> kept;
    for (const auto& n : names)
      if (n == only) kept.push_back(n);
    names = kept;
    if (names.empty() && why_none)
      *why_none = std::string("TURBID_DEVICE_BACKEND=") + only + " is not available here (cuda: " + no_gpu + ")";
    return names;
  }
  if (names.empty() && why_none)
    *why_none = no_gpu + "; and this build has no device-omp backend (TURBID_ENABLE_DEVICE_OMP)";
  return names;
}

inline std::unique_ptr<sph::Backend> make_device_backend(const std::string& name, int threads = 2) {
  return name == "cuda" ? sph::make_cuda_backend() : sph::make_omp_device_backend(threads);
}

// Runs body(name) for each device backend here (the failure messages name it), or skips the test
// with the reason when there is none.
template <class F>
void for_each_device_backend(F&& body) {
  std::string why;
  const std::vector<std::string> names = device_backends(&why);
  if (names.empty()) {
    // CI sets this: there the device tests must run (on device-omp), not skip.
    if (const char* req = std::getenv("TURBID_REQUIRE_DEVICE_TESTS"); req != nullptr && *req == '1')
      FAIL() << "TURBID_REQUIRE_DEVICE_TESTS=1 but no device backend is available: " << why;
    GTEST_SKIP() << why;
  }
  for (const std::string& name : names) {
    SCOPED_TRACE("device backend " + name);
    body(name);
  }
}

}  // namespace turbid::testing
