// Particle store (sph/particle_store.hpp): field registry, resize/reserve, permute, compact.
// References: values written by the test itself (exact integer and float bit patterns), the
// documented semantics new[i] = old[order[i]] and "keep in order", and the sum of field sizes.
#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "sph/fields.hpp"
#include "sph/particle_store.hpp"

namespace {

using namespace turbid::sph;

struct Store3 {
  ParticleStore s;
  FieldId a, v, tag;
  Store3() {
    a = s.add_field({"a", "m", ScalarType::f32, 1, true, true, true, Carry::copy});
    v = s.add_field({"v", "m/s", ScalarType::f64, 3, false, true, true, Carry::copy});
    tag = s.add_field({"tag", "", ScalarType::u8, 1, false, false, false, Carry::recompute});  // does not follow sort
  }
  void fill(std::size_t n) {
    s.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      s.data<float>(a)[i] = float(i) + 0.5f;
      for (int k = 0; k < 3; ++k) s.data<double>(v)[3 * i + std::size_t(k)] = 100.0 * double(i) + k;
      s.data<std::uint8_t>(tag)[i] = std::uint8_t(i + 1);
    }
  }
};

TEST(ParticleStore, AddAndFindFields) {
  Store3 t;
  EXPECT_EQ(t.s.field_count(), 3);
  EXPECT_EQ(t.s.find("v"), std::optional<FieldId>(t.v));
  EXPECT_EQ(t.s.require("tag"), t.tag);
  EXPECT_FALSE(t.s.find("nope").has_value());
  EXPECT_THROW(t.s.require("nope"), std::out_of_range);
  EXPECT_EQ(t.s.desc(t.v).components, 3);
  EXPECT_EQ(t.s.desc(t.a).unit, "m");
}

TEST(ParticleStore, DuplicateNameThrows) {
  Store3 t;
  EXPECT_THROW(t.s.add_field({"v", "m", ScalarType::f32, 1}), std::invalid_argument) << "field registered twice";
  EXPECT_EQ(t.s.field_count(), 3);
}

TEST(ParticleStore, BytesPerParticleIsSumOfFieldSizes) {
  Store3 t;
  // f32 x1 + f64 x3 + u8 x1 = 4 + 24 + 1
  EXPECT_EQ(t.s.field_bytes(t.a), 4u);
  EXPECT_EQ(t.s.field_bytes(t.v), 24u);
  EXPECT_EQ(t.s.field_bytes(t.tag), 1u);
  EXPECT_EQ(t.s.bytes_per_particle(), 29u);
  // The engine's fields: 2D water run without a gradient field: position 8, velocity 8,
  // acceleration 8, density 4, density_rate 4, pressure 4, mass 4, h 4, material 1, kind 1, id 4.
  PhysicsParams p;
  p.dimensions = 2;
  p.diffusion = Diffusion::fourtakas;
  ParticleStore s;
  register_fields(s, p);
  std::size_t sum = 0;
  for (int i = 0; i < s.field_count(); ++i) sum += scalar_size(s.desc(i).type) * std::size_t(s.desc(i).components);
  EXPECT_EQ(s.bytes_per_particle(), sum);
  EXPECT_EQ(s.bytes_per_particle(), 3u * 8 + 5 * 4 + 2 * 1 + 4);  // 50
  // Antuono diffusion adds the density gradient (D x f32); in 3D every vector is 12 bytes.
  p.dimensions = 3;
  p.diffusion = Diffusion::antuono;
  ParticleStore s3;
  const FieldIds ids = register_fields(s3, p);
  EXPECT_GE(ids.density_gradient, 0);
  EXPECT_EQ(s3.bytes_per_particle(), 12u * 4 + 4 * 5 + 1 * 2 + 4);
}

TEST(ParticleStore, ResizeKeepsDataAndZeroFills) {
  Store3 t;
  t.fill(10);
  t.s.resize(1000);  // beyond the capacity: reallocates
  EXPECT_EQ(t.s.size(), 1000u);
  EXPECT_GE(t.s.capacity(), 1000u);
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(t.s.data<float>(t.a)[i], float(i) + 0.5f) << i;
    EXPECT_EQ(t.s.data<double>(t.v)[3 * i + 2], 100.0 * double(i) + 2) << i;
    EXPECT_EQ(t.s.data<std::uint8_t>(t.tag)[i], std::uint8_t(i + 1)) << i;
  }
  for (std::size_t i = 10; i < 1000; ++i) {
    ASSERT_EQ(t.s.data<float>(t.a)[i], 0.0f) << "new entry " << i << " is zero";
    for (int k = 0; k < 3; ++k) ASSERT_EQ(t.s.data<double>(t.v)[3 * i + std::size_t(k)], 0.0) << i;
    ASSERT_EQ(t.s.data<std::uint8_t>(t.tag)[i], 0) << i;
  }
}

TEST(ParticleStore, ShrinkThenGrowZeroFills) {
  Store3 t;
  t.fill(10);
  const std::size_t cap = t.s.capacity();
  t.s.resize(4);
  EXPECT_EQ(t.s.capacity(), cap) << "shrinking keeps the allocation";
  t.s.resize(8);  // within capacity: entries 4..7 held old values and must read as new (zero)
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(t.s.data<float>(t.a)[i], float(i) + 0.5f);
  for (std::size_t i = 4; i < 8; ++i) {
    EXPECT_EQ(t.s.data<float>(t.a)[i], 0.0f) << i;
    EXPECT_EQ(t.s.data<double>(t.v)[3 * i], 0.0) << i;
    EXPECT_EQ(t.s.data<std::uint8_t>(t.tag)[i], 0) << i;
  }
}

TEST(ParticleStore, ReserveGrowsCapacityAndKeepsData) {
  Store3 t;
  t.fill(7);
  t.s.reserve(5000);
  EXPECT_EQ(t.s.capacity(), 5000u);
  EXPECT_EQ(t.s.size(), 7u);
  for (std::size_t i = 0; i < 7; ++i) {
    EXPECT_EQ(t.s.data<float>(t.a)[i], float(i) + 0.5f);
    EXPECT_EQ(t.s.data<double>(t.v)[3 * i + 1], 100.0 * double(i) + 1);
    EXPECT_EQ(t.s.data<std::uint8_t>(t.tag)[i], std::uint8_t(i + 1));
  }
  t.s.reserve(10);  // smaller: no change
  EXPECT_EQ(t.s.capacity(), 5000u);
  EXPECT_EQ(t.s.data<float>(t.a)[6], 6.5f);
  // A field added after reserve gets the full capacity, zeroed.
  const FieldId late = t.s.add_field({"late", "1", ScalarType::i32, 2});
  t.s.resize(5000);
  for (std::size_t i = 0; i < 2 * 5000; ++i) ASSERT_EQ(t.s.data<std::int32_t>(late)[i], 0);
}

TEST(ParticleStore, PermuteReordersOnlySortedFields) {
  Store3 t;
  t.fill(6);
  const std::uint32_t order[6] = {5, 0, 3, 1, 4, 2};
  t.s.permute(order);
  for (std::size_t i = 0; i < 6; ++i) {
    const std::size_t o = order[i];
    EXPECT_EQ(t.s.data<float>(t.a)[i], float(o) + 0.5f) << "new[i] = old[order[i]], f32, i=" << i;
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(t.s.data<double>(t.v)[3 * i + std::size_t(k)], 100.0 * double(o) + k) << "f64x3, i=" << i;
    EXPECT_EQ(t.s.data<std::uint8_t>(t.tag)[i], std::uint8_t(i + 1)) << "follows_sort=false is untouched, i=" << i;
  }
}

TEST(ParticleStore, PermuteEngineFields) {
  // The registered engine fields: position, velocity, density, mass, id follow the sort;
  // acceleration, density_rate and pressure do not (they are recomputed after every sort).
  PhysicsParams p;
  p.dimensions = 2;
  ParticleStore s;
  const FieldIds ids = register_fields(s, p);
  const std::size_t n = 5;
  s.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.data<float>(ids.position)[2 * i + 1] = float(i);
    s.data<float>(ids.acceleration)[2 * i + 1] = float(i);
    s.data<float>(ids.pressure)[i] = float(i);
    s.data<std::uint32_t>(ids.id)[i] = std::uint32_t(i);
  }
  const std::uint32_t order[5] = {4, 3, 2, 1, 0};
  s.permute(order);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(s.data<float>(ids.position)[2 * i + 1], float(order[i]));
    EXPECT_EQ(s.data<std::uint32_t>(ids.id)[i], order[i]);
    EXPECT_EQ(s.data<float>(ids.acceleration)[2 * i + 1], float(i)) << "acceleration does not follow the sort";
    EXPECT_EQ(s.data<float>(ids.pressure)[i], float(i)) << "pressure does not follow the sort";
  }
}

TEST(ParticleStore, CompactRemovesFlaggedInOrder) {
  Store3 t;
  t.fill(9);
  const std::uint8_t keep[9] = {1, 0, 0, 1, 1, 0, 1, 0, 1};
  EXPECT_EQ(t.s.compact(keep), 4u) << "removed count";
  ASSERT_EQ(t.s.size(), 5u);
  const std::size_t kept[5] = {0, 3, 4, 6, 8};
  for (std::size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(t.s.data<float>(t.a)[i], float(kept[i]) + 0.5f) << i;
    EXPECT_EQ(t.s.data<double>(t.v)[3 * i + 2], 100.0 * double(kept[i]) + 2) << i;
    // compact moves every field, including those that do not follow the sort
    EXPECT_EQ(t.s.data<std::uint8_t>(t.tag)[i], std::uint8_t(kept[i] + 1)) << i;
  }
  // Keeping everything removes nothing; removing everything empties the store.
  const std::uint8_t all[5] = {1, 1, 1, 1, 1}, none[5] = {0, 0, 0, 0, 0};
  EXPECT_EQ(t.s.compact(all), 0u);
  EXPECT_EQ(t.s.size(), 5u);
  EXPECT_EQ(t.s.compact(none), 5u);
  EXPECT_EQ(t.s.size(), 0u);
}

TEST(ParticleStore, MoveKeepsData) {
  Store3 t;
  t.fill(3);
  ParticleStore moved = std::move(t.s);
  EXPECT_EQ(moved.size(), 3u);
  EXPECT_EQ(moved.data<float>(t.a)[2], 2.5f);
}

}  // namespace
