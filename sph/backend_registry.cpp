// Backend availability when the CUDA backend is not compiled in (CPU-only build). The CUDA build
// provides the same functions from backend/cuda/.
#ifndef TURBID_HAVE_CUDA
#include <stdexcept>

#include "sph/backend.hpp"

namespace turbid::sph {

bool cuda_backend_compiled() { return false; }

int cuda_device_count(std::string* reason) {
  if (reason) *reason = "this build has no CUDA backend (nvcc was not found or TURBID_ENABLE_CUDA=OFF)";
  return 0;
}

std::unique_ptr<Backend> make_cuda_backend() {
  throw std::runtime_error("the CUDA backend is not compiled into this build (nvcc was not found at configure time)");
}

}  // namespace turbid::sph
#endif
