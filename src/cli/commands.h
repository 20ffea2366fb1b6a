#pragma once

// Subcommands of the `timeopt` command-line tool. Each Register* adds its subcommand to the app and
// sets `run` to the function that executes it after parsing; the function returns the exit code.
// Exit codes: 0 success, 2 invalid input or unreadable file, 3 infeasible, 1 anything else.

#include <unistd.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "timeopt/conic/solver.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/sim_io.h"
#include "timeopt/planner/planner.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitInvalidInput = 2;
constexpr int kExitInfeasible = 3;

// A waypoints CSV as `curve` and `waypoints` fit it: waypoints that coincide with the one before
// dropped (MergeCoincidentWaypoints); *merged gets how many.
inline Waypoints ReadDistinctWaypoints(const std::string& path, int* merged) {
  return MergeCoincidentWaypoints(ReadWaypointsCsv(path), kCoincidentWaypointFraction, merged);
}
// What the text output says after a waypoint count when some were dropped ("" when none was).
inline std::string DroppedWaypointsNote(int merged) {
  return merged > 0 ? " (" + std::to_string(merged) + " more dropped: each coincided with the one before)" : "";
}

// Said next to a flight whose limits were exceeded, so that a reader of the summary knows what it
// means: without a jerk limit the plan satisfies its limits but the jerk-input vehicle cannot follow
// its acceleration steps.
inline constexpr const char* kFlightNote =
    "expected without a jerk limit: the planned trajectory holds its limits, but its acceleration "
    "steps between cells and a jerk-input vehicle overshoots at each step ('Verification "
    "by simulation' in docs/simulation.md); time it with a jerk limit (--max-jerk)";

// The flight verdict's slack for jerk-limited plans (timeopt/sim/quadrotor_sim.h).
inline constexpr double kJerkLimitedFlightTolerance = kFlightTolerance;

// The distance field's memory budget for --max-memory (MiB): half of this machine's physical
// memory, so that a map too large for the machine is refused with a message (exit 2) before the
// field is allocated, not killed by the kernel. 4096 where the machine does not say.
inline int64_t DefaultMemoryBudgetMiB() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages <= 0 || page <= 0) return 4096;
  return static_cast<int64_t>(pages) * page / 2 / (1024 * 1024);
}
// --max-memory MiB, 1 to 2^40, described by `help` (which says what the budget covers).
inline void AddMemoryOption(CLI::App* sub, int64_t* mebibytes, const std::string& help) {
  sub->add_option("--max-memory", *mebibytes, help)
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 40))
      ->capture_default_str();
}
inline void AddMemoryBudgetOption(CLI::App* sub, int64_t* mebibytes) {
  AddMemoryOption(sub, mebibytes,
                  "Memory budget of the distance field, MiB (its peak is 9 bytes per voxel); default: half "
                  "of this machine's memory");
}

// The temporal solver `name` (socp or ipopt) under a memory budget (MiB): a problem whose
// TemporalPeakBytes is above it is invalid input before anything is solved, and the socp backend's
// Ipopt fallback keeps to it; ipopt_seconds caps Ipopt's CPU time (temporal_command.cpp).
std::unique_ptr<TemporalSolver> BudgetedSolver(const TemporalProblem& problem, const std::string& name,
                                               int64_t max_memory_mib, std::optional<double> ipopt_seconds);
// --ipopt-seconds, for BudgetedSolver.
void AddIpoptSecondsOption(CLI::App* sub, std::optional<double>* seconds);

inline void AddSolveMemoryOption(CLI::App* sub, int64_t* mebibytes) {
  AddMemoryOption(sub, mebibytes,
                  "Memory budget of the solve, MiB: a problem whose estimated peak (cells x a measured figure per "
                  "cell, docs/sizes-and-errors.md) is above it is refused before solving; default: half of this "
                  "machine's memory");
}

// The default quadrotor for the summaries' flights, with the verdict's slack for `limits`.
inline QuadrotorSim SummaryQuadrotor(const VehicleLimits& limits) {
  QuadrotorSimOptions options;
  options.limit_tolerance = DefaultFlightTolerance(limits);
  return QuadrotorSim(options);
}

// The flight block of the summaries (`plan`'s JSON, `waypoints`' result.json): the verdict of
// SummaryQuadrotor(limits), its ratios, the tolerance it allowed, and kFlightNote when a profile
// without a jerk limit was not flown within its limits.
inline nlohmann::ordered_json FlightSummary(const FeasibilityReport& flight, const VehicleLimits& limits) {
  // The report's own JSON (io), of which the summary keeps the verdict and the largest ratios.
  const nlohmann::ordered_json report = nlohmann::ordered_json::parse(FeasibilityReportToJson(flight));
  nlohmann::ordered_json j;
  for (const char* key :
       {"feasible", "max_velocity_ratio", "max_acceleration_ratio", "max_position_error", "max_speed_ratio",
        "max_acceleration_norm_ratio", "max_thrust_ratio", "min_thrust_ratio", "max_tilt_ratio", "tolerance"}) {
    if (report.contains(key)) j[key] = report[key];
  }
  if (!flight.feasible && !limits.max_jerk) j["note"] = kFlightNote;
  return j;
}

// The one mapping from the library's statuses to exit codes (exit_codes.cpp): 0 success, 2 invalid
// input, 3 infeasible (no trajectory satisfies the limits, or no path exists), 1 anything else.
int ExitCodeFor(TemporalStatus status);
int ExitCodeFor(PlanStatus status);
int ExitCodeFor(conic::Status status);

// The quadrotor's own limits as options (--max-speed, --max-acceleration-norm, --max-thrust,
// --min-thrust, --max-tilt), shared by waypoints, plan and simulate (quadrotor_options.cpp). Each
// given one overrides the problem's; a negative or non-finite value is invalid input (named).
struct QuadrotorLimitArgs {
  std::optional<double> max_speed, max_acceleration_norm, max_thrust, min_thrust, max_tilt;
  bool any() const { return max_speed || max_acceleration_norm || max_thrust || min_thrust || max_tilt; }
};
void AddQuadrotorLimitOptions(CLI::App* sub, QuadrotorLimitArgs* args);
void ApplyQuadrotorLimits(const QuadrotorLimitArgs& args, VehicleLimits* limits);

// Help of --trajectory (plan, temporal, waypoints).
inline constexpr const char* kTrajectoryOptionHelp =
    "Trajectory JSON: the curve and the profile, exact, for `timeopt export` and Python's Trajectory.load";

using Runner = std::function<int()>;

void RegisterCurveCommand(CLI::App& app, Runner& run);
void RegisterTemporalCommand(CLI::App& app, Runner& run);
void RegisterWaypointsCommand(CLI::App& app, Runner& run);
void RegisterMapCommand(CLI::App& app, Runner& run);
void RegisterPlanCommand(CLI::App& app, Runner& run);
void RegisterConicCommand(CLI::App& app, Runner& run);
void RegisterSimulateCommand(CLI::App& app, Runner& run);
void RegisterExportCommand(CLI::App& app, Runner& run);
void RegisterViewCommand(CLI::App& app, Runner& run);

}  // namespace timeopt::cli
