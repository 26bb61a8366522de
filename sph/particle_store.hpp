// The particle store: one array per registered field (structure of arrays), allocated with a
// capacity above the particle count so that passes may insert particles (splitting) without
// reallocating. Field metadata drives VTK output, checkpoints, sorting and daughter creation.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace turbid::sph {

enum class ScalarType : std::uint8_t { f32, f64, i32, u32, u8 };

std::size_t scalar_size(ScalarType t);
const char* scalar_name(ScalarType t);

// How a field is carried from a mother particle to its daughters when a particle splits (applied by
// SplitFieldTable in sph/splitting.hpp, the same on every backend).
enum class Carry : std::uint8_t {
  copy,       // daughters take the mother's value (velocity, density, material)
  divide,     // daughters share the mother's value equally (mass)
  recompute,  // a pass recomputes it (pressure, accelerations); the mother's value is a placeholder
};

struct FieldDesc {
  std::string name;         // VTK/checkpoint name, snake_case
  std::string unit;         // SI unit, "1" for dimensionless, "" for labels
  ScalarType type = ScalarType::f32;
  int components = 1;       // 1 for scalars, the dimension for vectors
  bool write_vtk = false;   // written to particles_NNNN.vtp
  bool checkpoint = true;   // written to checkpoints (needed for a bit-identical resume)
  bool follows_sort = true; // reordered when particles are sorted by cell
  Carry carry = Carry::copy;
};

using FieldId = int;

class ParticleStore {
 public:
  ParticleStore() = default;
  ParticleStore(ParticleStore&&) noexcept = default;
  ParticleStore& operator=(ParticleStore&&) noexcept = default;

  FieldId add_field(FieldDesc desc);
  std::optional<FieldId> find(std::string_view name) const;
  FieldId require(std::string_view name) const;  // throws std::out_of_range if absent
  const FieldDesc& desc(FieldId id) const { return fields_.at(std::size_t(id)).desc; }
  int field_count() const { return int(fields_.size()); }

  std::size_t size() const { return size_; }
  std::size_t capacity() const { return capacity_; }
  void reserve(std::size_t capacity);
  void resize(std::size_t n);  // grows capacity if needed; new entries are zero

  std::size_t bytes_per_particle() const;
  std::size_t field_bytes(FieldId id) const;  // bytes per particle of one field

  void* raw(FieldId id) { return fields_[std::size_t(id)].data.get(); }
  const void* raw(FieldId id) const { return fields_[std::size_t(id)].data.get(); }
  template <class T>
  T* data(FieldId id) {
    return static_cast<T*>(raw(id));
  }
  template <class T>
  const T* data(FieldId id) const {
    return static_cast<const T*>(raw(id));
  }

  // new[i] = old[order[i]] for every field that follows the sort.
  void permute(const std::uint32_t* order);
  // Keeps particles whose keep[i] != 0, in their order; returns how many were removed.
  std::size_t compact(const std::uint8_t* keep);

 private:
  struct Field {
    FieldDesc desc;
    std::unique_ptr<std::byte[]> data;
  };
  std::vector<Field> fields_;
  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
  std::unique_ptr<std::byte[]> scratch_;
  std::size_t scratch_bytes_ = 0;
};

}  // namespace turbid::sph
