// ParaView output of the particle store: one VTK XML PolyData file per frame
// (particles_NNNN.vtp, binary appended, zlib) plus the particles.pvd collection that gives each
// frame its time. What is written comes from the field registry (FieldDesc::write_vtk), not from
// a hand-kept list. Every file is written atomically (temp file in the same directory + rename).
// VTK headers stay inside vtk_writer.cpp.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "sph/particle_store.hpp"

namespace turbid::tools {

class VtkSeriesWriter {
 public:
  // Creates `dir` if missing. `dimensions` is 2 or 3 and must equal the components of the
  // "position" field. A new writer starts a new series: frame 0 and a fresh particles.pvd.
  VtkSeriesWriter(std::filesystem::path dir, int dimensions);

  // Writes the next frame: points from "position" (z = 0 in 2D), one vertex cell per particle,
  // a point-data array per field with write_vtk set (other than position), named as the field;
  // fields with `dimensions` components become 3-component vectors (z = 0 in 2D). Field data:
  // "TIME" and "TimeValue" (double, the time in s; VisIt and VTK's XML readers read one or the
  // other) and "units" (strings "name [unit]", position first). Then rewrites particles.pvd.
  // Throws std::runtime_error (naming the file) if VTK cannot write, std::invalid_argument if the
  // store has no suitable "position" field.
  void write(const sph::ParticleStore& store, double time);

  // Continues an existing series after a restart from a checkpoint taken at `time`: reads
  // particles.pvd in the directory (if any), keeps the frames with timestep <= time, and numbers
  // the next frame after them (later frames are overwritten as the run reaches them again).
  // Rewrites particles.pvd with the kept frames. Returns how many frames were kept.
  int resume_after(double time);

  // zlib level 1 (fastest) .. 9 (smallest); VTK's default is 5.
  void set_compression_level(int level) { compression_level_ = level; }

  std::filesystem::path last_file() const;  // empty before the first frame
  int frames() const { return int(frames_.size()); }
  const std::filesystem::path& directory() const { return dir_; }
  std::filesystem::path collection_file() const { return dir_ / "particles.pvd"; }
  static std::string frame_name(int index);  // "particles_0007.vtp"

 private:
  struct Frame {
    double time;
    std::string file;
  };
  void write_collection() const;

  std::filesystem::path dir_;
  int dimensions_;
  int compression_level_ = 5;
  std::vector<Frame> frames_;
};

}  // namespace turbid::tools
