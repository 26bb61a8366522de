// forces.csv columns; see forces.hpp.
#include "fsi/forces.hpp"

#include <stdexcept>

namespace turbid::fsi {

std::vector<std::string> force_columns(const Scene& scene) {
  const bool two_d = scene.dimensions == 2;
  const std::string f_unit = two_d ? " [N/m]" : " [N]";
  const std::string m_unit = two_d ? " [N m/m]" : " [N m]";
  std::vector<std::string> cols;
  for (const auto& st : scene.structures) {
    const std::string p = st.name + ".";
    cols.push_back(p + "Fx" + f_unit);
    cols.push_back(p + "Fy" + f_unit);
    if (!two_d) {
      cols.push_back(p + "Fz" + f_unit);
      cols.push_back(p + "Mx" + m_unit);
      cols.push_back(p + "My" + m_unit);
    }
    cols.push_back(p + "Mz" + m_unit);
    if (st.has_coefficients) {
      cols.push_back(p + "drag" + f_unit);
      cols.push_back(p + "lift" + f_unit);
      cols.push_back(p + "C_D [-]");
      cols.push_back(p + "C_L [-]");
    }
  }
  return cols;
}

std::vector<double> force_row(const Scene& scene, const std::vector<sph::BodyLoad>& loads) {
  if (loads.size() != scene.structures.size())
    throw std::logic_error("force_row: one load per structure expected");
  const bool two_d = scene.dimensions == 2;
  std::vector<double> row;
  for (std::size_t k = 0; k < loads.size(); ++k) {
    const auto& st = scene.structures[k];
    const auto& L = loads[k];
    row.push_back(L.force[0]);
    row.push_back(L.force[1]);
    if (!two_d) {
      row.push_back(L.force[2]);
      row.push_back(L.torque[0]);
      row.push_back(L.torque[1]);
    }
    row.push_back(L.torque[2]);
    if (st.has_coefficients) {
      double drag = 0, lift = 0;
      for (int a = 0; a < 3; ++a) {
        drag += L.force[a] * st.flow_direction[a];
        lift += L.force[a] * st.lift_direction[a];
      }
      const double area = two_d ? st.reference_length : st.reference_area;
      const double q = 0.5 * st.reference_density * st.reference_velocity * st.reference_velocity * area;
      row.push_back(drag);
      row.push_back(lift);
      row.push_back(drag / q);
      row.push_back(lift / q);
    }
  }
  return row;
}

}  // namespace turbid::fsi
