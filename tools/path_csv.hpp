// Samples of a prescribed path (motion: prescribed, fsi/prescribed_path.hpp) from a CSV file.
//
// The first line that is not blank and not a '#' comment is the header: comma-separated columns
// `name [unit]` in any order, `time [s]` required, then any of x, y (, z) [m] (the displacement
// from the structure's scene position) and (3D: rx, ry,) rz [deg] or [rad] (the rotation about the
// reference point: about x, then y, then z); a column left out is 0. Every following line that is
// not blank or a comment is one sample, one number per column; times must increase strictly.
// Errors are SceneError "CSV:LINE:COL: error: ..." naming the CSV file.
#pragma once
#include <string>

#include "fsi/scene.hpp"

namespace turbid::tools {

// Fills spec.times, spec.displacement and spec.angles (radians) from the file at `path`
// (`shown` names it in messages). dims 2 refuses z, rx and ry.
void read_path_csv(const std::string& path, const std::string& shown, int dims, fsi::PrescribedPathSpec& spec);

}  // namespace turbid::tools
