// Backend availability when the CUDA or device-omp backend is not compiled in. Their builds
// provide the same functions from backend/cuda/ and backend/omp_device/.
#include <stdexcept>

#include "sph/backend.hpp"

#ifndef TURBID_HAVE_CUDA

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

#ifndef TURBID_HAVE_DEVICE_OMP
namespace turbid::sph {

bool omp_device_backend_compiled() { return false; }

std::unique_ptr<Backend> make_omp_device_backend(int) {
  throw std::runtime_error(
      "the device-omp backend is not compiled into this build (it needs the CUDA toolkit's CCCL headers; "
      "configure with -DTURBID_ENABLE_DEVICE_OMP=ON)");
}

}  // namespace turbid::sph
#endif
