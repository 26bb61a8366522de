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
    if (st.motion != StructureSpec::Motion::fixed) {
      const std::vector<std::string> axes = two_d ? std::vector<std::string>{"x", "y"}
                                                  : std::vector<std::string>{"x", "y", "z"};
      for (const auto& a : axes) cols.push_back(p + a + " [m]");
      cols.push_back(p + "qw [-]");
      if (!two_d) {
        cols.push_back(p + "qx [-]");
        cols.push_back(p + "qy [-]");
      }
      cols.push_back(p + "qz [-]");
      for (const auto& a : axes) cols.push_back(p + "v" + a + " [m/s]");
      if (!two_d) {
        cols.push_back(p + "wx [rad/s]");
        cols.push_back(p + "wy [rad/s]");
      }
      cols.push_back(p + "wz [rad/s]");
      for (const auto& a : axes) cols.push_back(p + "contact_F" + a + f_unit);
    }
  }
  return cols;
}

std::vector<double> force_row(const Scene& scene, const std::vector<sph::BodyLoad>& loads,
                              const std::vector<BodyKinematics>& kinematics) {
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
    if (st.motion != StructureSpec::Motion::fixed) {
      if (kinematics.size() != loads.size())
        throw std::logic_error("force_row: one body state per structure expected for moving structures");
      const BodyKinematics& b = kinematics[k];
      const int n = two_d ? 2 : 3;
      for (int a = 0; a < n; ++a) row.push_back(b.position[std::size_t(a)]);
      row.push_back(b.orientation[0]);
      if (!two_d) {
        row.push_back(b.orientation[1]);
        row.push_back(b.orientation[2]);
      }
      row.push_back(b.orientation[3]);
      for (int a = 0; a < n; ++a) row.push_back(b.velocity[std::size_t(a)]);
      if (!two_d) {
        row.push_back(b.angular_velocity[0]);
        row.push_back(b.angular_velocity[1]);
      }
      row.push_back(b.angular_velocity[2]);
      for (int a = 0; a < n; ++a) row.push_back(b.contact_force[std::size_t(a)]);
    }
  }
  return row;
}

}  // namespace turbid::fsi
