// The device backend's one switch between its two builds (docs/architecture.md, "Backends"):
//
//  - nvcc: Thrust's CUDA system. Buffers live in GPU memory, passes run as CUDA kernels.
//  - g++ with THRUST_DEVICE_SYSTEM=THRUST_DEVICE_SYSTEM_OMP: Thrust's OpenMP system. Buffers live
//    in host memory, passes run on OpenMP threads. No CUDA runtime is needed, so CI runs the
//    device code path (sort, gathers, scans, reductions, compaction and every pass) without a GPU.
//
// Everything that differs between the two is here: memory (allocate, free, copy, clear), the
// launch of a per-particle functor (on CUDA a kernel with a register bound for the 3D pair
// passes; on OpenMP thrust::for_each_n) and the execution policy with its caching allocator.
// device_backend.inl holds the backend's logic once and includes only this for the difference.
// Each build puts its definitions in its own namespace (TURBID_DEVICE_NS), so both may be linked
// into one program without two different definitions of one name.
#pragma once
#include <thrust/execution_policy.h>
#include <thrust/iterator/counting_iterator.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <stdexcept>
#include <string>

#include "sph/config.hpp"

#if defined(__CUDACC__)
#define TURBID_DEVICE_CUDA 1
#define TURBID_DEVICE_NS device_cuda
#include <cuda_runtime.h>

#include "sph/backend/cuda/cuda_check.hpp"
#else
#define TURBID_DEVICE_CUDA 0
#define TURBID_DEVICE_NS device_omp
#if THRUST_DEVICE_SYSTEM != THRUST_DEVICE_SYSTEM_OMP
#error "device_system.hpp outside nvcc needs THRUST_DEVICE_SYSTEM=THRUST_DEVICE_SYSTEM_OMP"
#endif
#include <omp.h>
#include <thrust/for_each.h>
#include <thrust/system/omp/execution_policy.h>
#endif

namespace turbid::sph::TURBID_DEVICE_NS {

// ---- memory ---------------------------------------------------------------------------------

inline void* device_allocate(std::size_t bytes) {
  const std::size_t b = bytes > 0 ? bytes : 1;
#if TURBID_DEVICE_CUDA
  void* p = nullptr;
  const cudaError_t e = cudaMalloc(&p, b);
  if (e != cudaSuccess) cuda::throw_cuda_error(e, "cudaMalloc(" + std::to_string(bytes) + " bytes)", __FILE__, __LINE__);
  return p;
#else
  // 256-byte aligned, as cudaMalloc's blocks are (the passes cast them to any field type).
  void* p = std::aligned_alloc(256, (b + 255) / 256 * 256);
  if (p == nullptr) throw std::bad_alloc();
  return p;
#endif
}

inline void device_free(void* p) noexcept {
#if TURBID_DEVICE_CUDA
  // A destructor cannot throw; at program exit the runtime may already be unloaded.
  if (p != nullptr) (void)cudaFree(p);
#else
  std::free(p);
#endif
}

// Copies between the host and the device, or within the device (memcpy where they are one).
enum class CopyKind { to_device, to_host, on_device };
inline void device_copy(void* dst, const void* src, std::size_t bytes, CopyKind kind) {
  if (bytes == 0) return;
#if TURBID_DEVICE_CUDA
  const cudaMemcpyKind k = kind == CopyKind::to_device ? cudaMemcpyHostToDevice
                           : kind == CopyKind::to_host ? cudaMemcpyDeviceToHost
                                                       : cudaMemcpyDeviceToDevice;
  TURBID_CUDA_CHECK(cudaMemcpy(dst, src, bytes, k));
#else
  (void)kind;
  std::memcpy(dst, src, bytes);
#endif
}
inline void copy_to_device(void* dst, const void* src, std::size_t bytes) { device_copy(dst, src, bytes, CopyKind::to_device); }
inline void copy_to_host(void* dst, const void* src, std::size_t bytes) { device_copy(dst, src, bytes, CopyKind::to_host); }
inline void copy_on_device(void* dst, const void* src, std::size_t bytes) { device_copy(dst, src, bytes, CopyKind::on_device); }

inline void clear_device(void* dst, std::size_t bytes) {
  if (bytes == 0) return;
#if TURBID_DEVICE_CUDA
  TURBID_CUDA_CHECK(cudaMemset(dst, 0, bytes));
#else
  std::memset(dst, 0, bytes);
#endif
}

// Thrust's temporary storage (sort buffers, reduction partials) from blocks kept for reuse: after
// the first step a step allocates nothing. Blocks are returned to the device at destruction.
class CachingAllocator {
 public:
  using value_type = char;
  CachingAllocator() = default;
  CachingAllocator(const CachingAllocator&) = delete;
  CachingAllocator& operator=(const CachingAllocator&) = delete;
  ~CachingAllocator() {
    for (auto& [bytes, p] : free_) device_free(p);
    for (auto& [p, bytes] : used_) device_free(p);
  }
  char* allocate(std::ptrdiff_t bytes) {
    const std::size_t want = std::size_t(bytes > 0 ? bytes : 1);
    char* p = nullptr;
    auto it = free_.lower_bound(want);
    if (it != free_.end() && it->first <= 2 * want + 8192) {  // reuse a block, unless it is far too big
      p = it->second;
      used_.emplace(p, it->first);
      free_.erase(it);
      return p;
    }
    // A quarter more than asked, in 4 KiB pages: a count that grows a little each step (inflow,
    // splitting) keeps reusing the block.
    const std::size_t bytes_out = (want + want / 4 + 4095) / 4096 * 4096;
    p = static_cast<char*>(device_allocate(bytes_out));
    ++allocations_;
    used_.emplace(p, bytes_out);
    return p;
  }
  void deallocate(char* p, std::size_t) {
    auto it = used_.find(p);
    if (it == used_.end()) return;
    free_.emplace(it->second, p);
    used_.erase(it);
  }
  // Blocks allocated from the device since construction (a test checks that steady steps add none).
  std::size_t allocations() const { return allocations_; }
  // Bytes held, in use or cached.
  std::size_t bytes() const {
    std::size_t b = 0;
    for (auto& [bytes, p] : free_) b += bytes;
    for (auto& [p, bytes] : used_) b += bytes;
    return b;
  }

 private:
  std::multimap<std::size_t, char*> free_;  // by size
  std::map<char*, std::size_t> used_;
  std::size_t allocations_ = 0;
};

// The execution policies for Thrust's algorithms, with the caching allocator. `policy` blocks until
// the device is done (Thrust's CUDA par synchronises after each algorithm): for the algorithms whose
// result the host reads (a compaction's count). `async_policy` returns at once on CUDA (par_nosync):
// for sorts, scans and fills whose results only later device work reads, in stream order. On the
// OpenMP system both are the same synchronous policy.
inline auto policy(CachingAllocator& a) {
#if TURBID_DEVICE_CUDA
  return thrust::cuda::par(a);
#else
  return thrust::omp::par(a);
#endif
}
inline auto async_policy(CachingAllocator& a) {
#if TURBID_DEVICE_CUDA
  return thrust::cuda::par_nosync(a);
#else
  return thrust::omp::par(a);
#endif
}

// Host threads that run the passes: the OpenMP build's team (`requested` > 0 sets it, as the CPU
// backend does); 1 on CUDA, where the device does the work.
inline int host_threads(int requested) {
#if TURBID_DEVICE_CUDA
  (void)requested;
  return 1;
#else
  return requested > 0 ? requested : omp_get_max_threads();
#endif
}
inline void use_host_threads(int requested) {
#if TURBID_DEVICE_CUDA
  (void)requested;
#else
  if (requested > 0) omp_set_num_threads(requested);
#endif
}

// ---- launching a per-particle functor f(i), i in [0, n) ----------------------------------------

#if TURBID_DEVICE_CUDA
constexpr unsigned kBlock = 256;
inline unsigned blocks_for(std::size_t n) { return unsigned((n + kBlock - 1) / kBlock); }

// The functor (with its PhysicsParams, about 0.8 KB) stays in the kernel's parameter space:
// __grid_constant__ lets the passes index it at run time (materials[m], zones[k]) without a copy
// to local memory per thread (sm_70 and later; we build for sm_90).
template <class F, class Index>
__global__ void run_pass(const __grid_constant__ F f, Index n) {
  const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(Index(i));
}

// The same kernel with a register bound: at least MinBlocks blocks of kBlock threads per
// multiprocessor (3: <= 80 registers a thread, 4: <= 64). The 3D pair passes need 84-108 registers
// unbounded, which leaves 2 blocks (25% occupancy) on sm_90 for loops that wait on loads.
template <class F, int MinBlocks>
__global__ void __launch_bounds__(kBlock, MinBlocks) run_pass_bounded(const __grid_constant__ F f, std::uint32_t n) {
  const std::size_t i = std::size_t(blockIdx.x) * blockDim.x + threadIdx.x;
  if (i < n) f(std::uint32_t(i));
}

// Blocks per multiprocessor the 3D pair passes are compiled for: 4 (<= 64 registers) unless
// TURBID_CUDA_MIN_BLOCKS says 3 or 0 (unbounded). Measured on an H200 (docs/performance.md, the 3D
// dam break at 4 M particles): 0.88, 1.15 and 1.25 x 10^8 particle-steps/s for 0, 3 and 4.
inline int pair_min_blocks() {
  static const int v = [] {
    const char* e = std::getenv("TURBID_CUDA_MIN_BLOCKS");
    if (e == nullptr || *e == '\0') return 4;
    const int b = std::atoi(e);
    return b == 3 || b == 4 ? b : 0;
  }();
  return v;
}
#endif

// Runs f(i) for every i in [0, n). Index is std::uint32_t (particles, cells) or std::size_t
// (words of a field).
template <class Index, class F>
void launch(const char* name, Index n, const F& f) {
  if (n == 0) return;
#if TURBID_DEVICE_CUDA
  if (std::size_t(n) > std::size_t(kBlock) * 0x7fffffffu) throw std::length_error(std::string(name) + ": too many threads");
  run_pass<<<blocks_for(std::size_t(n)), kBlock>>>(f, n);
  TURBID_CUDA_CHECK_LAUNCH(name);
#else
  (void)name;
  thrust::for_each_n(thrust::omp::par, thrust::counting_iterator<Index>(0), n, f);
#endif
}

// Launches a pair pass (a neighbour loop per particle): on CUDA in 3D with the register bound
// above; otherwise as launch().
template <int D, class F>
void launch_pairs(const char* name, std::uint32_t n, const F& f) {
#if TURBID_DEVICE_CUDA
  if constexpr (D == 3) {
    if (n == 0) return;
    switch (pair_min_blocks()) {
      case 3: run_pass_bounded<F, 3><<<blocks_for(n), kBlock>>>(f, n); break;
      case 4: run_pass_bounded<F, 4><<<blocks_for(n), kBlock>>>(f, n); break;
      default: run_pass<<<blocks_for(n), kBlock>>>(f, n); break;
    }
    TURBID_CUDA_CHECK_LAUNCH(name);
    return;
  }
#endif
  launch(name, n, f);
}

// isfinite / isnan (float or double) in code that runs on either side.
template <class T>
TURBID_HD inline bool finite(T x) {
#if defined(__CUDA_ARCH__)
  return ::isfinite(x);
#else
  return std::isfinite(x);
#endif
}
template <class T>
TURBID_HD inline bool is_nan(T x) {
#if defined(__CUDA_ARCH__)
  return ::isnan(x);
#else
  return std::isnan(x);
#endif
}

}  // namespace turbid::sph::TURBID_DEVICE_NS
