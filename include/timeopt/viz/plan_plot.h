#pragma once

// A picture of a plan like the paper's Fig. 9: a horizontal slice of the ESDF (obstacles black,
// free space shaded by distance) with the trajectory drawn on top, coloured by speed, start and
// goal marked, and a speed colour bar. Written as PNG with cairo.

#include <limits>
#include <string>

#include "timeopt/map/esdf.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

struct PlanImageOptions {
  // Height of the map slice, metres; NaN (default): the mean height of the trajectory.
  double slice_height = std::numeric_limits<double>::quiet_NaN();
  int pixels_per_voxel = 4;       // image pixels per voxel edge (lowered for wide maps)
  int max_image_size = 1600;      // largest width or height of the map part, pixels
  double sample_rate_hz = 100.0;  // trajectory samples drawn per second of flight (at most 1e5 in all)
  // The speed at the red end of the colour scale, m/s; NaN (default): the trajectory's own top
  // speed. Set it to compare pictures of several trajectories on one scale.
  double speed_scale = std::numeric_limits<double>::quiet_NaN();
  // Put before the caption (empty: nothing), e.g. which trajectory this is.
  std::string title;
};

// Throws std::invalid_argument for a slice height outside the ESDF's box or bad options,
// timeopt::FileError when the file cannot be written.
void WritePlanPng(const Esdf& esdf, const Trajectory& trajectory, const std::string& path,
                  const PlanImageOptions& options = PlanImageOptions());

}  // namespace timeopt
