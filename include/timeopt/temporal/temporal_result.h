#pragma once

// What a temporal solver returns: its status, the backend that produced it, and the result.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "timeopt/temporal/joints.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt {

enum class TemporalStatus {
  kOptimal,         // profile, total_time and piece_durations are usable
  kInfeasible,      // no time allocation satisfies the limits; message says why when known
  kIterationLimit,  // the solver stopped first; nothing is usable
  kNumericalError,  // the solver failed numerically; nothing is usable
  kInvalidInput,    // the problem is malformed; message names the field
};

// "optimal", "infeasible", "iteration_limit", "numerical_error", "invalid_input".
// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<TemporalStatus, 5> kTemporalStatuses = {
    TemporalStatus::kOptimal,        TemporalStatus::kInfeasible,   TemporalStatus::kIterationLimit,
    TemporalStatus::kNumericalError, TemporalStatus::kInvalidInput,
};
const char* ToString(TemporalStatus status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, TemporalStatus* status);

enum class TemporalBackend { kSocp, kIpopt };

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<TemporalBackend, 2> kTemporalBackends = {
    TemporalBackend::kSocp,
    TemporalBackend::kIpopt,
};
const char* ToString(TemporalBackend backend);  // "socp", "ipopt"
// The enumerator named `text` (as ToString writes it) into *backend; false when none is.
bool FromString(const std::string& text, TemporalBackend* backend);

struct TemporalResult {
  TemporalStatus status = TemporalStatus::kNumericalError;
  std::string message;
  std::string solver;  // "socp" or "ipopt"
  // The path that answered: "structured" (the SOCP backend's banded interior-point method),
  // "conic" (its general conic solver), "ipopt" (Ipopt, also when the SOCP backend fell back to
  // it), or empty when presolve decided without a solve.
  std::string method;
  // Inequality rows of the last convex solve (a working set when the sequential convex programme
  // leaves rows out), for benchmarks.
  int rows = 0;
  double total_time = 0.0;              // T, seconds
  double objective = 0.0;               // J = T + rho sum a^2 ds
  std::vector<double> piece_durations;  // seconds
  int iterations = 0;
  double solve_time_seconds = 0.0;  // solver only (building excluded)
  double build_time_seconds = 0.0;  // discretization and problem assembly
  TemporalProfile profile;          // set when optimal
  std::vector<JointInfo> joints;    // joint types found (C1, G1 with ratio, stop)
  // Dense check of the exact trajectory (not only the grid): the largest |v_axis| / vmax_axis and
  // |acc_axis| / amax_axis over all axes and a fine sampling of every cell. Set when optimal.
  double max_velocity_ratio = 0.0;
  double max_acceleration_ratio = 0.0;
  // The quadrotor's limits on the same dense check, each set when its limit is given: the largest
  // ||v|| / max_speed, ||acc|| / max_acceleration_norm, ||acc + g e3|| / max_thrust, min_thrust /
  // ||acc + g e3|| (its smallest value) and tilt / max_tilt. Above 1: the limit is exceeded.
  std::optional<double> max_speed_ratio;
  std::optional<double> max_acceleration_norm_ratio;
  std::optional<double> max_thrust_ratio;
  std::optional<double> min_thrust_ratio;
  std::optional<double> max_tilt_ratio;
  // Jerk-limited mode: the largest |jerk_axis| / max_jerk_axis on the same dense check (0
  // otherwise), the number of convex solves of the sequential convex programme, and T after each
  // of them. On the structured path every solve is jerk-feasible (the first is linearized at the
  // jerk-free certified optimum) and the first, solved to looser tolerances as a linearization
  // point only, is never the answer; on the general path the first one is jerk-free (not
  // jerk-feasible) and each later one is. The Ipopt backend solves the exact, non-convex jerk rows
  // once: scp_iterations 0, no history.
  // Why the problem is infeasible (status kInfeasible): cause "boundary_speed" (a boundary speed
  // above a speed limit), "braking" (a start too fast to brake for a slower part ahead; where names
  // the arc length at which braking fails), "end_speed" (an end speed that cannot be reached),
  // "boundary_acceleration" (a boundary acceleration the limits cannot meet), or "limits" (the
  // limits allow no profile whatever the boundary speeds); where and a one-line detail.
  struct Infeasibility {
    std::string cause;
    std::string where;
    std::string detail;
  };
  std::optional<Infeasibility> infeasibility;
  // TemporalProblem::relax_boundary on an infeasible problem: the closest boundary speeds it could
  // fly (m/s along the tangent), the given ones, and the answer for them (status optimal).
  // start_scale is start_speed / start_speed_given (1 for a start at rest); start_acceleration says
  // what became of the start acceleration: "unchanged" (the speeds' relaxation), "scaled" (times
  // start_scale^2) or "braking_kept" (its part across the path times start_scale^2, its braking
  // along the path as given).
  struct BoundaryRelaxation {
    double start_speed_given = 0.0, start_speed = 0.0;
    double end_speed_given = 0.0, end_speed = 0.0;
    double start_scale = 1.0;
    std::string start_acceleration = "unchanged";
  };
  std::optional<BoundaryRelaxation> boundary_relaxation;
  bool jerk_limited = false;  // the problem had limits.max_jerk (set whatever the status)
  double max_jerk_ratio = 0.0;
  int scp_iterations = 0;
  std::vector<double> scp_history;

  // Optimal, but only to the backend's reduced tolerances (the conic solver's
  // reduced_feasibility_tolerance and reduced_gap_tolerance; Ipopt's acceptable level): rounding
  // stopped the solver short of its tolerances. `message` says why.
  bool reduced_accuracy = false;

  bool is_success() const { return status == TemporalStatus::kOptimal; }
};

}  // namespace timeopt
