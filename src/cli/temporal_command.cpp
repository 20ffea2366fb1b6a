// `timeopt temporal PROBLEM.json [--solver socp|ipopt] [--output RESULT.json]
//                   [--samples TRAJ.csv --rate HZ] [--plot PLOT.png] [--export-cbf SOCP.cbf]`
// `timeopt waypoints WAYPOINTS.csv [--kind cubic|minjerk] [--max-velocity V] [--max-acceleration A]
//                   [--max-jerk J]
//                   [-K K] [--rho RHO] [--solver socp|ipopt] --out-dir DIR`

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "commands.h"
#include "timeopt/conic/cbf.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/core/errors.h"
#include "timeopt/core/files.h"
#include "timeopt/viz/profile_plot.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_socp.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt::cli {
namespace {

TemporalBackend ParseBackend(const std::string& name) {
  TemporalBackend backend = TemporalBackend::kSocp;
  if (!FromString(name, &backend)) {
    throw std::invalid_argument("--solver: expected " + EnumChoices(kTemporalBackends) + ", got '" + name + "'");
  }
  return backend;
}

struct TemporalArgs {
  std::string problem;
  std::string solver = ToString(TemporalBackend::kSocp);
  std::string output;
  std::string samples;
  std::string trajectory;
  double rate = kDefaultSampleRateHz;
  std::string plot;
  std::string export_cbf;
  bool relax_boundary = false;  // also "relax_boundary": true in the problem
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();
  std::optional<double> ipopt_seconds;
};

// Writes the SOCP of `problem` (the one the socp backend solves) as CBF. When presolve has already
// decided the problem there is no program to write, or when the file cannot be written: a warning,
// and the solve's exit code stands.
void ExportSocp(const TemporalProblem& problem, const std::string& path) {
  conic::Problem socp;
  try {
    socp = BuildTemporalSocp(problem);
  } catch (const std::invalid_argument& e) {
    std::cerr << "timeopt: --export-cbf: nothing written: " << e.what() << "\n";
    return;
  }
  std::ostringstream text;
  conic::WriteCbf(socp, text);
  try {
    WriteTextFile(path, text.str());
  } catch (const FileError& e) {
    std::cerr << "timeopt: --export-cbf: nothing written: " << e.what() << "\n";
  }
}

// Solves, writes the requested outputs and returns the exit code.
int SolveAndWrite(const TemporalProblem& problem, const std::string& solver_name, const std::string& output,
                  const std::string& samples, const std::string& trajectory_path, double rate, const std::string& plot,
                  int64_t max_memory_mib, std::optional<double> ipopt_seconds) {
  const auto solver = BudgetedSolver(problem, solver_name, max_memory_mib, ipopt_seconds);
  const TemporalResult result = solver->Solve(problem);
  // Refuse an over-long sample request before writing the result (not after printing it).
  if (result.is_success() && !samples.empty()) Trajectory(problem.curve, result.profile).CheckSampleRate(rate);
  const std::string json = TemporalResultToJson(result);
  if (output.empty())
    std::cout << json;
  else
    WriteTextFile(output, json);
  if (!result.is_success()) {
    std::cerr << "timeopt: " << ToString(result.status) << ": " << result.message << "\n";
    return ExitCodeFor(result.status);
  }
  const Trajectory trajectory(problem.curve, result.profile);
  if (!samples.empty()) WriteTextFile(samples, SamplesToCsv(trajectory.Sample(rate)));
  if (!trajectory_path.empty()) WriteTrajectoryJson(trajectory, trajectory_path);
  if (!plot.empty()) WriteProfilePlotPng(trajectory, problem.limits, plot);
  return kExitOk;
}

int RunTemporal(const TemporalArgs& args) {
  TemporalProblem problem = ReadTemporalProblemJson(args.problem);
  if (args.relax_boundary) problem.relax_boundary = true;
  const int exit_code = SolveAndWrite(problem, args.solver, args.output, args.samples, args.trajectory, args.rate,
                                      args.plot, args.max_memory_mib, args.ipopt_seconds);
  if (!args.export_cbf.empty()) ExportSocp(problem, args.export_cbf);
  return exit_code;
}

// "max_velocity 2 m/s, max_acceleration 1 m/s^2, max_speed 3 m/s, " for the limits that are set.
std::string LimitsLine(const VehicleLimits& l) {
  std::ostringstream ss;
  if (l.max_velocity.allFinite()) ss << "max_velocity " << l.max_velocity.x() << " m/s, ";
  if (l.max_acceleration.allFinite()) ss << "max_acceleration " << l.max_acceleration.x() << " m/s^2, ";
  if (l.max_speed) ss << "max_speed " << *l.max_speed << " m/s, ";
  if (l.max_acceleration_norm) ss << "max_acceleration_norm " << *l.max_acceleration_norm << " m/s^2, ";
  if (l.max_thrust) ss << "max_thrust " << *l.max_thrust << " m/s^2, ";
  if (l.min_thrust) ss << "min_thrust " << *l.min_thrust << " m/s^2, ";
  if (l.max_tilt) ss << "max_tilt " << *l.max_tilt << " rad, ";
  return ss.str();
}

// ", max ||v||/max_speed 1, ..." for the quadrotor limits given, from a TemporalResult (the dense
// check) or a FeasibilityReport (the flight): both name their ratios alike.
template <typename Ratios>
std::string QuadrotorRatios(const Ratios& r) {
  std::ostringstream ss;
  if (r.max_speed_ratio) ss << ", max ||v||/max_speed " << *r.max_speed_ratio;
  if (r.max_acceleration_norm_ratio) ss << ", max ||a||/max_acceleration_norm " << *r.max_acceleration_norm_ratio;
  if (r.max_thrust_ratio) ss << ", max thrust/max_thrust " << *r.max_thrust_ratio;
  if (r.min_thrust_ratio) ss << ", min_thrust/min thrust " << *r.min_thrust_ratio;
  if (r.max_tilt_ratio) ss << ", max tilt/max_tilt " << *r.max_tilt_ratio;
  return ss.str();
}

// Defaults are the library's flight defaults (FlightLimits, kFlightConstraintMode: a trajectory
// that holds its limits between grid points and can be flown), never restated here.
struct WaypointsArgs {
  std::string waypoints;
  std::string kind = "minjerk";
  // Unset: the flight default, or none when a quadrotor limit bounds the same quantity.
  std::optional<double> max_velocity, max_acceleration;
  double max_jerk = FlightLimits().max_jerk->x();  // 0: none (the paper's profile)
  QuadrotorLimitArgs quadrotor;
  int K = TemporalProblem().cells_per_piece;
  double rho = TemporalProblem().rho;
  std::string solver = ToString(TemporalBackend::kSocp);
  std::string constraint_mode = ToString(kFlightConstraintMode);
  std::string out_dir = "results";
  std::string trajectory;
  double rate = kDefaultSampleRateHz;
  bool verbose = false, quiet = false, json = false;
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();
  std::optional<double> ipopt_seconds;
};

std::string FormatNumber(double value) {
  std::ostringstream ss;
  ss << std::setprecision(6) << value;
  return ss.str();
}

int RunWaypoints(const WaypointsArgs& args) {
  int merged = 0;
  const Waypoints waypoints = ReadDistinctWaypoints(args.waypoints, &merged);
  TemporalProblem problem;
  problem.curve = args.kind == "cubic" ? NaturalCubicSpline(waypoints) : MinimumJerkSpline(waypoints);
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const QuadrotorLimitArgs& q = args.quadrotor;
  const double default_v = FlightLimits().max_velocity.x();
  const double default_a = FlightLimits().max_acceleration.x();
  problem.limits.max_velocity.setConstant(args.max_velocity.value_or(q.max_speed ? kNone : default_v));
  problem.limits.max_acceleration.setConstant(
      args.max_acceleration.value_or(q.max_acceleration_norm || q.max_thrust || q.max_tilt ? kNone : default_a));
  ApplyQuadrotorLimits(q, &problem.limits);
  problem.limits.max_jerk.reset();
  if (args.max_jerk > 0.0) problem.limits.max_jerk = Eigen::Vector3d::Constant(args.max_jerk);
  problem.cells_per_piece = args.K;
  problem.rho = args.rho;
  if (!FromString(args.constraint_mode, &problem.constraint_mode)) {
    throw std::invalid_argument("--constraint-mode: expected " + EnumChoices(kConstraintModes));
  }
  problem.Validate();

  const std::filesystem::path dir(args.out_dir);
  EnsureParentDirectory((dir / "curve.json").string());
  WriteCurveJson(problem.curve, (dir / "curve.json").string());

  if (args.verbose) {
    std::cerr << "timeopt waypoints: curve: " << args.kind << ", " << problem.curve.num_pieces() << " pieces";
    if (merged > 0) std::cerr << " (" << merged << " coincident waypoints dropped)";
    std::cerr << "\n";
  }
  const auto solver = BudgetedSolver(problem, args.solver, args.max_memory_mib, args.ipopt_seconds);
  const TemporalResult result = solver->Solve(problem);
  if (args.verbose) {
    std::cerr << "timeopt waypoints: temporal: " << std::fixed << std::setprecision(1)
              << 1e3 * (result.build_time_seconds + result.solve_time_seconds) << " ms" << std::defaultfloat
              << std::setprecision(6) << ", " << ToString(result.status) << ", " << result.method << ", T "
              << result.total_time << " s";
    if (result.scp_iterations > 0) std::cerr << ", " << result.scp_iterations << " convex solves";
    std::cerr << "\n";
  }
  if (result.is_success()) Trajectory(problem.curve, result.profile).CheckSampleRate(args.rate);
  if (!result.is_success()) {
    WriteTextFile((dir / "result.json").string(), TemporalResultToJson(result));
    std::cerr << "timeopt: " << ToString(result.status) << ": " << result.message << "\n";
    return ExitCodeFor(result.status);
  }
  // result.json: the result and the flight block (as in `plan`'s summary).
  nlohmann::json result_json = nlohmann::json::parse(TemporalResultToJson(result));
  result_json["merged_waypoints"] = merged;
  const Trajectory trajectory(problem.curve, result.profile);
  WriteTextFile((dir / "samples.csv").string(), SamplesToCsv(trajectory.Sample(args.rate)));
  WriteTrajectoryJson(trajectory, (dir / "trajectory.json").string());
  if (!args.trajectory.empty()) WriteTrajectoryJson(trajectory, args.trajectory);
  WriteProfilePlotPng(trajectory, problem.limits, (dir / "profile.png").string());
  const QuadrotorSim sim = SummaryQuadrotor(problem.limits);
  std::ostringstream flown;
  try {
    const FeasibilityReport flight =
        sim.Fly(trajectory, problem.limits, problem.boundary.start_velocity, problem.boundary.start_acceleration);
    result_json["flight"] = FlightSummary(flight, problem.limits);
    if (args.verbose) {
      std::cerr << "timeopt waypoints: flight: " << (flight.feasible ? "the limits hold" : flight.message) << "\n";
    }
    flown << "flown by a jerk-input quadrotor (tracking bandwidth " << sim.options().bandwidth << " rad/s, "
          << 1.0 / sim.options().time_step << " Hz): max |v|/vmax " << flight.max_velocity_ratio << ", max |a|/amax "
          << flight.max_acceleration_ratio << QuadrotorRatios(flight) << " ("
          << (flight.feasible ? "limits hold" : "limits exceeded") << (problem.limits.max_jerk ? " within 1%" : "")
          << "; see `timeopt simulate`)";
    if (!flight.feasible && !problem.limits.max_jerk) flown << "\n  note: " << kFlightNote;
  } catch (const std::invalid_argument& e) {
    flown << "not flown in simulation: " << e.what();
    result_json["flight"] = {{"error", e.what()}};
  }
  WriteTextFile((dir / "result.json").string(), result_json.dump(2) + "\n");

  if (args.json) {
    std::cout << result_json.dump(2) << "\n";
    return kExitOk;
  }
  if (args.quiet) return kExitOk;
  std::cout << std::setprecision(6) << "waypoints: " << waypoints.cols() << DroppedWaypointsNote(merged) << " ("
            << args.kind << " curve, " << problem.curve.num_pieces() << " pieces, length "
            << problem.curve.ArcLength(1e-9) << " m)\n"
            << "limits: " << LimitsLine(problem.limits)
            << (args.max_jerk > 0.0 ? "max_jerk " + FormatNumber(args.max_jerk) + " m/s^3, " : std::string()) << "K "
            << args.K << ", rho " << args.rho << ", " << args.constraint_mode << " constraints\n"
            << "solver: " << result.solver << ", " << result.iterations << " iterations, "
            << result.solve_time_seconds * 1e3 << " ms\n"
            << "total_time: " << result.total_time << " s\n"
            << "max |v|/vmax along the trajectory: " << result.max_velocity_ratio
            << ", max |a|/amax: " << result.max_acceleration_ratio << QuadrotorRatios(result) << "\n"
            << flown.str() << "\n"
            << "written: " << (dir / "curve.json").string() << ", " << (dir / "result.json").string() << ", "
            << (dir / "samples.csv").string() << ", " << (dir / "trajectory.json").string() << ", "
            << (dir / "profile.png").string() << "\n";
  return kExitOk;
}

}  // namespace

std::unique_ptr<TemporalSolver> BudgetedSolver(const TemporalProblem& problem, const std::string& name,
                                               int64_t max_memory_mib, std::optional<double> ipopt_seconds) {
  const TemporalBackend backend = ParseBackend(name);
  const int64_t budget = max_memory_mib * 1024 * 1024;
  try {
    CheckTemporalMemory(problem, backend, budget);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string(e.what()) + " (fewer cells, or a larger --max-memory)");
  }
  return MakeBudgetedTemporalSolver(backend, budget, ipopt_seconds);
}

void AddIpoptSecondsOption(CLI::App* sub, std::optional<double>* seconds) {
  sub->add_option("--ipopt-seconds", *seconds,
                  "CPU seconds for an Ipopt solve: --solver ipopt (default 300), or the socp solver's fallback to "
                  "Ipopt's exact jerk rows (default 20; 0: none)")
      ->check(CLI::NonNegativeNumber);
}

void RegisterTemporalCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<TemporalArgs>();
  CLI::App* sub = app.add_subcommand(
      "temporal", "Minimum-time temporal profile along a given curve (problem JSON: docs/formats.md)");
  sub->add_option("PROBLEM", args->problem, "Problem JSON file")->required();
  sub->add_option("--solver", args->solver, "socp (our conic solver) or ipopt")
      ->check(CLI::IsMember(EnumNames(kTemporalBackends)))
      ->capture_default_str();
  sub->add_option("-o,--output", args->output, "Result JSON file (default: stdout)");
  sub->add_option("--samples", args->samples, "Trajectory samples CSV (t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz)");
  sub->add_option("--rate", args->rate, "Sample rate for --samples, Hz")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--plot", args->plot, "PNG of speed, velocity and acceleration against time");
  sub->add_option("--trajectory", args->trajectory, kTrajectoryOptionHelp);
  AddSolveMemoryOption(sub, &args->max_memory_mib);
  AddIpoptSecondsOption(sub, &args->ipopt_seconds);
  sub->add_flag("--relax-boundary", args->relax_boundary,
                "If the boundary speeds cannot be flown, answer with the closest ones that can (the result's "
                "boundary_relaxation) instead of infeasible");
  sub->add_option("--export-cbf", args->export_cbf,
                  "Also write the SOCP that --solver socp solves, in the Conic Benchmark Format (its "
                  "optimal value is the result's objective), for another conic solver");
  sub->callback([args, &run] { run = [args] { return RunTemporal(*args); }; });
}

void RegisterWaypointsCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<WaypointsArgs>();
  CLI::App* sub =
      app.add_subcommand("waypoints", "Fit a curve through waypoints, time it optimally, write samples and a plot");
  sub->add_option("WAYPOINTS", args->waypoints, "Waypoint CSV file (x,y,z rows)")->required();
  sub->add_option("--kind", args->kind, "cubic or minjerk (rest to rest)")
      ->check(CLI::IsMember({"cubic", "minjerk"}))
      ->capture_default_str();
  sub->add_option("--max-velocity", args->max_velocity,
                  "Per-axis velocity limit, m/s (default " + std::to_string(FlightLimits().max_velocity.x()) +
                      "; none when --max-speed is given)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--max-acceleration", args->max_acceleration,
                  "Per-axis acceleration limit, m/s^2 (default " + std::to_string(FlightLimits().max_acceleration.x()) +
                      "; none when --max-acceleration-norm, --max-thrust or --max-tilt is given)")
      ->check(CLI::PositiveNumber);
  AddQuadrotorLimitOptions(sub, &args->quadrotor);
  sub->add_option("--max-jerk", args->max_jerk,
                  "Per-axis jerk limit, m/s^3: a jerk-limited profile with continuous acceleration "
                  "(0: none, the paper's profile)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("-K,--cells", args->K, "Cells per piece")
      ->check(CLI::Range(1, kMaxCellsPerPiece))
      ->capture_default_str();
  sub->add_option("--rho", args->rho, "Acceleration regularization weight")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--solver", args->solver, "socp or ipopt")
      ->check(CLI::IsMember(EnumNames(kTemporalBackends)))
      ->capture_default_str();
  sub->add_option("--constraint-mode", args->constraint_mode, "paper or certified")
      ->check(CLI::IsMember(EnumNames(kConstraintModes)))
      ->capture_default_str();
  sub->add_option("--rate", args->rate, "Sample rate, Hz")->check(CLI::PositiveNumber)->capture_default_str();
  sub->add_option("--out-dir", args->out_dir, "Output directory")->capture_default_str();
  sub->add_option("--trajectory", args->trajectory,
                  std::string(kTrajectoryOptionHelp) + " (also written as trajectory.json in --out-dir)");
  AddSolveMemoryOption(sub, &args->max_memory_mib);
  AddIpoptSecondsOption(sub, &args->ipopt_seconds);
  sub->add_flag("-v,--verbose", args->verbose, "One line per stage on stderr (curve, temporal, flight)");
  sub->add_flag("-q,--quiet", args->quiet, "Print nothing on stdout (the files are still written)");
  sub->add_flag("--json", args->json, "Print result.json (the result and its flight block) instead of the summary");
  sub->callback([args, &run] { run = [args] { return RunWaypoints(*args); }; });
}

}  // namespace timeopt::cli
