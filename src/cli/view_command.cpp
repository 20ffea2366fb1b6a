// `timeopt view TRAJ.json [--map MAP] -o FILE.html [--max-velocity V] [--max-acceleration A]
//               [--max-jerk J]`: a trajectory file as the 3D page (docs/formats.md, "The 3D page").

#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/viz/plan_page.h"

namespace timeopt::cli {
namespace {

struct ViewArgs {
  std::string trajectory, map, output;
  std::optional<double> max_velocity, max_acceleration, max_jerk;
  double voxel_radius = PlanPageOptions().voxel_radius;
};

int RunView(const ViewArgs& args) {
  const Trajectory trajectory = ReadTrajectoryJson(args.trajectory);
  // The trajectory file holds no limits: the plots show those given here.
  constexpr double kNone = std::numeric_limits<double>::infinity();
  VehicleLimits limits;
  limits.max_velocity.setConstant(args.max_velocity.value_or(kNone));
  limits.max_acceleration.setConstant(args.max_acceleration.value_or(kNone));
  if (args.max_jerk) limits.max_jerk = Eigen::Vector3d::Constant(*args.max_jerk);
  std::optional<OccupancyMap> map;
  if (!args.map.empty()) map = OccupancyMap::Load(args.map);
  PlanPageOptions page;
  page.title = "timeopt: " + args.trajectory;
  page.voxel_radius = args.voxel_radius;
  std::ostringstream T;
  T << trajectory.duration() << " s";
  page.summary = {{"T", T.str()},
                  {"pieces", std::to_string(trajectory.curve().num_pieces())},
                  {"profile", trajectory.profile().jerk_limited() ? "jerk-limited" : "without a jerk limit"}};
  if (!args.map.empty()) page.summary.emplace_back("map", args.map);
  WritePlanPageHtml(trajectory, limits, map ? &*map : nullptr, args.output, page);
  return kExitOk;
}

}  // namespace

void RegisterViewCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* sub =
      app.add_subcommand("view", "A trajectory file as one self-contained 3D HTML page (three.js, Chart.js)");
  sub->add_option("trajectory", args->trajectory, "Trajectory JSON (--trajectory of plan, temporal, waypoints)")
      ->required();
  sub->add_option("-o,--output", args->output, "HTML file")->required();
  sub->add_option("--map", args->map, "OctoMap file: draw its occupied voxels near the path");
  sub->add_option("--voxel-radius", args->voxel_radius, "With --map: voxels within this distance of the path, m")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--max-velocity", args->max_velocity, "Per-axis velocity limit to draw, m/s")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-acceleration", args->max_acceleration, "Per-axis acceleration limit to draw, m/s^2")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-jerk", args->max_jerk, "Per-axis jerk limit to draw, m/s^3")->check(CLI::PositiveNumber);
  sub->callback([args, &run] { run = [args] { return RunView(*args); }; });
}

}  // namespace timeopt::cli
