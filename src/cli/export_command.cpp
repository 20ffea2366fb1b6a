// `timeopt export TRAJ.json --format csv|polynomial|px4|rosbag -o OUT [--rate HZ]
//                 [--yaw fixed:RAD|velocity|goal] [--max-yaw-rate RAD_PER_S] [--map MAP]`:
// a trajectory file (from `plan`, `temporal` or `waypoints` --trajectory) into the flight stack's
// formats (docs/formats.md, "Exports").

#include <cmath>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/core/files.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt::cli {
namespace {

struct ExportArgs {
  std::string trajectory;
  std::string format;
  std::string output;
  double rate = kDefaultSampleRateHz;
  std::string yaw = "velocity";
  double max_yaw_rate = YawOptions().max_rate;
  std::string map;
  double voxel_radius = 1.0;
  double max_position_error = PolynomialFitOptions().max_position_error;
  double max_velocity_error = PolynomialFitOptions().max_velocity_error;
  double max_acceleration_error = PolynomialFitOptions().max_acceleration_error;
};

int RunExport(const ExportArgs& args) {
  const Trajectory trajectory = ReadTrajectoryJson(args.trajectory);
  ExportFormat format = ExportFormat::kCsv;
  if (!FromString(args.format, &format))
    throw std::invalid_argument("--format: expected " + EnumChoices(kExportFormats));
  ExportOptions options;
  options.rate_hz = args.rate;
  options.yaw = ParseYawSpec(args.yaw, args.max_yaw_rate);
  options.fit.max_position_error = args.max_position_error;
  options.fit.max_velocity_error = args.max_velocity_error;
  options.fit.max_acceleration_error = args.max_acceleration_error;
  options.voxel_radius = args.voxel_radius;
  std::optional<OccupancyMap> map;
  if (!args.map.empty()) {
    if (format != ExportFormat::kRosbag) {
      throw std::invalid_argument("--map: only the rosbag format draws the map (got --format " + args.format + ")");
    }
    map = OccupancyMap::Load(args.map);
    options.map = &*map;
  }
  WriteExport(trajectory, format, args.output, options);
  return kExitOk;
}

}  // namespace

void RegisterExportCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* sub = app.add_subcommand(
      "export",
      "Export a trajectory file (--trajectory of plan, temporal, waypoints) as CSV, polynomial segments, "
      "PX4 setpoints (NED) or a ROS 1 bag");
  sub->add_option("trajectory", args->trajectory, "Trajectory JSON")->required();
  sub->add_option("--format", args->format,
                  "csv (ENU samples with yaw), polynomial (JSON segments), px4 (NED "
                  "TrajectorySetpoint rows), rosbag (nav_msgs/Path, MultiDOFJointTrajectory, markers)")
      ->required()
      ->check(CLI::IsMember(EnumNames(kExportFormats)));
  sub->add_option("-o,--output", args->output, "Output file")->required();
  sub->add_option("--rate", args->rate, "Sample rate of csv, px4 and rosbag, Hz")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--yaw", args->yaw,
                  "Heading: fixed:RAD (ENU, from +x counter-clockwise), velocity (along the horizontal "
                  "velocity) or goal (toward the end)")
      ->capture_default_str();
  sub->add_option("--max-yaw-rate", args->max_yaw_rate, "Largest yaw rate, rad/s")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--map", args->map, "rosbag: draw the occupied voxels of this OctoMap near the path");
  sub->add_option("--voxel-radius", args->voxel_radius, "rosbag with --map: voxels within this distance of the path, m")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--max-position-error", args->max_position_error, "polynomial: largest position error, m")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-velocity-error", args->max_velocity_error, "polynomial: largest velocity error, m/s")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--max-acceleration-error", args->max_acceleration_error,
                  "polynomial: largest acceleration error, m/s^2")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->callback([args, &run] { run = [args] { return RunExport(*args); }; });
}

}  // namespace timeopt::cli
