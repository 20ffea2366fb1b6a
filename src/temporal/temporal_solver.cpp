// The temporal stage's solve policy: which path answers a problem, in the problem's own units
// (TemporalSolver::Solve), the one solve of the paper's and certified rows, and the nearest flyable
// start (RelaxStartState). The jerk-limited programme is in jerk_solver.cpp, the names and options
// in temporal_options.cpp, the finishing of an answer in result_finishing.cpp.

#include "timeopt/temporal/temporal_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "banded_ipm.h"
#include "discretization_internal.h"
#include "infeasibility.h"
#include "solver_internal.h"

namespace timeopt {

TemporalSolver::TemporalSolver() = default;
TemporalSolver::~TemporalSolver() = default;
JerkRows TemporalSolver::jerk_rows() const { return JerkRows::kLinearized; }

namespace {

// True when the problem is feasible by construction: at rest at both ends (zero boundary
// velocities and accelerations), with limits that let the vehicle hover with room to spare
// (max_thrust above gravity, min_thrust below it; the other limits are positive). Then the same
// path taken slowly enough is a solution: velocity, acceleration and jerk shrink like the speed,
// its square and its cube, on every grid of two or more cells per piece and in every mode.
bool FeasibleAtRest(const TemporalProblem& p) {
  const TemporalBoundary& b = p.boundary;
  if (!b.start_velocity.isZero(0.0) || !b.end_velocity.isZero(0.0) || !b.start_acceleration.isZero(0.0) ||
      !b.end_acceleration.isZero(0.0)) {
    return false;
  }
  // One cell per piece cannot leave rest and reach it again (a grid too coarse, not the limits).
  if (p.cells_per_piece < 2) return false;
  const VehicleLimits& l = p.limits;
  if (l.max_thrust && !(*l.max_thrust > l.gravity)) return false;
  if (l.min_thrust && !(*l.min_thrust < l.gravity)) return false;
  return true;
}

// Units of the jerk-limited solve. Its rows mix b, b^(1/2) and b^(3/2) (the jerk), so their
// numbers span powers of the problem's units: a curve of 1e7 m at limits of 1e-4, or of 1 cm at
// 1e4, gave the conic solver (and Ipopt) values 1e20 apart, false verdicts and stalls. The problem
// is solved instead in units where the curve's size is 1 and the time is the longest that one
// limit alone imposes on it (length / speed, sqrt(length / acceleration), cbrt(length / jerk)):
// the binding limits then are of order 1 and the others larger. (The paper's and certified rows
// are solved as given: the structured path normalizes its rows, and their tests pin the refusal of
// coefficients whose squares overflow. Scaling them did not cure the property sweep's stalls on
// minimum-jerk rest ends either.) Not with lambda_a, which the jerk-limited mode refuses anyway.
struct ProblemUnits {
  double length = 1.0;  // metres
  double time = 1.0;    // seconds
};

ProblemUnits UnitsOf(const TemporalProblem& p) {
  ProblemUnits u;
  if (p.limits.max_acceleration_change) return u;
  // The size: the largest reach |f(s) - f(0)| <= sum_k |c_k| (k >= 1) of any piece on any axis.
  double length = 0.0;
  for (const PolynomialPiece& piece : p.curve.pieces()) {
    const auto& c = piece.coefficients();
    if (c.cols() > 1) length = std::max(length, c.rightCols(c.cols() - 1).cwiseAbs().rowwise().sum().maxCoeff());
  }
  if (!(length > 0.0) || !std::isfinite(length)) return u;
  double time = 0.0;
  const auto limit = [&](double value, double order) {
    if (std::isfinite(value) && value > 0.0) time = std::max(time, std::pow(length / value, 1.0 / order));
  };
  const VehicleLimits& l = p.limits;
  for (int a = 0; a < 3; ++a) {
    limit(l.max_velocity(a), 1.0);
    limit(l.max_acceleration(a), 2.0);
    if (l.max_jerk) limit((*l.max_jerk)(a), 3.0);
  }
  if (l.max_speed) limit(*l.max_speed, 1.0);
  if (l.max_acceleration_norm) limit(*l.max_acceleration_norm, 2.0);
  if (!(time > 0.0) || !std::isfinite(time)) return u;
  u.length = length;
  u.time = time;
  return u;
}

// The same problem in units `u` (lengths divided by u.length, times by u.time); false when a value
// would not stay finite and valid there.
bool InUnits(const TemporalProblem& p, const ProblemUnits& u, TemporalProblem* out) {
  TemporalProblem& q = *out;
  q = p;
  std::vector<PolynomialPiece> pieces;
  pieces.reserve(p.curve.pieces().size());
  for (const PolynomialPiece& piece : p.curve.pieces()) pieces.emplace_back(piece.coefficients() / u.length);
  q.curve = PiecewiseCurve(std::move(pieces));
  const double velocity = u.time / u.length, acceleration = velocity * u.time, jerk = acceleration * u.time;
  VehicleLimits& l = q.limits;
  l.max_velocity *= velocity;
  l.max_acceleration *= acceleration;
  if (l.max_jerk) *l.max_jerk *= jerk;
  if (l.max_speed) *l.max_speed *= velocity;
  if (l.max_acceleration_norm) *l.max_acceleration_norm *= acceleration;
  if (l.max_thrust) *l.max_thrust *= acceleration;
  if (l.min_thrust) *l.min_thrust *= acceleration;
  l.gravity *= acceleration;
  q.boundary.start_velocity *= velocity;
  q.boundary.end_velocity *= velocity;
  q.boundary.start_acceleration *= acceleration;
  q.boundary.end_acceleration *= acceleration;
  q.zero_tangent_tolerance /= u.length;
  // J = T + rho sum a^2 ds with a = sddot: T = time T', a = a' / time^2, so J = time (T' + rho'
  // sum a'^2 ds) with rho' = rho / time^5.
  q.rho = p.rho / std::pow(u.time, 5.0);
  try {
    q.Validate();
  } catch (const std::invalid_argument&) {
    return false;
  }
  return true;
}

// `solve` on the problem in its own units (ProblemUnits), the answer back in seconds. An invalid
// verdict comes from the problem as given; so does an infeasible verdict's message when the
// presolve (`discretize`, cheap) finds it, since those messages quote the user's numbers.
template <typename Solve, typename Discretize>
TemporalResult SolveInUnits(const TemporalProblem& problem, const Solve& solve, const Discretize& discretize) {
  const ProblemUnits u = UnitsOf(problem);
  TemporalProblem scaled;
  if ((u.length == 1.0 && u.time == 1.0) || !InUnits(problem, u, &scaled)) return solve(problem);
  TemporalResult result = solve(scaled);
  if (result.status == TemporalStatus::kInvalidInput) return solve(problem);
  if (result.status == TemporalStatus::kInfeasible) {
    try {
      const TemporalDiscretization d = discretize(problem);
      if (d.infeasible_reason) result.message = *d.infeasible_reason;
    } catch (const std::exception&) {
      return solve(problem);
    }
    return result;
  }
  result.total_time *= u.time;
  result.objective *= u.time;
  for (double& t : result.piece_durations) t *= u.time;
  for (double& t : result.scp_history) t *= u.time;
  if (result.status == TemporalStatus::kOptimal) result.profile = result.profile.TimeScaled(u.time);
  return result;
}

}  // namespace

TemporalResult TemporalSolver::Solve(const TemporalProblem& problem) {
  if (problem.limits.max_jerk) {
    // A piece too short for a jerk-limited profile in double precision: its answer could not be
    // trusted (rounding made the rows too tight, and answers 9% slow passed as optimal), so none.
    std::optional<std::string> too_short;
    try {
      problem.Validate();
      too_short = internal::JerkPieceTooShort(problem);
    } catch (const std::invalid_argument&) {
      // reported by the solve below
    }
    if (too_short) {
      TemporalResult refused;
      refused.status = TemporalStatus::kInvalidInput;
      refused.message = *too_short;
      refused.solver = ToString(backend());
      refused.jerk_limited = true;
      return refused;
    }
  }
  TemporalResult result =
      problem.limits.max_jerk
          ? SolveInUnits(
                problem, [this](const TemporalProblem& p) { return SolveJerkLimited(p); },
                [](const TemporalProblem& p) { return DiscretizeJerkLimited(p, JerkRows::kNone, nullptr); })
          : SolvePaperOrCertified(problem);
  if (result.status == TemporalStatus::kInfeasible && FeasibleAtRest(problem)) {
    // A certificate for a problem that has a solution by construction: the solver's rounding, not
    // the limits (seen on a 1e7 m curve at limits of 1e-4 in the jerk-limited mode).
    result.status = TemporalStatus::kNumericalError;
    result.message = "the solver reported no feasible time allocation (" + result.message +
                     "), but a rest-to-rest problem whose limits allow hovering always has one (the "
                     "same path, slowly enough): a numerical failure";
  }
  const bool fallback =
      problem.limits.max_jerk && jerk_ipopt_fallback_seconds() > 0.0 && !probing_start_ &&
      (result.status == TemporalStatus::kNumericalError || result.status == TemporalStatus::kIterationLimit);
  const std::int64_t fallback_bytes = fallback ? TemporalPeakBytes(problem, TemporalBackend::kIpopt) : 0;
  const bool fallback_fits = jerk_ipopt_fallback_memory() <= 0 || fallback_bytes <= jerk_ipopt_fallback_memory();
  if (fallback && !fallback_fits) {
    result.message += "; the Ipopt fallback was skipped: its exact rows would need about " +
                      std::to_string(fallback_bytes >> 20) + " MiB, above the memory budget of " +
                      std::to_string(jerk_ipopt_fallback_memory() >> 20) + " MiB";
  }
  if (fallback && fallback_fits) {
    // Bounded, so that a problem Ipopt cannot solve either ends with a status, not a wait.
    IpoptTemporalOptions fallback;
    fallback.max_solve_time_seconds = jerk_ipopt_fallback_seconds();
    TemporalResult exact = MakeIpoptTemporalSolver(fallback)->Solve(problem);
    exact.build_time_seconds += result.build_time_seconds;
    exact.solve_time_seconds += result.solve_time_seconds;
    exact.iterations += result.iterations;
    // Only an answer is taken: Ipopt's "infeasible" on the non-convex rows is a local verdict, not
    // a certificate.
    if (exact.status == TemporalStatus::kOptimal) {
      exact.message = "the conic solves failed (" + result.message + "); solved by Ipopt's exact jerk rows" +
                      (exact.message.empty() ? std::string() : ": " + exact.message);
      return exact;
    }
    result.message += "; Ipopt's exact jerk rows did not solve it either (" + exact.message + ")";
    result.build_time_seconds = exact.build_time_seconds;
    result.solve_time_seconds = exact.solve_time_seconds;
    result.iterations = exact.iterations;
  }
  // Rows that make no chain along the path (a jerk limit, lambda_a, the quadrotor's cones): the
  // nearest start state is found by bisection (RelaxStartState); a jerk-limited numerical failure
  // too. (With cones relax_boundary was silently ignored: the chain's reachability cannot run.)
  const bool scale_start =
      problem.relax_boundary &&
      (problem.limits.max_jerk || problem.limits.max_acceleration_change || problem.limits.HasNormLimits()) &&
      (problem.boundary.start_velocity.squaredNorm() > 0.0 || problem.boundary.start_acceleration.squaredNorm() > 0.0);
  if (scale_start && problem.limits.max_jerk && result.status == TemporalStatus::kNumericalError) {
    return RelaxStartState(problem, std::move(result));
  }
  if (result.status != TemporalStatus::kInfeasible) return result;
  // Why, and (asked for) the closest boundary speeds: only infeasible problems pay for this.
  std::optional<internal::RelaxedSpeeds> relaxed;
  result.infeasibility = internal::DiagnoseInfeasible(problem, result.message, &relaxed);
  if (!problem.relax_boundary) return result;
  if (!relaxed) return scale_start ? RelaxStartState(problem, std::move(result)) : result;
  TemporalProblem closest = problem;
  closest.relax_boundary = false;
  closest.boundary.start_velocity = problem.boundary.start_velocity * relaxed->start_factor;
  closest.boundary.end_velocity = problem.boundary.end_velocity * relaxed->end_factor;
  TemporalResult answer = Solve(closest);
  answer.build_time_seconds += result.build_time_seconds;
  answer.solve_time_seconds += result.solve_time_seconds;
  answer.iterations += result.iterations;
  if (answer.is_success()) {
    TemporalResult::BoundaryRelaxation relaxation;
    relaxation.start_speed_given = problem.boundary.start_velocity.norm();
    relaxation.start_speed = closest.boundary.start_velocity.norm();
    relaxation.end_speed_given = problem.boundary.end_velocity.norm();
    relaxation.end_speed = closest.boundary.end_velocity.norm();
    relaxation.start_scale =
        relaxation.start_speed_given > 0.0 ? relaxation.start_speed / relaxation.start_speed_given : 1.0;
    answer.boundary_relaxation = relaxation;
    answer.infeasibility = result.infeasibility;  // why the given boundaries could not be flown
    answer.message = "boundary relaxed: " + result.infeasibility->detail;
  }
  return answer;
}

namespace {
// The bisection of RelaxStartState: a vehicle tracking at its limits is usually a few percent
// over what a new curve allows, so the first try is 0.9; 0.01 is within a flight's 1% on speed.
// About 7 solves per search.
constexpr double kStartScaleFirstGuess = 0.9;
constexpr double kStartScaleTolerance = 0.01;
}  // namespace

TemporalResult TemporalSolver::RelaxStartState(const TemporalProblem& problem, TemporalResult failed) {
  const Eigen::Vector3d v0 = problem.boundary.start_velocity, a0 = problem.boundary.start_acceleration;
  const double speed = v0.norm();
  const Eigen::Vector3d along = speed > 0.0 ? Eigen::Vector3d(v0 / speed) : Eigen::Vector3d::Zero();
  const Eigen::Vector3d tangential = along * along.dot(a0);
  const bool braking = along.dot(a0) < 0.0;
  TemporalProblem scaled = problem;
  scaled.relax_boundary = false;
  struct Probing {
    bool& flag;
    explicit Probing(bool& f) : flag(f) { flag = true; }
    ~Probing() { flag = false; }
  } probing(probing_start_);
  double build = failed.build_time_seconds, solve = failed.solve_time_seconds;
  int iterations = failed.iterations;
  // The largest lambda, within kStartScaleTolerance, whose state solves: the velocity times lambda,
  // the acceleration times lambda^2 (keep_braking: only its part across the path). A status other
  // than optimal, infeasible or a numerical error (an iteration or time limit) ends the search.
  const auto search = [&](bool keep_braking, double* scale) {
    double feasible = 0.0, infeasible = 1.0;
    std::optional<TemporalResult> best;
    for (double lambda = kStartScaleFirstGuess; infeasible - feasible > kStartScaleTolerance;
         lambda = 0.5 * (feasible + infeasible)) {
      scaled.boundary.start_velocity = lambda * v0;
      scaled.boundary.start_acceleration = keep_braking
                                               ? Eigen::Vector3d(lambda * lambda * (a0 - tangential) + tangential)
                                               : Eigen::Vector3d(lambda * lambda * a0);
      TemporalResult attempt = Solve(scaled);
      build += attempt.build_time_seconds;
      solve += attempt.solve_time_seconds;
      iterations += attempt.iterations;
      if (attempt.status == TemporalStatus::kOptimal) {
        feasible = lambda;
        best = std::move(attempt);
      } else if (attempt.status == TemporalStatus::kInfeasible || attempt.status == TemporalStatus::kNumericalError) {
        infeasible = lambda;
      } else {
        break;
      }
    }
    *scale = feasible;
    return best;
  };
  // A braking start keeps its braking (lowering it would only lengthen the stop) when some lambda
  // allows that; otherwise the whole acceleration is scaled (at lambda = 0, rest).
  double scale = 0.0;
  bool kept = braking;
  std::optional<TemporalResult> best;
  if (braking) best = search(true, &scale);
  if (!best) {
    kept = false;
    best = search(false, &scale);
  }
  if (!best) {
    failed.build_time_seconds = build;
    failed.solve_time_seconds = solve;
    failed.iterations = iterations;
    return failed;
  }
  TemporalResult answer = std::move(*best);
  answer.build_time_seconds = build;
  answer.solve_time_seconds = solve;
  answer.iterations = iterations;
  TemporalResult::BoundaryRelaxation relaxation;
  relaxation.start_speed_given = speed;
  relaxation.start_speed = scale * speed;
  relaxation.end_speed_given = relaxation.end_speed = problem.boundary.end_velocity.norm();
  relaxation.start_scale = scale;
  relaxation.start_acceleration = kept ? "braking_kept" : "scaled";
  answer.boundary_relaxation = relaxation;
  answer.infeasibility = failed.infeasibility;  // why the given start could not be flown (if found)
  std::ostringstream message;
  message << "boundary relaxed: start state scaled by " << scale
          << (kept ? " (braking kept)" : " (acceleration by its square)") << ": "
          << (failed.infeasibility ? failed.infeasibility->detail : failed.message);
  answer.message = message.str();
  return answer;
}

TemporalResult TemporalSolver::SolvePaperOrCertified(const TemporalProblem& problem) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_since = [](Clock::time_point from) {
    return std::chrono::duration<double>(Clock::now() - from).count();
  };
  TemporalResult result;
  result.solver = ToString(backend());
  const Clock::time_point start = Clock::now();
  TemporalDiscretization d;
  try {
    d = Discretize(problem);  // validates the problem first
  } catch (const std::invalid_argument& e) {
    result.status = TemporalStatus::kInvalidInput;
    result.message = e.what();
    result.build_time_seconds = seconds_since(start);
    return result;
  }
  result.joints = d.joints;
  result.build_time_seconds = seconds_since(start);
  if (d.infeasible_reason) {
    result.status = TemporalStatus::kInfeasible;
    result.message = *d.infeasible_reason;
    return result;
  }
  const std::string name = result.solver;
  internal::MapSolveExceptions(name, &result, [&](bool* finishing) {
    std::vector<double> x;
    if (d.num_vars == 0) {
      // Every grid value is fixed: nothing to optimize, only to check.
      if (d.MaxViolation(x) > 0.0) {
        result.status = TemporalStatus::kInfeasible;
        result.message = "the fixed speeds violate a limit";
        return false;
      }
      *finishing = true;
      internal::FinishOptimalResult(problem, d, x, &result);
      return true;
    }
    SolveDiscretized(d, &result, &x);
    if (result.status != TemporalStatus::kOptimal) return false;
    if (static_cast<int>(x.size()) != d.num_vars) {
      result.status = TemporalStatus::kNumericalError;
      result.message = name + " backend: optimal without a solution of the right size";
      return false;
    }
    const std::string message = result.message;
    *finishing = true;
    internal::FinishOptimalResult(problem, d, x, &result);
    result.message = message;
    return true;
  });
  return result;
}

}  // namespace timeopt
