#pragma once

// The paper's Fig. 3b as a PNG: speed, per-axis velocity and per-axis acceleration against time
// with the limits drawn as dashed lines.

#include <string>

#include "timeopt/core/vehicle_limits.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

// Samples the trajectory at `samples` evenly spaced times (>= 2) and writes the plot.
void WriteProfilePlotPng(const Trajectory& trajectory, const VehicleLimits& limits, const std::string& path,
                         int samples = 2000);

}  // namespace timeopt
