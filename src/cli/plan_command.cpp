// `timeopt plan [--map MAP] [--start x,y,z] [--goal x,y,z] [--max-velocity V]
//               [--max-acceleration A] [--robot-radius R] [--config FILE.json] [--output TRAJ.csv]
//               [--plot PLOT.png] [--unknown free|occupied]`
// Front-end search, spatial optimization and temporal stage on an OctoMap file; prints a summary
// JSON on stdout. Without --map it plans on the shipped default map (kDefault* below) and writes
// results/plan.csv and results/plan.png.
//
// Config JSON (every key optional, unknown keys rejected; command-line flags win):
//   {"robot_radius": 0.3, "safety_margin": 0.2, "max_segment_length": 1.0, "max_attempts": 3,
//    "limits": {"max_velocity": 2.0 | [vx, vy, vz], "max_acceleration": 2.0 | [..]},
//    "temporal": {"K": 30, "rho": 0.0, "constraint_mode": "certified" | "paper"},
//    "spatial": {"formulation": "spatial" | "time_coupled", "smoothness_weight", "collision_weight",
//                "length_weight", "penalty_decay_length", "collision_samples_per_piece",
//                "max_iterations", "heuristic_speed", "dynamic_weight"},
//    "search": {"heuristic_weight", "clearance_cost_weight", "max_expanded_nodes"}}

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "timeopt/core/errors.h"
#include "timeopt/core/files.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/viz/plan_plot.h"
#include "timeopt/planner/planner.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt::cli {
namespace {

// The README's main job: across the shipped 20 x 20 m forest (maps/README.md), corner to corner.
constexpr const char* kDefaultMap = "maps/forest_20x20.bt";
constexpr const char* kDefaultStart = "1,1,1.5";
constexpr const char* kDefaultGoal = "19,19,1.5";
constexpr const char* kDefaultOutput = "results/plan.csv";
constexpr const char* kDefaultPlot = "results/plan.png";

struct PlanArgs {
  std::string map, start, goal, config, output, plot;
  std::string unknown = "free";
  std::optional<double> max_velocity, max_acceleration, robot_radius;
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

using Json = nlohmann::json;

void CheckKeys(const Json& object, const std::string& context,
               std::initializer_list<const char*> allowed) {
  if (!object.is_object()) throw std::invalid_argument(context + ": expected an object");
  for (const auto& item : object.items()) {
    bool known = false;
    for (const char* key : allowed) known = known || item.key() == key;
    if (!known) throw std::invalid_argument(context + ": unknown key '" + item.key() + "'");
  }
}

double Number(const Json& object, const char* key, const std::string& context, double current) {
  if (!object.contains(key)) return current;
  const Json& v = object.at(key);
  if (!v.is_number()) throw std::invalid_argument(context + "." + key + ": expected a number");
  return v.get<double>();
}

Eigen::Vector3d Limit(const Json& object, const char* key, const std::string& context,
                      const Eigen::Vector3d& current) {
  if (!object.contains(key)) return current;
  const Json& v = object.at(key);
  if (v.is_number()) return Eigen::Vector3d::Constant(v.get<double>());
  if (v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()) {
    return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  }
  throw std::invalid_argument(context + "." + key + ": expected a number or [x, y, z]");
}

void ApplyConfig(const std::string& path, PlannerOptions* o) {
  std::ifstream in(path);
  if (!in) throw FileError("cannot read config '" + path + "'");
  Json root;
  try {
    root = Json::parse(in);
  } catch (const Json::exception& e) {
    throw std::invalid_argument("config '" + path + "': not valid JSON: " + e.what());
  }
  const std::string c = "config";
  CheckKeys(root, c, {"robot_radius", "safety_margin", "max_segment_length", "max_attempts", "limits",
                      "temporal", "spatial", "search"});
  o->robot_radius = Number(root, "robot_radius", c, o->robot_radius);
  o->safety_margin = Number(root, "safety_margin", c, o->safety_margin);
  o->max_segment_length = Number(root, "max_segment_length", c, o->max_segment_length);
  o->max_attempts = static_cast<int>(Number(root, "max_attempts", c, o->max_attempts));
  if (root.contains("limits")) {
    const Json& l = root["limits"];
    CheckKeys(l, c + ".limits", {"max_velocity", "max_acceleration"});
    o->limits.max_velocity = Limit(l, "max_velocity", c + ".limits", o->limits.max_velocity);
    o->limits.max_acceleration = Limit(l, "max_acceleration", c + ".limits", o->limits.max_acceleration);
  }
  if (root.contains("temporal")) {
    const Json& t = root["temporal"];
    CheckKeys(t, c + ".temporal", {"K", "rho", "constraint_mode"});
    o->temporal_cells_per_piece =
        static_cast<int>(Number(t, "K", c + ".temporal", o->temporal_cells_per_piece));
    o->rho = Number(t, "rho", c + ".temporal", o->rho);
    if (t.contains("constraint_mode")) {
      const Json& m = t["constraint_mode"];
      if (m == "certified") o->constraint_mode = ConstraintMode::kCertified;
      else if (m == "paper") o->constraint_mode = ConstraintMode::kPaper;
      else throw std::invalid_argument(c + ".temporal.constraint_mode: expected \"certified\" or \"paper\"");
    }
  }
  if (root.contains("spatial")) {
    const Json& s = root["spatial"];
    const std::string sc = c + ".spatial";
    CheckKeys(s, sc, {"formulation", "smoothness_weight", "collision_weight", "length_weight",
                      "penalty_decay_length", "collision_samples_per_piece", "max_iterations",
                      "heuristic_speed", "dynamic_weight"});
    SpatialOptimizerOptions& so = o->spatial;
    if (s.contains("formulation")) {
      const Json& f = s["formulation"];
      if (f == "spatial") so.formulation = SpatialFormulation::kSpatial;
      else if (f == "time_coupled") so.formulation = SpatialFormulation::kTimeCoupled;
      else throw std::invalid_argument(sc + ".formulation: expected \"spatial\" or \"time_coupled\"");
    }
    so.smoothness_weight = Number(s, "smoothness_weight", sc, so.smoothness_weight);
    so.collision_weight = Number(s, "collision_weight", sc, so.collision_weight);
    so.length_weight = Number(s, "length_weight", sc, so.length_weight);
    so.penalty_decay_length = Number(s, "penalty_decay_length", sc, so.penalty_decay_length);
    so.collision_samples_per_piece = static_cast<int>(
        Number(s, "collision_samples_per_piece", sc, so.collision_samples_per_piece));
    so.max_iterations = static_cast<int>(Number(s, "max_iterations", sc, so.max_iterations));
    so.heuristic_speed = Number(s, "heuristic_speed", sc, so.heuristic_speed);
    so.dynamic_weight = Number(s, "dynamic_weight", sc, so.dynamic_weight);
  }
  if (root.contains("search")) {
    const Json& s = root["search"];
    const std::string sc = c + ".search";
    CheckKeys(s, sc, {"heuristic_weight", "clearance_cost_weight", "max_expanded_nodes"});
    o->search.heuristic_weight = Number(s, "heuristic_weight", sc, o->search.heuristic_weight);
    o->search.clearance_cost_weight =
        Number(s, "clearance_cost_weight", sc, o->search.clearance_cost_weight);
    o->search.max_expanded_nodes = static_cast<int64_t>(
        Number(s, "max_expanded_nodes", sc, static_cast<double>(o->search.max_expanded_nodes)));
  }
}

int ExitCodeFor(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSuccess: return kExitOk;
    case PlanStatus::kInvalidInput:
    case PlanStatus::kStartOutsideMap:
    case PlanStatus::kGoalOutsideMap:
    case PlanStatus::kStartInCollision:
    case PlanStatus::kGoalInCollision: return kExitInvalidInput;
    case PlanStatus::kUnreachable:
    case PlanStatus::kTemporalInfeasible: return kExitInfeasible;
    default: return kExitFailure;
  }
}

int RunPlan(PlanArgs args) {
  const bool defaults = args.map.empty();
  if (defaults) {
    args.map = kDefaultMap;
    if (args.start.empty()) args.start = kDefaultStart;
    if (args.goal.empty()) args.goal = kDefaultGoal;
    if (args.output.empty()) args.output = kDefaultOutput;
    if (args.plot.empty()) args.plot = kDefaultPlot;
  }
  if (args.start.empty() || args.goal.empty()) {
    throw std::invalid_argument("--start and --goal are required with --map");
  }
  const Eigen::Vector3d start = ParsePoint(args.start, "--start");
  const Eigen::Vector3d goal = ParsePoint(args.goal, "--goal");
  PlannerOptions options;
  options.limits.max_velocity.setConstant(2.0);
  options.limits.max_acceleration.setConstant(2.0);
  if (!args.config.empty()) ApplyConfig(args.config, &options);
  if (args.max_velocity) options.limits.max_velocity.setConstant(*args.max_velocity);
  if (args.max_acceleration) options.limits.max_acceleration.setConstant(*args.max_acceleration);
  if (args.robot_radius) options.robot_radius = *args.robot_radius;
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("options: " + error);

  using Clock = std::chrono::steady_clock;
  const OccupancyMap map = OccupancyMap::Load(
      args.map, args.unknown == "occupied" ? UnknownSpace::kOccupied : UnknownSpace::kFree);
  auto t = Clock::now();
  const Esdf esdf = Esdf::FromMap(map);
  const double esdf_ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  Planner planner(esdf);
  const PlanResult plan = planner.Plan(start, goal, options);

  Json summary;
  summary["status"] = ToString(plan.status);
  summary["message"] = plan.message;
  summary["map"] = args.map;
  summary["start"] = {start.x(), start.y(), start.z()};
  summary["goal"] = {goal.x(), goal.y(), goal.z()};
  summary["robot_radius"] = options.robot_radius;
  summary["formulation"] = ToString(options.spatial.formulation);
  summary["constraint_mode"] = ToString(options.constraint_mode);
  const bool ok = plan.is_success();
  const bool has_curve = !plan.curve.empty();
  summary["total_time"] = ok ? Json(plan.temporal.total_time) : Json(nullptr);
  summary["path_length"] = has_curve ? Json(plan.path_length) : Json(nullptr);
  summary["min_clearance"] = has_curve ? Json(plan.min_clearance) : Json(nullptr);
  summary["pieces"] = plan.curve.num_pieces();
  summary["waypoints"] = static_cast<int>(plan.waypoints.cols());
  summary["spatial_attempts"] = plan.spatial_attempts;
  summary["spatial_iterations"] = static_cast<int>(plan.spatial.iterations.size());
  summary["max_velocity_ratio"] = ok ? Json(plan.temporal.max_velocity_ratio) : Json(nullptr);
  summary["max_acceleration_ratio"] = ok ? Json(plan.temporal.max_acceleration_ratio) : Json(nullptr);
  summary["time_ms"] = {{"esdf", esdf_ms},
                        {"search", plan.times.search_ms},
                        {"spatial", plan.times.spatial_ms},
                        {"check", plan.times.check_ms},
                        {"temporal", plan.times.temporal_ms},
                        {"plan_total", plan.times.total_ms}};
  if (ok) {
    const Trajectory trajectory(plan.curve, plan.temporal.profile);
    // The trajectory flown by the default jerk-input quadrotor from a hover (see `timeopt simulate`).
    try {
      const FeasibilityReport flight = QuadrotorSim().Fly(trajectory, options.limits,
                                                          Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      summary["flight"] = {{"feasible", flight.feasible},
                           {"max_velocity_ratio", flight.max_velocity_ratio},
                           {"max_acceleration_ratio", flight.max_acceleration_ratio},
                           {"max_position_error", flight.max_position_error}};
      if (!flight.feasible) summary["flight"]["note"] = kFlightNote;
    } catch (const std::invalid_argument& e) {
      summary["flight"] = {{"error", e.what()}};
    }
    if (!args.output.empty()) {
      EnsureParentDirectory(args.output);
      std::ofstream out(args.output);
      if (!out) throw FileError("cannot write '" + args.output + "'");
      out << SamplesToCsv(trajectory.Sample(100.0));
      if (!out) throw FileError("cannot write '" + args.output + "'");
      summary["output"] = args.output;
    }
    if (!args.plot.empty()) {
      EnsureParentDirectory(args.plot);
      WritePlanPng(esdf, trajectory, args.plot);
      summary["plot"] = args.plot;
    }
  }
  std::cout << summary.dump(2) << "\n";
  if (!ok) std::cerr << "timeopt: plan: " << ToString(plan.status) << ": " << plan.message << "\n";
  return ExitCodeFor(plan.status);
}

}  // namespace

void RegisterPlanCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<PlanArgs>();
  CLI::App* sub = app.add_subcommand(
      "plan",
      "Plan a minimum-time trajectory on a map: A* front-end, Ceres spatial stage, SOCP temporal "
      "stage. Without --map: the shipped default map (" +
          std::string(kDefaultMap) + ", " + kDefaultStart + " -> " + kDefaultGoal +
          "), writing results/plan.csv and results/plan.png");
  sub->add_option("--map", args->map, "OctoMap file (.bt/.ot)");
  sub->add_option("--start", args->start, "Start position x,y,z (metres)");
  sub->add_option("--goal", args->goal, "Goal position x,y,z (metres)");
  sub->add_option("--max-velocity", args->max_velocity, "Per-axis velocity limit, m/s (default 2)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-acceleration", args->max_acceleration,
                  "Per-axis acceleration limit, m/s^2 (default 2)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--robot-radius", args->robot_radius, "Robot radius, metres (default 0.3)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--unknown", args->unknown,
                  "Unobserved voxels inside the map's box: free (optimistic) or occupied")
      ->check(CLI::IsMember({"free", "occupied"}))
      ->capture_default_str();
  sub->add_option("--config", args->config, "Planner options JSON (see the source's header)");
  sub->add_option("-o,--output", args->output, "Trajectory samples CSV at 100 Hz");
  sub->add_option("--plot", args->plot, "PNG: trajectory over a map slice, coloured by speed");
  sub->callback([args, &run] { run = [args] { return RunPlan(*args); }; });
}

}  // namespace timeopt::cli
