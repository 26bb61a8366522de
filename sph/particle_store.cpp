// Storage and bookkeeping of the particle store; see particle_store.hpp.
#include "sph/particle_store.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace turbid::sph {

std::size_t scalar_size(ScalarType t) {
  switch (t) {
    case ScalarType::f32: return 4;
    case ScalarType::f64: return 8;
    case ScalarType::i32: return 4;
    case ScalarType::u32: return 4;
    case ScalarType::u8: return 1;
  }
  return 0;
}

const char* scalar_name(ScalarType t) {
  switch (t) {
    case ScalarType::f32: return "f32";
    case ScalarType::f64: return "f64";
    case ScalarType::i32: return "i32";
    case ScalarType::u32: return "u32";
    case ScalarType::u8: return "u8";
  }
  return "?";
}

namespace {
std::unique_ptr<std::byte[]> zeroed(std::size_t bytes) {
  auto p = std::make_unique<std::byte[]>(std::max<std::size_t>(bytes, 1));
  std::memset(p.get(), 0, std::max<std::size_t>(bytes, 1));
  return p;
}
}  // namespace

FieldId ParticleStore::add_field(FieldDesc desc) {
  if (find(desc.name)) throw std::invalid_argument("field registered twice: " + desc.name);
  if (desc.carry == Carry::divide && desc.type != ScalarType::f32 && desc.type != ScalarType::f64)
    throw std::invalid_argument("field '" + desc.name + "' carries to daughters by division but is not floating point");
  Field f{std::move(desc), nullptr};
  f.data = zeroed(capacity_ * scalar_size(f.desc.type) * std::size_t(f.desc.components));
  fields_.push_back(std::move(f));
  return FieldId(fields_.size() - 1);
}

std::optional<FieldId> ParticleStore::find(std::string_view name) const {
  for (std::size_t i = 0; i < fields_.size(); ++i)
    if (fields_[i].desc.name == name) return FieldId(i);
  return std::nullopt;
}

FieldId ParticleStore::require(std::string_view name) const {
  if (auto id = find(name)) return *id;
  throw std::out_of_range("no particle field named '" + std::string(name) + "'");
}

std::size_t ParticleStore::field_bytes(FieldId id) const {
  const auto& d = desc(id);
  return scalar_size(d.type) * std::size_t(d.components);
}

std::size_t ParticleStore::bytes_per_particle() const {
  std::size_t b = 0;
  for (int i = 0; i < field_count(); ++i) b += field_bytes(i);
  return b;
}

void ParticleStore::reserve(std::size_t capacity) {
  if (capacity <= capacity_) return;
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    const std::size_t fb = field_bytes(FieldId(i));
    auto fresh = zeroed(capacity * fb);
    if (size_ > 0) std::memcpy(fresh.get(), fields_[i].data.get(), size_ * fb);
    fields_[i].data = std::move(fresh);
  }
  capacity_ = capacity;
}

void ParticleStore::resize(std::size_t n) {
  if (n > capacity_) reserve(std::max(n, capacity_ + capacity_ / 2));
  if (n > size_) {
    for (std::size_t i = 0; i < fields_.size(); ++i) {
      const std::size_t fb = field_bytes(FieldId(i));
      std::memset(fields_[i].data.get() + size_ * fb, 0, (n - size_) * fb);
    }
  }
  size_ = n;
}

void ParticleStore::permute(const std::uint32_t* order) {
  std::size_t need = 0;
  for (int i = 0; i < field_count(); ++i) need = std::max(need, field_bytes(i) * size_);
  if (need > scratch_bytes_) {
    scratch_ = std::make_unique<std::byte[]>(need);
    scratch_bytes_ = need;
  }
  const std::ptrdiff_t n = std::ptrdiff_t(size_);
  for (auto& f : fields_) {
    if (!f.desc.follows_sort) continue;
    const std::size_t fb = scalar_size(f.desc.type) * std::size_t(f.desc.components);
    std::byte* src = f.data.get();
    std::byte* dst = scratch_.get();
    if (fb == 4) {
      auto* s = reinterpret_cast<const std::uint32_t*>(src);
      auto* d = reinterpret_cast<std::uint32_t*>(dst);
#pragma omp parallel for schedule(static) if (n >= 4096)
      for (std::ptrdiff_t i = 0; i < n; ++i) d[i] = s[order[i]];
    } else {
#pragma omp parallel for schedule(static) if (n >= 4096)
      for (std::ptrdiff_t i = 0; i < n; ++i) std::memcpy(dst + std::size_t(i) * fb, src + std::size_t(order[i]) * fb, fb);
    }
    std::memcpy(src, dst, size_ * fb);
  }
}

std::size_t ParticleStore::compact(const std::uint8_t* keep) {
  std::size_t w = 0;
  for (std::size_t r = 0; r < size_; ++r) {
    if (!keep[r]) continue;
    if (w != r) {
      for (auto& f : fields_) {
        const std::size_t fb = scalar_size(f.desc.type) * std::size_t(f.desc.components);
        std::memcpy(f.data.get() + w * fb, f.data.get() + r * fb, fb);
      }
    }
    ++w;
  }
  const std::size_t removed = size_ - w;
  size_ = w;
  return removed;
}

}  // namespace turbid::sph
