// VTK XML PolyData series writer; see vtk_writer.hpp.
#include "tools/vtk_writer.hpp"

#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkFloatArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkTypeInt32Array.h>
#include <vtkTypeInt64Array.h>
#include <vtkTypeUInt32Array.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLPolyDataWriter.h>

#include <charconv>
#include <cstdio>
#include <cstdint>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "tools/atomic_file.hpp"

namespace turbid::tools {
namespace fs = std::filesystem;
using sph::ScalarType;

namespace {

// Shortest text that reads back as the same double.
std::string format_double(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// A VTK array with `out_comp` components holding the field; when the component counts agree
// the array borrows the store's memory (no copy; the store outlives the synchronous write),
// otherwise the extra components (z in 2D) are zero.
template <class ArrayT, class T>
vtkSmartPointer<vtkDataArray> make_array(const void* raw, std::size_t n, int in_comp, int out_comp) {
  auto a = vtkSmartPointer<ArrayT>::New();
  a->SetNumberOfComponents(out_comp);
  const T* src = static_cast<const T*>(raw);
  if (in_comp == out_comp) {
    // save = 1: VTK never frees or writes the borrowed memory.
    a->SetArray(const_cast<T*>(src), vtkIdType(n) * out_comp, 1);
  } else {
    a->SetNumberOfTuples(vtkIdType(n));
    T* dst = a->GetPointer(0);
    for (std::size_t i = 0; i < n; ++i) {
      for (int c = 0; c < out_comp; ++c)
        dst[i * std::size_t(out_comp) + std::size_t(c)] = c < in_comp ? src[i * std::size_t(in_comp) + std::size_t(c)] : T(0);
    }
  }
  return a;
}

vtkSmartPointer<vtkDataArray> field_array(const sph::ParticleStore& store, sph::FieldId id, int out_comp) {
  const auto& d = store.desc(id);
  const void* raw = store.raw(id);
  const std::size_t n = store.size();
  switch (d.type) {
    case ScalarType::f32: return make_array<vtkFloatArray, float>(raw, n, d.components, out_comp);
    case ScalarType::f64: return make_array<vtkDoubleArray, double>(raw, n, d.components, out_comp);
    case ScalarType::i32: return make_array<vtkTypeInt32Array, std::int32_t>(raw, n, d.components, out_comp);
    case ScalarType::u32: return make_array<vtkTypeUInt32Array, std::uint32_t>(raw, n, d.components, out_comp);
    case ScalarType::u8: return make_array<vtkUnsignedCharArray, unsigned char>(raw, n, d.components, out_comp);
  }
  throw std::logic_error("unknown scalar type of field '" + d.name + "'");
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// Value of attribute `key="..."` in one line of our own .pvd, or empty.
std::string attribute(const std::string& line, const std::string& key) {
  const std::string pat = " " + key + "=\"";
  const auto b = line.find(pat);
  if (b == std::string::npos) return {};
  const auto s = b + pat.size();
  const auto e = line.find('"', s);
  return e == std::string::npos ? std::string{} : line.substr(s, e - s);
}

}  // namespace

VtkSeriesWriter::VtkSeriesWriter(fs::path dir, int dimensions) : dir_(std::move(dir)), dimensions_(dimensions) {
  if (dimensions != 2 && dimensions != 3)
    throw std::invalid_argument("VtkSeriesWriter: dimensions must be 2 or 3, got " + std::to_string(dimensions));
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw std::runtime_error("cannot create output directory '" + dir_.string() + "': " + ec.message());
}

std::string VtkSeriesWriter::frame_name(int index) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "particles_%04d.vtp", index);
  return buf;
}

fs::path VtkSeriesWriter::last_file() const {
  return frames_.empty() ? fs::path{} : dir_ / frames_.back().file;
}

void VtkSeriesWriter::write(const sph::ParticleStore& store, double time) {
  const auto pos_id = store.find("position");
  if (!pos_id) throw std::invalid_argument("VtkSeriesWriter: the store has no field named 'position'");
  const auto& pos = store.desc(*pos_id);
  if (pos.components != dimensions_ || (pos.type != ScalarType::f32 && pos.type != ScalarType::f64))
    throw std::invalid_argument("VtkSeriesWriter: field 'position' must be f32 or f64 with " +
                                std::to_string(dimensions_) + " components, has " + scalar_name(pos.type) +
                                " x " + std::to_string(pos.components));
  const std::size_t n = store.size();

  vtkNew<vtkPolyData> poly;
  vtkNew<vtkPoints> points;
  points->SetData(field_array(store, *pos_id, 3));
  poly->SetPoints(points);

  // One vertex per particle, so ParaView renders the points without a Glyph filter.
  vtkNew<vtkCellArray> verts;
  vtkNew<vtkTypeInt64Array> offsets;
  vtkNew<vtkTypeInt64Array> connectivity;
  offsets->SetNumberOfValues(vtkIdType(n) + 1);
  connectivity->SetNumberOfValues(vtkIdType(n));
  for (std::size_t i = 0; i < n; ++i) {
    offsets->SetValue(vtkIdType(i), vtkTypeInt64(i));
    connectivity->SetValue(vtkIdType(i), vtkTypeInt64(i));
  }
  offsets->SetValue(vtkIdType(n), vtkTypeInt64(n));
  verts->SetData(offsets, connectivity);
  poly->SetVerts(verts);

  vtkNew<vtkStringArray> units;
  units->SetName("units");
  units->InsertNextValue(pos.name + " [" + pos.unit + "]");
  for (int id = 0; id < store.field_count(); ++id) {
    if (id == *pos_id) continue;
    const auto& d = store.desc(id);
    if (!d.write_vtk) continue;
    const int out_comp = d.components == dimensions_ ? 3 : d.components;
    auto a = field_array(store, id, out_comp);
    a->SetName(d.name.c_str());
    poly->GetPointData()->AddArray(a);
    units->InsertNextValue(d.name + " [" + d.unit + "]");
  }
  vtkFieldData* fd = poly->GetFieldData();
  for (const char* name : {"TIME", "TimeValue"}) {
    vtkNew<vtkDoubleArray> t;
    t->SetName(name);
    t->SetNumberOfTuples(1);
    t->SetValue(0, time);
    fd->AddArray(t);
  }
  fd->AddArray(units);

  const int index = frames();
  const std::string name = frame_name(index);
  const fs::path target = dir_ / name;
  const fs::path temp = temp_path_for(target);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetFileName(temp.c_str());
  writer->SetInputData(poly);
  writer->SetDataModeToAppended();
  writer->EncodeAppendedDataOff();  // raw bytes after the XML header, not base64
  writer->SetCompressorTypeToZLib();
  writer->SetCompressionLevel(compression_level_);
  writer->SetHeaderTypeToUInt64();  // blocks above 4 GiB
  const int ok = writer->Write();
  if (!ok || writer->GetErrorCode() != 0) {
    std::error_code ignore;
    fs::remove(temp, ignore);
    throw std::runtime_error("VTK could not write '" + target.string() + "' (error code " +
                             std::to_string(writer->GetErrorCode()) + ")");
  }
  commit_temp_file(temp, target);

  frames_.push_back({time, name});
  write_collection();
}

void VtkSeriesWriter::write_collection() const {
  std::ostringstream o;
  o << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "  <Collection>\n";
  for (const auto& f : frames_)
    o << "    <DataSet timestep=\"" << format_double(f.time) << "\" group=\"\" part=\"0\" file=\""
      << xml_escape(f.file) << "\"/>\n";
  o << "  </Collection>\n"
    << "</VTKFile>\n";
  write_text_atomic(collection_file(), o.str());
}

int VtkSeriesWriter::resume_after(double time) {
  frames_.clear();
  std::ifstream in(collection_file());
  std::string line;
  while (in && std::getline(in, line)) {
    if (line.find("<DataSet") == std::string::npos) continue;
    const std::string ts = attribute(line, "timestep");
    const std::string file = attribute(line, "file");
    double t = std::numeric_limits<double>::quiet_NaN();
    const auto r = std::from_chars(ts.data(), ts.data() + ts.size(), t);
    if (r.ec != std::errc{} || file.empty())
      throw std::runtime_error("cannot read frame entry in '" + collection_file().string() + "': " + line);
    // Frames are numbered in order: the kept ones are exactly particles_0000 .. particles_(k-1).
    if (!(t <= time) || file != frame_name(frames())) break;
    frames_.push_back({t, file});
  }
  write_collection();
  return frames();
}

}  // namespace turbid::tools
