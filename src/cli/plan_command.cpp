// `timeopt plan [--map MAP] [--start x,y,z] [--goal x,y,z] [--max-velocity V]
//               [--max-acceleration A] [--max-jerk J] [--robot-radius R] [--config FILE.json] [--output TRAJ.csv]
//               [--plot PLOT.png] [--unknown free|occupied]`
// Front-end search, spatial optimization and temporal stage on an OctoMap file; prints a summary
// JSON on stdout. Without --map it plans on the shipped default map (kDefault* below) and writes
// results/plan.csv and results/plan.png.
//
// --config FILE.json: planner options (the format is in timeopt/io/planner_io.h; flags win).

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "timeopt/core/errors.h"
#include "timeopt/core/files.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/io/planner_io.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/viz/plan_page.h"
#include "timeopt/viz/plan_plot.h"
#include "timeopt/planner/planner.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt::cli {
namespace {

// The most rows `plan --output` writes (about 150 MB of CSV).
constexpr double kMaxPlanSamples = 1e6;

// The README's main job: across the shipped 20 x 20 m forest (maps/README.md), corner to corner.
constexpr const char* kDefaultMap = "maps/forest_20x20.bt";
constexpr const char* kDefaultStart = "1,1,1.5";
constexpr const char* kDefaultGoal = "19,19,1.5";
constexpr const char* kDefaultOutput = "results/plan.csv";
constexpr const char* kDefaultPlot = "results/plan.png";
constexpr const char* kDefaultHtml = "results/plan.html";

struct PlanArgs {
  std::string map, start, goal, config, output, plot, trajectory, html;
  std::string start_velocity, start_acceleration;  // x,y,z: a start in motion (re-planning)
  bool print_config = false;
  bool verbose = false, quiet = false;
  std::string unknown = ToString(UnknownSpace::kFree);
  std::optional<double> max_velocity, max_acceleration, max_jerk, robot_radius;
  double region_margin = kDefaultRegionMargin;  // metres around start and goal; see --region-margin
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();
  bool whole_map = false;
  QuadrotorLimitArgs quadrotor;  // in addition to the per-axis limits the planner needs
};

Eigen::Vector3d ParsePoint(const std::string& text, const std::string& name) {
  std::string s = text;
  for (char& c : s) {
    if (c == ',') c = ' ';
  }
  std::istringstream in(s);
  Eigen::Vector3d p;
  std::string rest;
  if (!(in >> p.x() >> p.y() >> p.z()) || (in >> rest) || !p.allFinite()) {
    throw std::invalid_argument(name + ": expected x,y,z (three finite numbers), got '" + text + "'");
  }
  return p;
}

using Json = nlohmann::ordered_json;

// The shipped default map, looked for in order: under the working directory (the source tree as
// it), in the installation next to this executable (<prefix>/bin/timeopt reads
// <prefix>/share/timeopt/maps/), and in the source tree this binary was built from (running it
// from the build folder). A FileError names every place tried.
std::string FindDefaultMap() {
  namespace fs = std::filesystem;
  std::vector<fs::path> tried = {fs::path(kDefaultMap)};
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  if (!error) tried.push_back(exe.parent_path().parent_path() / TIMEOPT_INSTALL_DATA_DIR / kDefaultMap);
  tried.push_back(fs::path(TIMEOPT_SOURCE_DATA_DIR) / kDefaultMap);
  std::string where;
  for (const fs::path& path : tried) {
    if (fs::is_regular_file(path, error)) return path.lexically_normal().string();
    where += (where.empty() ? "" : ", ") + path.lexically_normal().string();
  }
  throw FileError("the shipped default map was not found (looked in " + where +
                  "); give one with --map, --start and --goal");
}

// The planner's options: the library's defaults, then --config, then the flags; validated.
PlannerOptions OptionsFrom(const PlanArgs& args) {
  PlannerOptions options;
  if (!args.config.empty()) options = ReadPlannerConfigJson(args.config, options);
  if (args.max_velocity) options.limits.max_velocity.setConstant(*args.max_velocity);
  if (args.max_acceleration) options.limits.max_acceleration.setConstant(*args.max_acceleration);
  if (args.max_jerk) {
    if (*args.max_jerk > 0.0)
      options.limits.max_jerk = Eigen::Vector3d::Constant(*args.max_jerk);
    else
      options.limits.max_jerk.reset();
  }
  ApplyQuadrotorLimits(args.quadrotor, &options.limits);
  if (!args.start_velocity.empty()) options.start_velocity = ParsePoint(args.start_velocity, "--start-velocity");
  if (!args.start_acceleration.empty()) {
    options.start_acceleration = ParsePoint(args.start_acceleration, "--start-acceleration");
  }
  if (args.robot_radius) options.robot_radius = *args.robot_radius;
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("options: " + error);
  return options;
}

// The 3D page's summary lines from the plan's summary JSON.
std::vector<std::pair<std::string, std::string>> PageSummary(const Json& summary, const Trajectory& trajectory) {
  std::vector<std::pair<std::string, std::string>> lines;
  const auto text = [](const Json& value) {
    if (value.is_null()) return std::string("none");
    if (value.is_string()) return value.get<std::string>();
    std::ostringstream out;
    if (value.is_array()) {
      bool same = true;
      for (const Json& v : value) same = same && v == value[0];
      if (same && !value.empty()) {
        out << value[0].get<double>();
        return out.str();
      }
    }
    out << value.dump();
    return out.str();
  };
  std::ostringstream T;
  T << std::setprecision(6) << trajectory.duration() << " s";
  lines.emplace_back("T", T.str());
  lines.emplace_back("status", text(summary["status"]));
  const Json& limits = summary["limits"];
  lines.emplace_back("limits", "v " + text(limits["max_velocity"]) + " m/s, a " + text(limits["max_acceleration"]) +
                                   " m/s^2, j " + text(limits["max_jerk"]) + " m/s^3 (per axis)");
  lines.emplace_back("mode", limits["max_jerk"].is_null() ? text(summary["constraint_mode"]) + " rows, no jerk limit"
                                                          : std::string("jerk-limited"));
  if (summary.contains("flight") && summary["flight"].contains("feasible")) {
    const Json& f = summary["flight"];
    std::ostringstream flight;
    flight << (f["feasible"].get<bool>() ? "the limits hold" : "a limit is exceeded") << " (max |v|/vmax "
           << std::setprecision(4) << f["max_velocity_ratio"].get<double>() << ", max |a|/amax "
           << f["max_acceleration_ratio"].get<double>() << ")";
    lines.emplace_back("flight", flight.str());
  }
  lines.emplace_back("map", text(summary["map"]));
  return lines;
}

int RunPlan(PlanArgs args) {
  if (args.print_config) {
    // The complete configuration these flags give, as --config reads it; nothing is planned.
    std::cout << PlannerConfigToJson(OptionsFrom(args));
    return kExitOk;
  }
  const bool defaults = args.map.empty();
  if (defaults) {
    args.map = FindDefaultMap();
    if (args.start.empty()) args.start = kDefaultStart;
    if (args.goal.empty()) args.goal = kDefaultGoal;
    if (args.output.empty()) args.output = kDefaultOutput;
    if (args.plot.empty()) args.plot = kDefaultPlot;
    if (args.html.empty()) args.html = kDefaultHtml;
  }
  if (args.start.empty() || args.goal.empty()) {
    throw std::invalid_argument("--start and --goal are required with --map");
  }
  const Eigen::Vector3d start = ParsePoint(args.start, "--start");
  const Eigen::Vector3d goal = ParsePoint(args.goal, "--goal");
  PlannerOptions options = OptionsFrom(args);
  // --verbose: one line per stage on stderr as it ends.
  const auto progress = [&args](const std::string& stage, double seconds, const std::string& outcome) {
    if (!args.verbose) return;
    std::cerr << "timeopt plan: " << stage << ": " << std::fixed << std::setprecision(1) << seconds * 1e3 << " ms"
              << std::defaultfloat << std::setprecision(6) << (outcome.empty() ? "" : ", " + outcome) << "\n";
  };
  options.on_stage = progress;

  using Clock = std::chrono::steady_clock;
  UnknownSpace unknown = UnknownSpace::kFree;
  if (!FromString(args.unknown, &unknown)) {
    throw std::invalid_argument("--unknown: expected " + EnumChoices(kUnknownSpaces));
  }
  auto t = Clock::now();
  const OccupancyMap map = OccupancyMap::Load(args.map, unknown);
  progress("map", std::chrono::duration<double, std::milli>(Clock::now() - t).count(), args.map);
  t = Clock::now();
  const Eigen::AlignedBox3d region = PlanRegion(start, goal, args.region_margin);
  const int64_t budget = args.max_memory_mib * 1024 * 1024;
  const Esdf esdf =
      args.whole_map ? Esdf::FromMap(map, std::nullopt, budget) : Esdf::FromMapRegion(map, region, budget);
  const double esdf_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  progress("esdf", esdf_ms, std::to_string(esdf.box().num_voxels()) + " voxels");
  Planner planner(esdf);
  const PlanResult plan = planner.Plan(start, goal, options);

  // The plan's own fields (io), then what this command adds: the inputs, the ESDF time, the flight.
  const Json result = Json::parse(PlanResultToJson(plan));
  Json summary;
  for (const char* key : {"status", "message"}) summary[key] = result.at(key);
  summary["map"] = args.map;
  summary["start"] = {start.x(), start.y(), start.z()};
  summary["goal"] = {goal.x(), goal.y(), goal.z()};
  summary["robot_radius"] = options.robot_radius;
  summary["formulation"] = ToString(options.spatial.formulation);
  summary["constraint_mode"] = ToString(options.constraint_mode);
  const auto per_axis = [](const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); };
  summary["limits"] = {{"max_velocity", per_axis(options.limits.max_velocity)},
                       {"max_acceleration", per_axis(options.limits.max_acceleration)},
                       {"max_jerk", options.limits.max_jerk ? per_axis(*options.limits.max_jerk) : Json(nullptr)}};
  const auto norm_limit = [&](const char* key, const std::optional<double>& value) {
    if (value) summary["limits"][key] = *value;
  };
  norm_limit("max_speed", options.limits.max_speed);
  norm_limit("max_acceleration_norm", options.limits.max_acceleration_norm);
  norm_limit("max_thrust", options.limits.max_thrust);
  norm_limit("min_thrust", options.limits.min_thrust);
  norm_limit("max_tilt", options.limits.max_tilt);
  for (const auto& item : result.items()) summary[item.key()] = item.value();
  summary["time_ms"]["esdf"] = esdf_ms;
  const Eigen::AlignedBox3d field_box = esdf.box().Metric(esdf.resolution());
  summary["esdf_box"] = {{"min", {field_box.min().x(), field_box.min().y(), field_box.min().z()}},
                         {"max", {field_box.max().x(), field_box.max().y(), field_box.max().z()}},
                         {"voxels", esdf.box().num_voxels()}};
  const bool ok = plan.is_success();
  if (ok) {
    const Trajectory trajectory(plan.curve, plan.temporal.profile);
    // The trajectory flown by the default jerk-input quadrotor from the start state (a hover unless
    // --start-velocity / --start-acceleration; see `timeopt simulate`).
    t = Clock::now();
    try {
      const FeasibilityReport flight =
          SummaryQuadrotor(options.limits)
              .Fly(trajectory, options.limits, options.start_velocity, options.start_acceleration);
      summary["flight"] = FlightSummary(flight, options.limits);
      progress("flight", std::chrono::duration<double, std::milli>(Clock::now() - t).count(),
               flight.feasible ? "the limits hold" : flight.message);
    } catch (const std::invalid_argument& e) {
      summary["flight"] = {{"error", e.what()}};
    }
    if (!args.output.empty()) {
      EnsureParentDirectory(args.output);
      // 100 Hz, or fewer where that would pass kMaxPlanSamples rows (a flight of 2e7 s at limits
      // of 1e-6 asked for 2e9): the rows carry their times, and output_rate_hz says which.
      const double rate = std::min(kDefaultSampleRateHz, kMaxPlanSamples / std::max(trajectory.duration(), 1e-300));
      WriteTextFile(args.output, SamplesToCsv(trajectory.Sample(rate)));
      summary["output"] = args.output;
      summary["output_rate_hz"] = rate;
    }
    if (!args.trajectory.empty()) {
      EnsureParentDirectory(args.trajectory);
      WriteTrajectoryJson(trajectory, args.trajectory);
      summary["trajectory"] = args.trajectory;
    }
    if (!args.plot.empty()) {
      EnsureParentDirectory(args.plot);
      WritePlanPng(esdf, trajectory, args.plot);
      summary["plot"] = args.plot;
    }
    if (!args.html.empty()) {
      EnsureParentDirectory(args.html);
      PlanPageOptions page;
      page.title = "timeopt plan: " + args.start + " -> " + args.goal;
      page.summary = PageSummary(summary, trajectory);
      WritePlanPageHtml(trajectory, options.limits, &map, args.html, page);
      summary["html"] = args.html;
    }
  }
  if (!args.quiet) std::cout << summary.dump(2) << "\n";
  if (!ok) std::cerr << "timeopt: plan: " << ToString(plan.status) << ": " << plan.message << "\n";
  return ExitCodeFor(plan.status);
}

}  // namespace

void RegisterPlanCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<PlanArgs>();
  CLI::App* sub =
      app.add_subcommand("plan",
                         "Plan a minimum-time trajectory on a map: A* front-end, Ceres spatial stage, SOCP temporal "
                         "stage. Without --map: the shipped default map (" +
                             std::string(kDefaultMap) + ", " + kDefaultStart + " -> " + kDefaultGoal +
                             "), writing results/plan.csv and results/plan.png");
  sub->add_option("--map", args->map, "OctoMap file (.bt/.ot)");
  sub->add_option("--start", args->start, "Start position x,y,z (metres)");
  sub->add_option("--goal", args->goal, "Goal position x,y,z (metres)");
  // The defaults shown are the library's (PlannerOptions), never restated here.
  const PlannerOptions defaults;
  const auto shown = [](double value) {
    std::ostringstream text;
    text << value;
    return " (default " + text.str() + ")";
  };
  sub->add_option("--max-velocity", args->max_velocity,
                  "Per-axis velocity limit, m/s" + shown(defaults.limits.max_velocity.x()))
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-acceleration", args->max_acceleration,
                  "Per-axis acceleration limit, m/s^2" + shown(defaults.limits.max_acceleration.x()))
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-jerk", args->max_jerk,
                  "Per-axis jerk limit, m/s^3 (0: none, the paper's profile)" +
                      (defaults.limits.max_jerk ? shown(defaults.limits.max_jerk->x()) : std::string()))
      ->check(CLI::NonNegativeNumber);
  // The quadrotor's limits apply with the per-axis ones (the front end and the spatial stage size
  // the path by those).
  AddQuadrotorLimitOptions(sub, &args->quadrotor);
  sub->add_option("--start-velocity", args->start_velocity,
                  "The vehicle's velocity at the start, x,y,z m/s (re-planning in flight; default: at rest)");
  sub->add_option("--start-acceleration", args->start_acceleration,
                  "The vehicle's acceleration at the start, x,y,z m/s^2 (default: 0)");
  sub->add_option("--robot-radius", args->robot_radius, "Robot radius, metres" + shown(defaults.robot_radius))
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--unknown", args->unknown, "Unobserved voxels inside the map's box: free (optimistic) or occupied")
      ->check(CLI::IsMember(EnumNames(kUnknownSpaces)))
      ->capture_default_str();
  sub->add_option("--region-margin", args->region_margin,
                  "The distance field covers the box of start and goal grown by this much, metres "
                  "(clipped to the map; its cut faces count as occupied)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--whole-map", args->whole_map, "The distance field covers the whole map (no region of interest)");
  AddMemoryBudgetOption(sub, &args->max_memory_mib);
  sub->add_flag("-v,--verbose", args->verbose,
                "One line per stage on stderr as it ends (map, ESDF, search, spatial, check, temporal)");
  sub->add_flag("-q,--quiet", args->quiet,
                "Print no summary (the files are still written; the exit code says how it went)");
  sub->add_flag("--print-config", args->print_config,
                "Print the planner configuration that the defaults, --config and the flags give, as JSON for "
                "--config, and plan nothing (the quadrotor limits and the start state are flags only, not in it)");
  sub->add_option("--config", args->config,
                  "Planner options JSON (keys: timeopt/io/planner_io.h; flags override them)");
  sub->add_option("-o,--output", args->output, "Trajectory samples CSV at 100 Hz");
  sub->add_option("--plot", args->plot, "PNG: trajectory over a map slice, coloured by speed");
  sub->add_option("--trajectory", args->trajectory, kTrajectoryOptionHelp);
  sub->add_option("--html", args->html,
                  "3D page: the plan over the map's voxels, with plots and playback (one HTML file)");
  sub->callback([args, &run] { run = [args] { return RunPlan(*args); }; });
}

}  // namespace timeopt::cli
