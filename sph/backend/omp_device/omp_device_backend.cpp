// The "device-omp" backend: the device backend (backend/device/device_backend.inl) built by g++ for
// Thrust's OpenMP system (THRUST_DEVICE_SYSTEM_OMP, set by CMake for this file's target). It runs
// the GPU code path on CPU threads: the same sort, gathers, scans, reductions and pass launches,
// so that every CI run executes them without a GPU (docs/architecture.md, "Backends"). For speed
// use the "cpu" backend, which adds neighbour lists and vectorised pair loops.
#include "sph/backend/device/device_backend.inl"

namespace turbid::sph {

bool omp_device_backend_compiled() { return true; }

std::unique_ptr<Backend> make_omp_device_backend(int threads) {
  return std::make_unique<device_omp::DeviceBackend>("device-omp", threads);
}

}  // namespace turbid::sph
