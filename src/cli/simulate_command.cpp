// `timeopt simulate PROBLEM.json [--solver socp|ipopt] [--bandwidth W] [--control-rate HZ]
//                   [--settle-time S] [--max-jerk J] [--vehicle-max-jerk J] [--output REPORT.json]
//                   [--states STATES.csv]`
// `timeopt simulate --samples TRAJ.csv --max-velocity V --max-acceleration A [same options]`
// Solves the temporal problem (or takes another planner's samples), flies the trajectory with the
// jerk-input quadrotor of sim/ and writes the feasibility report. Exit codes: 0 every velocity and
// acceleration limit held during the flight, 1 a limit was exceeded (one line on stderr) or the
// solve failed, 3 the temporal problem is infeasible, 2 invalid input.

#include <cmath>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/core/files.h"
#include "timeopt/io/sim_io.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt::cli {
namespace {

// The vehicle's defaults are the library's (QuadrotorSimOptions), never restated here.
struct SimulateArgs {
  std::string problem;
  std::string samples;
  double max_velocity = 0.0;
  double max_acceleration = 0.0;
  std::string solver = ToString(TemporalBackend::kSocp);
  double bandwidth = QuadrotorSimOptions().bandwidth;
  double control_rate = 1.0 / QuadrotorSimOptions().time_step;
  double settle_time = QuadrotorSimOptions().settle_time;
  // The problem's jerk limit (limits.max_jerk, every axis): overrides the JSON's; 0 removes it.
  std::optional<double> max_jerk;
  double vehicle_max_jerk = 0.0;  // the vehicle's own jerk limit (0: none)
  // Relative slack of the verdict. Unset: rounding only (1e-9), or 1% for a problem with a jerk
  // limit (the 1 kHz controller lags a continuous reference by a little).
  std::optional<double> tolerance;
  QuadrotorLimitArgs quadrotor;  // override the problem's (or, with --samples, add to the per-axis ones)
  std::string output;
  std::string states;
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();  // the solve's (PROBLEM.json)
  std::optional<double> ipopt_seconds;
};

int RunSimulate(const SimulateArgs& args) {
  if (args.problem.empty() == args.samples.empty()) {
    throw std::invalid_argument("give either PROBLEM.json or --samples TRAJ.csv");
  }
  if (!args.samples.empty() &&
      !((args.max_velocity > 0.0 || args.quadrotor.max_speed) &&
        (args.max_acceleration > 0.0 || args.quadrotor.max_acceleration_norm || args.quadrotor.max_thrust))) {
    throw std::invalid_argument(
        "--samples needs --max-velocity and --max-acceleration (m/s, m/s^2 per axis), or "
        "--max-speed and --max-acceleration-norm or --max-thrust");
  }
  if (!args.samples.empty() && args.max_jerk) {
    throw std::invalid_argument(
        "--max-jerk sets the problem's jerk limit, so it needs PROBLEM.json; for the "
        "vehicle's own limit use --vehicle-max-jerk");
  }
  if (!std::isfinite(args.control_rate) || !std::isfinite(args.bandwidth) || !std::isfinite(args.settle_time) ||
      !std::isfinite(args.max_jerk.value_or(0.0)) || !std::isfinite(args.vehicle_max_jerk) ||
      !std::isfinite(args.max_velocity) || !std::isfinite(args.max_acceleration)) {
    throw std::invalid_argument(
        "--control-rate, --bandwidth, --settle-time, --max-jerk, --vehicle-max-jerk, "
        "--max-velocity and --max-acceleration must be finite");
  }
  if (args.control_rate < 10.0 * args.bandwidth) {
    throw std::invalid_argument(
        "--control-rate must be at least 10 x --bandwidth (10 controller steps per "
        "time constant 1 / bandwidth)");
  }
  QuadrotorSimOptions options;
  options.bandwidth = args.bandwidth;
  options.time_step = 1.0 / args.control_rate;
  options.settle_time = args.settle_time;
  if (args.vehicle_max_jerk > 0.0) options.max_jerk = Eigen::Vector3d::Constant(args.vehicle_max_jerk);
  options.record_states = !args.states.empty();
  if (args.tolerance) options.limit_tolerance = *args.tolerance;
  QuadrotorSim sim(options);  // invalid options throw before the solve

  nlohmann::ordered_json json;
  json["feasible"] = nullptr;  // first in the output; set below
  json["message"] = "";
  FeasibilityReport report;
  try {
    if (!args.samples.empty()) {
      // Another planner's trajectory: the vehicle starts in its first sample.
      const std::vector<TrajectoryState> samples = ReadSamplesCsv(args.samples);
      TemporalLimits limits;
      constexpr double kNone = std::numeric_limits<double>::infinity();
      limits.max_velocity.setConstant(args.max_velocity > 0.0 ? args.max_velocity : kNone);
      limits.max_acceleration.setConstant(args.max_acceleration > 0.0 ? args.max_acceleration : kNone);
      ApplyQuadrotorLimits(args.quadrotor, &limits);
      const double duration = samples.back().t - samples.front().t;
      if (!args.tolerance) {
        // Samples are flown as a C2 interpolation of themselves: the product's flight criterion.
        options.limit_tolerance = kFlightTolerance;
        sim = QuadrotorSim(options);
      }
      report = sim.Run(SampledReference(samples), duration, limits);
      json["samples"] = static_cast<int>(samples.size());
      json["total_time"] = duration;
    } else {
      TemporalProblem problem = ReadTemporalProblemJson(args.problem);
      if (args.max_jerk) {
        if (*args.max_jerk > 0.0)
          problem.limits.max_jerk = Eigen::Vector3d::Constant(*args.max_jerk);
        else
          problem.limits.max_jerk.reset();
      }
      ApplyQuadrotorLimits(args.quadrotor, &problem.limits);
      problem.Validate();
      const TemporalResult result =
          BudgetedSolver(problem, args.solver, args.max_memory_mib, args.ipopt_seconds)->Solve(problem);
      if (!result.is_success()) {
        std::cerr << "timeopt: " << ToString(result.status) << ": " << result.message << "\n";
        return ExitCodeFor(result.status);
      }
      if (!args.tolerance) {
        options.limit_tolerance = DefaultFlightTolerance(problem.limits);
        sim = QuadrotorSim(options);
      }
      // The vehicle starts in the problem's start state (a hover for rest-to-rest problems).
      report = sim.Fly(Trajectory(problem.curve, result.profile), problem.limits, problem.boundary.start_velocity,
                       problem.boundary.start_acceleration);
      json["total_time"] = result.total_time;
      // The reference itself, sampled densely by the temporal stage (no tracking).
      json["reference_max_velocity_ratio"] = result.max_velocity_ratio;
      json["reference_max_acceleration_ratio"] = result.max_acceleration_ratio;
    }
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    const bool recording = !args.states.empty() && what.find("record_states") != std::string::npos;
    throw std::invalid_argument((recording ? "--states: " : "") + what);
  }

  const nlohmann::ordered_json flown = nlohmann::ordered_json::parse(FeasibilityReportToJson(report));
  for (const auto& item : flown.items()) json[item.key()] = item.value();
  json["tolerance"] = report.tolerance;
  json["bandwidth"] = args.bandwidth;
  json["control_rate"] = args.control_rate;
  const std::string text = json.dump(2) + "\n";
  if (args.output.empty())
    std::cout << text;
  else
    WriteTextFile(args.output, text);
  if (!args.states.empty()) WriteTextFile(args.states, SimStatesToCsv(report.states));
  if (!report.feasible) {
    std::cerr << "timeopt: limit exceeded in simulation: " << report.message << "\n";
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void RegisterSimulateCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* sub =
      app.add_subcommand("simulate",
                         "Solve a temporal problem and fly the trajectory with a jerk-input quadrotor under "
                         "feedback; report whether every limit held in continuous time");
  sub->add_option("PROBLEM", args->problem, "Problem JSON file (as for `temporal`)");
  sub->add_option("--samples", args->samples,
                  "Fly a given trajectory instead: samples CSV t,x,y,z,vx,vy,vz,ax,ay,az[,jx,jy,jz] "
                  "(e.g. from `temporal --samples` or another planner)");
  sub->add_option("--max-velocity", args->max_velocity, "With --samples: velocity limit per axis, m/s");
  sub->add_option("--max-acceleration", args->max_acceleration, "With --samples: acceleration limit per axis, m/s^2");
  sub->add_option("--solver", args->solver, "socp (our conic solver) or ipopt")
      ->check(CLI::IsMember(EnumNames(kTemporalBackends)))
      ->capture_default_str();
  sub->add_option("--bandwidth", args->bandwidth, "Tracking loop bandwidth (all poles at -W), rad/s")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--control-rate", args->control_rate, "Controller rate (jerk held between updates), Hz")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--settle-time", args->settle_time, "Flight after the trajectory ends, s")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  sub->add_option("--max-jerk", args->max_jerk,
                  "The problem's jerk limit per axis, m/s^3: the profile becomes jerk-limited (overrides "
                  "limits.max_jerk; 0 removes it)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--vehicle-max-jerk", args->vehicle_max_jerk,
                  "The vehicle's own jerk limit per axis, m/s^3: commands beyond it are clipped (0: none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  AddQuadrotorLimitOptions(sub, &args->quadrotor);
  sub->add_option("--tolerance", args->tolerance,
                  "Relative slack of the verdict (default: 0.01 for a problem with limits.max_jerk and for "
                  "--samples, rounding only (1e-9) otherwise)")
      ->check(CLI::Range(0.0, 1.0));
  AddSolveMemoryOption(sub, &args->max_memory_mib);
  AddIpoptSecondsOption(sub, &args->ipopt_seconds);
  sub->add_option("-o,--output", args->output, "Report JSON file (default: stdout)");
  sub->add_option("--states", args->states,
                  "CSV of the vehicle's state at every controller step (t,x..z,vx..vz,ax..az,jx..jz,ex..ez)");
  sub->callback([args, &run] { run = [args] { return RunSimulate(*args); }; });
}

}  // namespace timeopt::cli
