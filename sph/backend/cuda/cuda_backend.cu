// The "cuda" backend: the device backend (backend/device/device_backend.inl) built by nvcc for
// Thrust's CUDA system, plus what only CUDA has: finding a usable GPU and creating its context.
#include "sph/backend/device/device_backend.inl"

#ifndef TURBID_CUDA_ARCHITECTURES
#define TURBID_CUDA_ARCHITECTURES "unknown"
#endif

namespace turbid::sph {
namespace device_cuda {
// Does nothing; cudaFuncGetAttributes on it tells whether this binary has code for the device.
__global__ void probe_kernel() {}
}  // namespace device_cuda

bool cuda_backend_compiled() { return true; }

int cuda_device_count(std::string* reason) {
  auto say = [&](std::string s) {
    if (reason) *reason = std::move(s);
  };
  int n = 0;
  cudaError_t e = cudaGetDeviceCount(&n);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(std::string("cudaGetDeviceCount: ") + cudaGetErrorString(e));
    return 0;
  }
  if (n <= 0) {
    say("cudaGetDeviceCount: no CUDA device found");
    return 0;
  }
  cudaDeviceProp prop{};
  e = cudaGetDeviceProperties(&prop, 0);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(std::string("cudaGetDeviceProperties(0): ") + cudaGetErrorString(e));
    return 0;
  }
  char text[512];
  std::snprintf(text, sizeof text, "%s (%.1f GiB, sm_%d%d)", prop.name, double(prop.totalGlobalMem) / double(1ull << 30),
                prop.major, prop.minor);
  std::string what = text;
  if (n > 1) what += " and " + std::to_string(n - 1) + " more (device 0 is used)";
  // A device this binary has no code for (e.g. built for sm_90, run on sm_80) cannot run a step.
  cudaFuncAttributes attr{};
  e = cudaFuncGetAttributes(&attr, device_cuda::probe_kernel);
  if (e != cudaSuccess) {
    (void)cudaGetLastError();
    say(what + ": no kernel image for this device (built for CUDA architectures " TURBID_CUDA_ARCHITECTURES "): " +
        cudaGetErrorString(e));
    return 0;
  }
  say(what);
  return n;
}

std::unique_ptr<Backend> make_cuda_backend() {
  std::string why;
  if (cuda_device_count(&why) <= 0) throw std::runtime_error("cuda backend: no usable CUDA device: " + why);
  TURBID_CUDA_CHECK(cudaSetDevice(0));
  TURBID_CUDA_CHECK(cudaFree(nullptr));  // create the context now, so that a broken device fails here
  return std::make_unique<device_cuda::DeviceBackend>("cuda", 0);
}

}  // namespace turbid::sph
