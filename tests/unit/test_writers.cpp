// Output writers and checkpoints (tools/): VTK series, CSV series, run.json, checkpoints, atomic
// files. References: VTK's own XML reader (binary VTK keeps float32/int bits exactly), the CSV
// and .pvd texts as specified in tools/*.hpp, and memcmp for bit-identical restarts.
#include <gtest/gtest.h>
#include <unistd.h>

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "sph/particle_store.hpp"
#include "tools/atomic_file.hpp"
#include "tools/checkpoint.hpp"
#include "tools/csv_writer.hpp"
#include "tools/run_report.hpp"
#include "tools/vtk_writer.hpp"

namespace fs = std::filesystem;
using turbid::sph::Carry;
using turbid::sph::FieldDesc;
using turbid::sph::ParticleStore;
using turbid::sph::ScalarType;

namespace {

// A fresh, empty directory per test, removed afterwards.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("turbid_writers_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every entry (recursively) whose name marks an unfinished write.
std::vector<std::string> leftovers(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find(".tmp") != std::string::npos || name.ends_with(".old")) out.push_back(e.path().string());
  }
  return out;
}

struct Ids {
  int position, velocity, density, material, body, tag, mass, pressure;
};

// position/velocity (f32 x dim), density (f32), material (u8), body (i32), tag (u32) are written
// to VTK; mass (f64) is checkpointed only; pressure is written to VTK but not checkpointed.
ParticleStore make_store(int dim, std::size_t n, Ids& ids) {
  ParticleStore s;
  ids.position = s.add_field({"position", "m", ScalarType::f32, dim, true, true, true, Carry::copy});
  ids.velocity = s.add_field({"velocity", "m/s", ScalarType::f32, dim, true, true, true, Carry::copy});
  ids.density = s.add_field({"density", "kg/m^3", ScalarType::f32, 1, true, true, true, Carry::copy});
  ids.material = s.add_field({"material", "", ScalarType::u8, 1, true, true, true, Carry::copy});
  ids.body = s.add_field({"body", "", ScalarType::i32, 1, true, true, true, Carry::copy});
  ids.tag = s.add_field({"tag", "", ScalarType::u32, 1, true, true, true, Carry::copy});
  ids.mass = s.add_field({"mass", "kg", ScalarType::f64, 1, false, true, true, Carry::divide});
  ids.pressure = s.add_field({"pressure", "Pa", ScalarType::f32, 1, true, false, true, Carry::recompute});
  s.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < dim; ++c) {
      s.data<float>(ids.position)[i * dim + c] = 0.1f * float(i) + 1.0f / float(3 + c);
      s.data<float>(ids.velocity)[i * dim + c] = -0.7f * float(i) + float(c) / 7.0f;
    }
    s.data<float>(ids.density)[i] = 1000.0f + 1.0f / float(i + 3);
    s.data<std::uint8_t>(ids.material)[i] = std::uint8_t(i % 3 + 250 * (i == 1));
    s.data<std::int32_t>(ids.body)[i] = int(i) - 3;
    s.data<std::uint32_t>(ids.tag)[i] = 4000000000u + std::uint32_t(i);
    s.data<double>(ids.mass)[i] = 0.1 / double(i + 1);
    s.data<float>(ids.pressure)[i] = 9.81f * float(i);
  }
  return s;
}

template <class T>
void expect_array(vtkPolyData* poly, const char* name, int vtk_type, int out_comp, const ParticleStore& s, int id) {
  SCOPED_TRACE(name);
  vtkDataArray* a = poly->GetPointData()->GetArray(name);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->GetDataType(), vtk_type);
  ASSERT_EQ(a->GetNumberOfComponents(), out_comp);
  ASSERT_EQ(a->GetNumberOfTuples(), vtkIdType(s.size()));
  const int in_comp = s.desc(id).components;
  const T* src = s.data<T>(id);
  const T* got = static_cast<const T*>(a->GetVoidPointer(0));
  for (std::size_t i = 0; i < s.size(); ++i)
    for (int c = 0; c < out_comp; ++c) {
      const T want = c < in_comp ? src[i * in_comp + c] : T(0);
      EXPECT_EQ(got[i * out_comp + c], want) << "particle " << i << " component " << c;
    }
}

// Reads one frame back with VTK's reader and compares it with the store, exactly.
void expect_frame_matches(const fs::path& file, const ParticleStore& s, const Ids& ids, int dim, double time) {
  SCOPED_TRACE(file.string());
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(file.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  ASSERT_NE(poly, nullptr);
  const std::size_t n = s.size();
  ASSERT_EQ(poly->GetNumberOfPoints(), vtkIdType(n));
  EXPECT_EQ(poly->GetNumberOfVerts(), vtkIdType(n)) << "one vertex cell per particle";
  EXPECT_EQ(poly->GetPoints()->GetDataType(), VTK_FLOAT);
  for (std::size_t i = 0; i < n; ++i) {
    double p[3];
    poly->GetPoint(vtkIdType(i), p);
    for (int c = 0; c < 3; ++c) {
      const float want = c < dim ? s.data<float>(ids.position)[i * dim + c] : 0.0f;
      EXPECT_EQ(float(p[c]), want) << "particle " << i << " coordinate " << c;
    }
  }
  expect_array<float>(poly, "velocity", VTK_FLOAT, 3, s, ids.velocity);
  expect_array<float>(poly, "density", VTK_FLOAT, 1, s, ids.density);
  expect_array<std::uint8_t>(poly, "material", VTK_UNSIGNED_CHAR, 1, s, ids.material);
  expect_array<std::int32_t>(poly, "body", VTK_INT, 1, s, ids.body);
  expect_array<std::uint32_t>(poly, "tag", VTK_UNSIGNED_INT, 1, s, ids.tag);
  expect_array<float>(poly, "pressure", VTK_FLOAT, 1, s, ids.pressure);
  EXPECT_EQ(poly->GetPointData()->GetArray("mass"), nullptr) << "write_vtk is off for mass";
  EXPECT_EQ(poly->GetPointData()->GetArray("position"), nullptr) << "position is the points";

  vtkFieldData* fd = poly->GetFieldData();
  for (const char* tname : {"TIME", "TimeValue"}) {
    vtkDataArray* t = fd->GetArray(tname);
    ASSERT_NE(t, nullptr) << tname;
    EXPECT_EQ(t->GetDataType(), VTK_DOUBLE);
    EXPECT_EQ(t->GetTuple1(0), time) << tname;
  }
  auto* units = vtkStringArray::SafeDownCast(fd->GetAbstractArray("units"));
  ASSERT_NE(units, nullptr);
  std::vector<std::string> u;
  for (vtkIdType i = 0; i < units->GetNumberOfValues(); ++i) u.push_back(units->GetValue(i));
  const std::vector<std::string> want = {"position [m]", "velocity [m/s]", "density [kg/m^3]", "material []",
                                         "body []",      "tag []",         "pressure [Pa]"};
  EXPECT_EQ(u, want);
}

void vtk_round_trip(int dim) {
  TempDir tmp("vtk" + std::to_string(dim));
  const fs::path out = tmp.path / "out";  // created by the writer
  Ids ids{};
  ParticleStore s = make_store(dim, 11, ids);
  turbid::tools::VtkSeriesWriter w(out, dim);
  EXPECT_EQ(w.frames(), 0);
  EXPECT_TRUE(w.last_file().empty());

  w.write(s, 0.0);
  EXPECT_EQ(w.frames(), 1);
  EXPECT_EQ(w.last_file(), out / "particles_0000.vtp");
  expect_frame_matches(w.last_file(), s, ids, dim, 0.0);

  // Second frame: particles moved, one more particle; a time with no exact binary value.
  s.resize(12);
  for (std::size_t i = 0; i < s.size() * std::size_t(dim); ++i) s.data<float>(ids.position)[i] += 0.25f;
  s.data<float>(ids.density)[11] = 999.5f;
  w.write(s, 0.1);
  EXPECT_EQ(w.frames(), 2);
  EXPECT_EQ(w.last_file(), out / "particles_0001.vtp");
  expect_frame_matches(w.last_file(), s, ids, dim, 0.1);

  // Reference: the ParaView collection format, one DataSet per frame with its time (shortest
  // round-trip decimal, so "0.1" reads back as the same double).
  const std::string pvd = read_text(out / "particles.pvd");
  EXPECT_NE(pvd.find("type=\"Collection\""), std::string::npos) << pvd;
  EXPECT_NE(pvd.find("<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"particles_0000.vtp\"/>"), std::string::npos) << pvd;
  EXPECT_NE(pvd.find("<DataSet timestep=\"0.1\" group=\"\" part=\"0\" file=\"particles_0001.vtp\"/>"), std::string::npos) << pvd;
  EXPECT_TRUE(leftovers(out).empty());
}

}  // namespace

TEST(VtkSeriesWriter, RoundTrip2DExact) {
  // Exact round trip: binary VTK stores float32/int bits; 2D vectors come back with z = 0.
  vtk_round_trip(2);
}

TEST(VtkSeriesWriter, RoundTrip3DExact) {
  // Exact round trip: binary VTK stores float32/int bits.
  vtk_round_trip(3);
}

TEST(VtkSeriesWriter, EmptyStoreAndDoublePosition) {
  // An empty store still gives a valid file (0 points); f64 positions stay f64 (VTK_DOUBLE).
  TempDir tmp("vtkempty");
  ParticleStore s;
  const int pos = s.add_field({"position", "m", ScalarType::f64, 3, true, true, true, Carry::copy});
  turbid::tools::VtkSeriesWriter w(tmp.path, 3);
  w.write(s, 0.0);
  vtkNew<vtkXMLPolyDataReader> r;
  r->SetFileName(w.last_file().c_str());
  r->Update();
  EXPECT_EQ(r->GetOutput()->GetNumberOfPoints(), 0);

  s.resize(2);
  s.data<double>(pos)[3] = 1.0 / 3.0;
  w.write(s, 1.0);
  r->SetFileName(w.last_file().c_str());
  r->Update();
  ASSERT_EQ(r->GetOutput()->GetNumberOfPoints(), 2);
  EXPECT_EQ(r->GetOutput()->GetPoints()->GetDataType(), VTK_DOUBLE);
  EXPECT_EQ(r->GetOutput()->GetPoint(1)[0], 1.0 / 3.0);
}

TEST(VtkSeriesWriter, RejectsMissingOrWrongPosition) {
  TempDir tmp("vtkbad");
  ParticleStore s;
  s.add_field({"density", "kg/m^3", ScalarType::f32, 1, true, true, true, Carry::copy});
  turbid::tools::VtkSeriesWriter w(tmp.path, 2);
  EXPECT_THROW(w.write(s, 0.0), std::invalid_argument);
  s.add_field({"position", "m", ScalarType::f32, 3, true, true, true, Carry::copy});
  EXPECT_THROW(w.write(s, 0.0), std::invalid_argument) << "3 components in a 2D writer";
  EXPECT_EQ(w.frames(), 0);
  EXPECT_THROW(turbid::tools::VtkSeriesWriter(tmp.path, 4), std::invalid_argument);
}

TEST(VtkSeriesWriter, ResumeKeepsFramesUpToCheckpointTime) {
  // Restart after a checkpoint at t = 0.2: frames at 0, 0.1, 0.2 stay; 0.3 is written again as 0003.
  TempDir tmp("vtkresume");
  Ids ids{};
  ParticleStore s = make_store(2, 4, ids);
  {
    turbid::tools::VtkSeriesWriter w(tmp.path, 2);
    for (double t : {0.0, 0.1, 0.2, 0.3}) w.write(s, t);
  }
  turbid::tools::VtkSeriesWriter w(tmp.path, 2);
  EXPECT_EQ(w.resume_after(0.2), 3);
  w.write(s, 0.30000000000000004);
  EXPECT_EQ(w.last_file(), tmp.path / "particles_0003.vtp");
  const std::string pvd = read_text(w.collection_file());
  EXPECT_NE(pvd.find("timestep=\"0.2\" group=\"\" part=\"0\" file=\"particles_0002.vtp\""), std::string::npos) << pvd;
  EXPECT_NE(pvd.find("timestep=\"0.30000000000000004\" group=\"\" part=\"0\" file=\"particles_0003.vtp\""),
            std::string::npos) << pvd;
  EXPECT_EQ(pvd.find("timestep=\"0.3\""), std::string::npos) << pvd;
}

TEST(CsvSeriesWriter, HeaderAndRowsRoundTripExactly) {
  // Reference: header exactly "time,<name>,..."; cells are shortest round-trip decimals.
  TempDir tmp("csv");
  const fs::path file = tmp.path / "sub" / "probes.csv";
  const std::vector<std::vector<double>> rows = {
      {0.0, 0.1, -2.5}, {1.0 / 3.0, 1e-300, 123456789.123456789}, {0.5, -0.0, 6.02214076e23}};
  {
    turbid::tools::CsvSeriesWriter w(file, {"front", "height"});
    w.append(rows[0]);
    w.append(rows[1][0], std::vector<double>{rows[1][1], rows[1][2]});
    w.append(rows[2]);
    EXPECT_EQ(w.rows(), 3u);
    EXPECT_THROW(w.append({1.0, 2.0}), std::invalid_argument);
    // Flushed after every row: readable before the writer closes.
    const std::string text = read_text(file);
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 4) << text;
  }
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time,front,height");
  for (const auto& want : rows) {
    ASSERT_TRUE(std::getline(in, line));
    std::vector<double> got;
    std::size_t start = 0;
    while (true) {
      const auto cut = line.find(',', start);
      const std::string cell = line.substr(start, cut == std::string::npos ? std::string::npos : cut - start);
      double v = std::numeric_limits<double>::quiet_NaN();
      std::from_chars(cell.data(), cell.data() + cell.size(), v);
      got.push_back(v);
      if (cut == std::string::npos) break;
      start = cut + 1;
    }
    ASSERT_EQ(got.size(), want.size()) << line;
    for (std::size_t k = 0; k < want.size(); ++k)
      EXPECT_EQ(std::memcmp(&got[k], &want[k], sizeof(double)), 0) << line << " cell " << k;
  }
  EXPECT_FALSE(std::getline(in, line));
  EXPECT_TRUE(leftovers(tmp.path).empty());
}

TEST(CsvSeriesWriter, ResumeKeepsRowsUpToTime) {
  TempDir tmp("csvresume");
  const fs::path file = tmp.path / "forces.csv";
  {
    turbid::tools::CsvSeriesWriter w(file, {"pipe_fx", "pipe_fy"});
    for (double t : {0.0, 0.1, 0.2, 0.3}) w.append({t, 2 * t, 3 * t});
  }
  {
    turbid::tools::CsvSeriesWriter w(file, {"pipe_fx", "pipe_fy"}, 0.2);
    EXPECT_EQ(w.rows(), 3u);
    w.append({0.25, 1.0, 2.0});
  }
  EXPECT_EQ(read_text(file), "time,pipe_fx,pipe_fy\n0,0,0\n0.1,0.2,0.30000000000000004\n0.2,0.4,0.6000000000000001\n0.25,1,2\n");
  {
    // Another header (the scene changed): start afresh.
    turbid::tools::CsvSeriesWriter w(file, {"other"}, 0.2);
    EXPECT_EQ(w.rows(), 0u);
  }
  EXPECT_EQ(read_text(file), "time,other\n");
  {
    turbid::tools::CsvSeriesWriter w(file, {"a,b"});  // RFC 4180 quoting
  }
  EXPECT_EQ(read_text(file), "time,\"a,b\"\n");
}

TEST(AtomicFile, ReplacesWholeFileAndLeavesNoTemp) {
  TempDir tmp("atomic");
  const fs::path f = tmp.path / "a.txt";
  EXPECT_EQ(turbid::tools::temp_path_for(f).parent_path(), tmp.path) << "same directory, so rename is atomic";
  turbid::tools::write_text_atomic(f, "first version, longer\n");
  turbid::tools::write_text_atomic(f, "second\n");
  EXPECT_EQ(read_text(f), "second\n");
  EXPECT_TRUE(leftovers(tmp.path).empty());
  EXPECT_THROW(turbid::tools::write_text_atomic(tmp.path / "missing_dir" / "x", "x"), std::runtime_error);
  EXPECT_TRUE(leftovers(tmp.path).empty());
}

TEST(AtomicFile, RunJsonIsPrettyAndParses) {
  TempDir tmp("runjson");
  const fs::path f = tmp.path / "results" / "run.json";
  nlohmann::json j = {{"steps", 1200}, {"particle_steps_per_second", 1.5e7}, {"name", "dam_break_2d"}};
  turbid::tools::write_run_json(f, j);
  const std::string text = read_text(f);
  EXPECT_EQ(nlohmann::json::parse(text), j);
  EXPECT_EQ(text, j.dump(2) + "\n");
  EXPECT_TRUE(leftovers(tmp.path).empty());
}

namespace {
ParticleStore make_target(int dim, Ids& ids) {
  // Same registry, different contents and size: the restore must overwrite all of it.
  ParticleStore t = make_store(dim, 3, ids);
  for (int id = 0; id < t.field_count(); ++id) std::memset(t.raw(id), 0x5a, t.size() * t.field_bytes(id));
  return t;
}
}  // namespace

TEST(Checkpoint, RoundTripIsBitIdentical) {
  // Reference: memcmp of every checkpointed field, including NaN payloads and -0.0.
  TempDir tmp("ckpt");
  const fs::path dir = tmp.path / "run" / "checkpoint";
  Ids ids{};
  ParticleStore s = make_store(3, 17, ids);
  s.data<float>(ids.density)[2] = -0.0f;
  const std::uint32_t nan_bits = 0x7fc01234u;
  std::memcpy(&s.data<float>(ids.velocity)[5], &nan_bits, 4);
  s.data<double>(ids.mass)[7] = std::nextafter(1.0, 2.0);
  const nlohmann::json state = {{"time", 0.30000000000000004}, {"step", 4242}, {"bodies", {{"pipe", {1.0, 2.0}}}}};

  turbid::tools::write_checkpoint(dir, make_store(3, 5, ids), {{"time", 0.0}});  // an older one to replace
  turbid::tools::write_checkpoint(dir, s, state);
  EXPECT_TRUE(leftovers(tmp.path).empty());
  EXPECT_TRUE(fs::exists(dir / "checkpoint.json"));
  EXPECT_FALSE(fs::exists(dir / "pressure.bin")) << "pressure is not checkpointed";

  Ids tids{};
  ParticleStore t = make_target(3, tids);
  const nlohmann::json got = turbid::tools::read_checkpoint(dir, t);
  EXPECT_EQ(got, state);
  EXPECT_EQ(got["time"].get<double>(), 0.30000000000000004);
  ASSERT_EQ(t.size(), s.size());
  for (int id = 0; id < s.field_count(); ++id) {
    SCOPED_TRACE(s.desc(id).name);
    const std::size_t bytes = s.size() * s.field_bytes(id);
    if (s.desc(id).checkpoint) {
      EXPECT_EQ(std::memcmp(t.raw(id), s.raw(id), bytes), 0);
    } else {
      const std::vector<std::byte> zeros(bytes);
      EXPECT_EQ(std::memcmp(t.raw(id), zeros.data(), bytes), 0) << "fields not checkpointed are zeroed";
    }
  }
}

TEST(Checkpoint, TruncatedFieldFileIsAnErrorNamingFileAndField) {
  TempDir tmp("ckpttrunc");
  const fs::path dir = tmp.path / "checkpoint/";  // trailing slash names the same directory
  Ids ids{};
  turbid::tools::write_checkpoint(dir, make_store(2, 9, ids), nullptr);
  fs::resize_file(tmp.path / "checkpoint" / "density.bin", 9 * 4 - 4);
  Ids tids{};
  ParticleStore t = make_target(2, tids);
  try {
    turbid::tools::read_checkpoint(dir, t);
    FAIL() << "no error for a truncated field file";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("density.bin"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'density'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  }
  EXPECT_EQ(t.size(), 3u) << "the store is not touched when a size check fails";
}

TEST(Checkpoint, MismatchesAreErrors) {
  TempDir tmp("ckptmismatch");
  const fs::path dir = tmp.path / "checkpoint";
  Ids ids{};
  turbid::tools::write_checkpoint(dir, make_store(2, 4, ids), nullptr);

  auto message = [&](ParticleStore& t) {
    try {
      turbid::tools::read_checkpoint(dir, t);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  {  // the store lacks a saved field
    ParticleStore t;
    t.add_field({"position", "m", ScalarType::f32, 2, true, true, true, Carry::copy});
    EXPECT_NE(message(t).find("'velocity'"), std::string::npos) << message(t);
  }
  {  // wrong type
    ParticleStore t = make_store(2, 1, ids);
    ParticleStore u;
    for (int id = 0; id < t.field_count(); ++id) {
      FieldDesc d = t.desc(id);
      if (d.name == "material") d.type = ScalarType::i32;
      u.add_field(d);
    }
    const std::string m = message(u);
    EXPECT_NE(m.find("'material'"), std::string::npos) << m;
    EXPECT_NE(m.find("u8"), std::string::npos) << m;
  }
  {  // wrong components (3D store, 2D checkpoint)
    ParticleStore t = make_store(3, 1, ids);
    EXPECT_NE(message(t).find("components"), std::string::npos) << message(t);
  }
  {  // a checkpointed field of the store is not in the checkpoint
    ParticleStore t = make_store(2, 1, ids);
    t.add_field({"stress", "Pa", ScalarType::f32, 4, false, true, true, Carry::copy});
    EXPECT_NE(message(t).find("'stress'"), std::string::npos) << message(t);
  }
  {  // a flipped byte: checksum
    std::fstream f(dir / "body.bin", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(5);
    f.put(char(0x7f));
    f.close();
    ParticleStore t = make_store(2, 1, ids);
    const std::string m = message(t);
    EXPECT_NE(m.find("body.bin"), std::string::npos) << m;
    EXPECT_NE(m.find("checksum"), std::string::npos) << m;
  }
  {  // not a checkpoint at all
    ParticleStore t = make_store(2, 1, ids);
    const fs::path other = tmp.path / "nothing";
    EXPECT_THROW(turbid::tools::read_checkpoint(other, t), std::runtime_error);
    fs::create_directories(other);
    std::ofstream(other / "checkpoint.json") << "{ not json";
    try {
      turbid::tools::read_checkpoint(other, t);
      ADD_FAILURE() << "no error for invalid JSON";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("checkpoint.json"), std::string::npos) << e.what();
    }
  }
}

// Issue #27 item 5: a checkpoint.json edited after it was written is refused, saying which block
// changed: the state (a time changed by hand), or the field list (a field file replaced and its
// checksum recomputed, which the per-file checksum alone lets through).
TEST(Checkpoint, AnEditedStateOrARecomputedChecksumIsRefused) {
  TempDir tmp("ckptedit");
  const fs::path dir = tmp.path / "checkpoint";
  Ids ids{};
  turbid::tools::write_checkpoint(dir, make_store(2, 5, ids), {{"time", 0.25}, {"step", 40}});
  const fs::path meta_file = dir / "checkpoint.json";
  const std::string original = [&] {
    std::ifstream in(meta_file);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }();
  auto refusal = [&](const std::string& meta_text) {
    std::ofstream(meta_file, std::ios::trunc) << meta_text;
    Ids tids{};
    ParticleStore t = make_target(2, tids);
    try {
      turbid::tools::read_checkpoint(dir, t);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(refusal(original), "no error");
  {  // the state's time edited
    std::string edited = original;
    const std::size_t at = edited.find("0.25");
    ASSERT_NE(at, std::string::npos);
    edited.replace(at, 4, "0.35");
    const std::string m = refusal(edited);
    EXPECT_NE(m.find("checkpoint.json"), std::string::npos) << m;
    EXPECT_NE(m.find("the 'state' block differs"), std::string::npos) << m;
    EXPECT_THROW(turbid::tools::read_checkpoint_state(dir), std::runtime_error);
  }
  {  // density.bin replaced (first byte changed) and its FNV-1a checksum recomputed in the JSON
    std::fstream f(dir / "density.bin", std::ios::in | std::ios::out | std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    bytes[0] = char(bytes[0] ^ 0x55);
    f.seekp(0);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    f.close();
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ull;
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
    std::string edited = original;
    const std::size_t field = edited.find("\"density.bin\"");
    ASSERT_NE(field, std::string::npos);
    const std::size_t sum = edited.find("\"fnv1a64\": \"", edited.rfind('{', field));
    ASSERT_NE(sum, std::string::npos);
    edited.replace(sum + 12, 16, hex);
    const std::string m = refusal(edited);
    EXPECT_NE(m.find("the 'fields' list"), std::string::npos) << m;
  }
}

TEST(Checkpoint, ReadsOldCopyAfterACrashBetweenRenames) {
  // write_checkpoint renames dir -> dir.old before dir.tmp -> dir; a crash in between leaves dir.old.
  TempDir tmp("ckptold");
  const fs::path dir = tmp.path / "checkpoint";
  Ids ids{};
  ParticleStore s = make_store(2, 6, ids);
  turbid::tools::write_checkpoint(dir, s, {{"step", 7}});
  fs::rename(dir, tmp.path / "checkpoint.old");
  Ids tids{};
  ParticleStore t = make_target(2, tids);
  EXPECT_EQ(turbid::tools::read_checkpoint(dir, t)["step"], 7);
  EXPECT_EQ(turbid::tools::read_checkpoint_state(dir)["step"], 7);  // the state alone, from the same old copy
  EXPECT_EQ(std::memcmp(t.raw(tids.position), s.raw(ids.position), s.size() * s.field_bytes(ids.position)), 0);
  // The next write keeps working and cleans up.
  turbid::tools::write_checkpoint(dir, s, {{"step", 8}});
  EXPECT_TRUE(leftovers(tmp.path).empty());
  EXPECT_EQ(turbid::tools::read_checkpoint(dir, t)["step"], 8);
}
