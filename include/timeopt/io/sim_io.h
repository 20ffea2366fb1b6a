#pragma once

// The simulator's report as JSON and its recorded states as CSV.

#include <string>
#include <vector>

#include "timeopt/sim/quadrotor_sim.h"

namespace timeopt {

// {"feasible", "message", "max_velocity_ratio", "max_velocity_time", "max_acceleration_ratio",
//  "max_acceleration_time", "max_jerk", "max_jerk_ratio", "clipped_steps", "max_position_error",
//  "max_position_error_time", "final_position_error", "steps"} (the states are not included).
std::string FeasibilityReportToJson(const FeasibilityReport& report, int indent = 2);

// Header t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,ex,ey,ez (e: position error) then one row per state,
// 10 significant digits.
std::string SimStatesToCsv(const std::vector<SimState>& states);

}  // namespace timeopt
