#pragma once

// A plan in 3D as one self-contained HTML page: three.js and Chart.js (Debian's libjs-three and
// libjs-chart.js, read from /usr/share/javascript when the page is written) and the data are
// inlined, so the file opens in a browser with no network and can be attached or archived.
//
// It shows the occupied voxels near the path (instanced boxes), the trajectory coloured by speed
// with a colour bar in m/s, start and goal, the vehicle moving along t (play/pause, a time slider),
// plots of speed, per-axis acceleration and jerk against t with the limits and a cursor at the
// slider's time, the caller's summary lines, and an orbit camera (drag to turn, wheel to zoom,
// right-drag to pan) aimed at the path. z is up.
//
// Test hooks: once drawn, <body> carries data-ready="true" and data-samples="N" (the number of
// trajectory samples in the page).

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "timeopt/core/vehicle_limits.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

struct PlanPageOptions {
  std::string title = "timeopt plan";
  // Lines of the summary panel, (label, value), shown in order (e.g. T, limits, mode, flight).
  std::vector<std::pair<std::string, std::string>> summary;
  double sample_rate_hz = 50.0;  // trajectory samples per second in the page (fewer past max_samples)
  size_t max_samples = 20000;
  double voxel_radius = 2.0;  // m: occupied voxels within this distance of the path are drawn
  // At most this many voxels are drawn; more are thinned evenly (the summary says so).
  size_t max_voxels = 150000;
};

// The page itself. map may be null (no voxels). Throws std::invalid_argument for bad options and
// timeopt::FileError when Debian's three.js or Chart.js files are missing (naming the package).
std::string PlanPageHtml(const Trajectory& trajectory, const VehicleLimits& limits, const OccupancyMap* map,
                         const PlanPageOptions& options = {});
void WritePlanPageHtml(const Trajectory& trajectory, const VehicleLimits& limits, const OccupancyMap* map,
                       const std::string& path, const PlanPageOptions& options = {});

// The page is at most this large (the caps above keep it there; a larger one is a logic error,
// thrown as std::logic_error).
inline constexpr size_t kMaxPlanPageBytes = size_t{15} << 20;

}  // namespace timeopt
