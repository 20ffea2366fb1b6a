#pragma once

// The trajectory file and the exports built from it (all in docs/formats.md).
//
// Trajectory JSON: the curve and the profile, exact (not samples):
//   {"format": "timeopt-trajectory", "version": 1, "frame": "ENU", "duration": T,
//    "curve": {...curve JSON...},
//    "profile": {"cells_per_piece": K, "b": [[...K + 1 per piece...]]}                  (linear cells)
//            or {"cells_per_piece": K, "half_b": [[...2K + 1...]], "shapes": [["rest_start", ...]],
//                "cell_edges": [[...K + 1...]]}                         (jerk-limited; edges optional)}
// Numbers are written so that they read back exactly: a trajectory read back samples to the bit
// what the one written did.
//
// Exports (each from a Trajectory, with a heading from PlanYaw):
// - ExportCsv: t, x, y, z, vx, vy, vz, ax, ay, az, jx, jy, jz, yaw, yaw_rate in ENU;
// - ExportPx4Csv: timestamp_us, x, y, z, vx, vy, vz, ax, ay, az, yaw, yawspeed in NED (x north =
//   ENU y, y east = ENU x, z down = -ENU z; yaw from north, clockwise: pi / 2 - ENU yaw);
// - ExportPolynomialJson: FitPolynomialSegments with each segment's yaw, and the error bounds;
// - RosbagContentJson: what the bag writer (timeopt_rosbag.py) turns into ROS messages.
//
// Errors: std::invalid_argument naming the field; timeopt::FileError for unreadable files.

#include <array>
#include <string>
#include <vector>

#include "timeopt/map/occupancy_map.h"
#include "timeopt/trajectory/polynomial_segments.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/trajectory/yaw.h"

namespace timeopt {

std::string TrajectoryToJson(const Trajectory& trajectory, int indent = 2);
void WriteTrajectoryJson(const Trajectory& trajectory, const std::string& path);
// Throws std::invalid_argument naming the field (`context` prefixes it), also when "duration"
// differs from the profile's own by more than 1e-9 of it (an edited or truncated file).
Trajectory ParseTrajectoryJson(const std::string& json_text, const std::string& context = "trajectory");
Trajectory ReadTrajectoryJson(const std::string& path);

// The sample times of Trajectory::Sample(rate_hz) with their states and the heading at them.
struct HeadedSamples {
  std::vector<TrajectoryState> states;
  YawProfile yaw;
};
HeadedSamples SampleWithYaw(const Trajectory& trajectory, double rate_hz, const YawOptions& yaw);

std::string ExportCsv(const HeadedSamples& samples);
std::string ExportPx4Csv(const HeadedSamples& samples);

// The segments' JSON: {"frame": "ENU", "degree", "duration", "segments": [{"start", "duration",
// "coefficients": [[x0..xn], [y0..yn], [z0..zn]], "exact", "yaw": [yaw0, yaw_rate]}],
// "max_error": {"position", "velocity", "check_spacing"}, "tolerance": {"position", "velocity"},
// "yaw": {"mode", "max_rate"}}. The yaw is PlanYaw on the segments' edges, linear in each.
std::string ExportPolynomialJson(const Trajectory& trajectory, const PolynomialFitOptions& fit, const YawOptions& yaw);

// The bag's content for the writer script: samples, start and goal, and with a map the occupied
// voxels within `voxel_radius` metres of the path (at most kMaxMarkerVoxels; more is
// std::invalid_argument naming the radius).
inline constexpr size_t kMaxMarkerVoxels = 1000000;
std::string RosbagContentJson(const HeadedSamples& samples, const OccupancyMap* map, double voxel_radius);

// The export formats, and one export written to a file with its options (the command line's
// `timeopt export` and Python's timeopt.export).
enum class ExportFormat { kCsv, kPolynomial, kPx4, kRosbag };
inline constexpr std::array<ExportFormat, 4> kExportFormats = {ExportFormat::kCsv, ExportFormat::kPolynomial,
                                                               ExportFormat::kPx4, ExportFormat::kRosbag};
const char* ToString(ExportFormat format);
bool FromString(const std::string& text, ExportFormat* format);

struct ExportOptions {
  double rate_hz = kDefaultSampleRateHz;  // csv, px4, rosbag
  YawOptions yaw;
  PolynomialFitOptions fit;           // polynomial
  const OccupancyMap* map = nullptr;  // rosbag only (std::invalid_argument for another format)
  double voxel_radius = 1.0;          // m, rosbag with a map
};
void WriteExport(const Trajectory& trajectory, ExportFormat format, const std::string& path,
                 const ExportOptions& options);

// Writes `content` (RosbagContentJson) as a ROS 1 bag at bag_path: Debian's /usr/bin/python3 runs
// the writer timeopt_rosbag.py (with python3-rosbag and the message packages), found at
// $TIMEOPT_ROSBAG_WRITER, else in the source tree this library was built from, else installed in
// <prefix>/share/timeopt/. Throws timeopt::FileError when the writer, its interpreter or its
// packages are missing or the bag cannot be written, with the writer's own message.
void WriteRosbag(const std::string& content, const std::string& bag_path);

}  // namespace timeopt
