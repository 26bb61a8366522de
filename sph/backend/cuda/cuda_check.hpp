// Error checks for the CUDA backend: every runtime call goes through TURBID_CUDA_CHECK and every
// kernel launch is followed by TURBID_CUDA_CHECK_LAUNCH("kernel name"), so a failure becomes a
// std::runtime_error that names the call or kernel, the source line and CUDA's own message.
// Set TURBID_CUDA_SYNC=1 in the environment to synchronise after each launch, so that an error
// inside a kernel is reported at that kernel rather than at the next copy.
#pragma once
#include <cuda_runtime.h>

#include <cstdlib>
#include <stdexcept>
#include <string>

namespace turbid::sph::cuda {

inline std::string cuda_error_text(cudaError_t e) {
  return std::string(cudaGetErrorName(e)) + ": " + cudaGetErrorString(e);
}

[[noreturn]] inline void throw_cuda_error(cudaError_t e, const std::string& what, const char* file, int line) {
  (void)cudaGetLastError();  // clear a non-sticky error so that later calls start clean
  throw std::runtime_error("CUDA error in " + what + " at " + file + ":" + std::to_string(line) + ": " +
                           cuda_error_text(e));
}

inline void check_call(cudaError_t e, const char* call, const char* file, int line) {
  if (e != cudaSuccess) throw_cuda_error(e, call, file, line);
}

inline bool sync_after_launch() {
  static const bool on = [] {
    const char* v = std::getenv("TURBID_CUDA_SYNC");
    return v != nullptr && v[0] != '\0' && v[0] != '0';
  }();
  return on;
}

inline void check_launch(const char* kernel, const char* file, int line) {
  cudaError_t e = cudaGetLastError();
  if (e == cudaSuccess && sync_after_launch()) e = cudaDeviceSynchronize();
  if (e != cudaSuccess) throw_cuda_error(e, std::string("kernel ") + kernel, file, line);
}

}  // namespace turbid::sph::cuda

#define TURBID_CUDA_CHECK(call) ::turbid::sph::cuda::check_call((call), #call, __FILE__, __LINE__)
#define TURBID_CUDA_CHECK_LAUNCH(kernel) ::turbid::sph::cuda::check_launch((kernel), __FILE__, __LINE__)
