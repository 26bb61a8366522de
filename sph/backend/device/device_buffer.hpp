// An owned, untyped block of device memory (move-only): GPU memory in the CUDA build, host memory
// in the OpenMP build (device_system.hpp). The device backend keeps one per particle field, sized
// from the field registry, so it needs no code per field.
#pragma once
#include <cstddef>
#include <utility>

#include "sph/backend/device/device_system.hpp"

namespace turbid::sph::TURBID_DEVICE_NS {

class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(std::size_t bytes) { allocate(bytes); }
  ~DeviceBuffer() { release(); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& o) noexcept
      : ptr_(std::exchange(o.ptr_, nullptr)), bytes_(std::exchange(o.bytes_, 0)) {}
  DeviceBuffer& operator=(DeviceBuffer&& o) noexcept {
    if (this != &o) {
      release();
      ptr_ = std::exchange(o.ptr_, nullptr);
      bytes_ = std::exchange(o.bytes_, 0);
    }
    return *this;
  }

  // Replaces the block by a fresh one of `bytes` (contents undefined).
  void allocate(std::size_t bytes) {
    release();
    ptr_ = device_allocate(bytes);
    bytes_ = bytes;
  }
  // Grows to at least `bytes`; contents are lost when it grows.
  void ensure(std::size_t bytes) {
    if (ptr_ == nullptr || bytes > bytes_) allocate(bytes);
  }
  void clear() { clear_device(ptr_, bytes_); }

  void* get() const { return ptr_; }
  template <class T>
  T* as() const {
    return static_cast<T*>(ptr_);
  }
  std::size_t bytes() const { return bytes_; }
  void swap(DeviceBuffer& o) noexcept {
    std::swap(ptr_, o.ptr_);
    std::swap(bytes_, o.bytes_);
  }

 private:
  void release() noexcept {
    device_free(ptr_);
    ptr_ = nullptr;
    bytes_ = 0;
  }

  void* ptr_ = nullptr;
  std::size_t bytes_ = 0;
};

}  // namespace turbid::sph::TURBID_DEVICE_NS
