#include "timeopt/io/sim_io.h"

#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>

namespace timeopt {

std::string FeasibilityReportToJson(const FeasibilityReport& report, int indent) {
  nlohmann::ordered_json j;
  j["feasible"] = report.feasible;
  j["tolerance"] = report.tolerance;
  j["message"] = report.message;
  j["max_velocity_ratio"] = report.max_velocity_ratio;
  j["max_velocity_time"] = report.max_velocity_time;
  j["max_acceleration_ratio"] = report.max_acceleration_ratio;
  j["max_acceleration_time"] = report.max_acceleration_time;
  j["max_jerk"] = report.max_jerk;
  j["max_jerk_ratio"] = report.max_jerk_ratio;
  const auto ratio = [&](const char* key, const std::optional<double>& value) {
    if (value) j[key] = *value;
  };
  ratio("max_speed_ratio", report.max_speed_ratio);
  ratio("max_acceleration_norm_ratio", report.max_acceleration_norm_ratio);
  ratio("max_thrust_ratio", report.max_thrust_ratio);
  ratio("min_thrust_ratio", report.min_thrust_ratio);
  ratio("max_tilt_ratio", report.max_tilt_ratio);
  j["clipped_steps"] = report.clipped_steps;
  j["max_position_error"] = report.max_position_error;
  j["max_position_error_time"] = report.max_position_error_time;
  j["final_position_error"] = report.final_position_error;
  j["steps"] = report.steps;
  return j.dump(indent) + "\n";
}

std::string SimStatesToCsv(const std::vector<SimState>& states) {
  std::ostringstream csv;
  csv << std::setprecision(10) << "t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,ex,ey,ez\n";
  for (const SimState& s : states) {
    csv << s.t;
    for (const Eigen::Vector3d* v : {&s.position, &s.velocity, &s.acceleration, &s.jerk, &s.position_error}) {
      csv << "," << v->x() << "," << v->y() << "," << v->z();
    }
    csv << "\n";
  }
  return csv.str();
}

}  // namespace timeopt
