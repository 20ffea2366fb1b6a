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

#include "timeopt/core/enum_strings.h"
#include "banded_ipm.h"
#include "discretization_internal.h"
#include "infeasibility.h"
#include "solver_internal.h"
#include "timeopt/core/option_check.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

TemporalSolver::TemporalSolver() = default;
TemporalSolver::~TemporalSolver() = default;
JerkRows TemporalSolver::jerk_rows() const { return JerkRows::kLinearized; }

const char* ToString(TemporalStatus status) {
  switch (status) {
    case TemporalStatus::kOptimal:
      return "optimal";
    case TemporalStatus::kInfeasible:
      return "infeasible";
    case TemporalStatus::kIterationLimit:
      return "iteration_limit";
    case TemporalStatus::kNumericalError:
      return "numerical_error";
    case TemporalStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

bool FromString(const std::string& text, TemporalStatus* status) {
  return EnumFromString(text, kTemporalStatuses, status);
}

const char* ToString(TemporalBackend backend) {
  switch (backend) {
    case TemporalBackend::kSocp:
      return "socp";
    case TemporalBackend::kIpopt:
      return "ipopt";
  }
  return "unknown";
}

bool FromString(const std::string& text, TemporalBackend* backend) {
  return EnumFromString(text, kTemporalBackends, backend);
}

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

// The checks both backends' options share: a positive finite tolerance and an iteration limit of
// at least `min_iterations`.
bool ValidSolverOptions(double tolerance, int max_iterations, int min_iterations, std::string* error) {
  if (!std::isfinite(tolerance) || !(tolerance > 0.0)) {
    return internal::FailOption(error, "tolerance", "a positive finite number", tolerance);
  }
  if (max_iterations < min_iterations) {
    return internal::FailOption(error, "max_iterations", "an integer >= " + std::to_string(min_iterations),
                                max_iterations);
  }
  return true;
}

}  // namespace

bool SocpTemporalOptions::operator==(const SocpTemporalOptions& o) const {
  // A field added to the struct mostly changes its size (32 bytes on 64-bit machines): compare it
  // here too.
  static_assert(sizeof(void*) != 8 || sizeof(SocpTemporalOptions) == 32,
                "SocpTemporalOptions has a new field: compare it in operator==");
  return tolerance == o.tolerance && max_iterations == o.max_iterations && structured == o.structured &&
         jerk_ipopt_fallback_seconds == o.jerk_ipopt_fallback_seconds && max_memory_bytes == o.max_memory_bytes;
}

bool SocpTemporalOptions::IsValid(std::string* error) const {
  if (!ValidSolverOptions(tolerance, max_iterations, 1, error)) return false;
  if (!(max_memory_bytes >= 0)) {
    if (error) *error = "max_memory_bytes: expected a number >= 0, got " + std::to_string(max_memory_bytes);
    return false;
  }
  if (!(jerk_ipopt_fallback_seconds >= 0.0)) {
    if (error) {
      *error =
          "jerk_ipopt_fallback_seconds: expected a number >= 0, got " + std::to_string(jerk_ipopt_fallback_seconds);
    }
    return false;
  }
  return true;
}

bool IpoptTemporalOptions::IsValid(std::string* error) const {
  if (!ValidSolverOptions(tolerance, max_iterations, 0, error)) return false;
  if (!(max_solve_time_seconds > 0.0)) {
    if (error)
      *error =
          "max_solve_time_seconds: expected a positive number, got " + std::to_string(max_solve_time_seconds);
    return false;
  }
  return true;
}

std::int64_t TemporalPeakBytes(const TemporalProblem& problem, TemporalBackend backend) {
  // Bytes, from the measured peaks per cell rounded up (see the declaration): the process, then per
  // cell with the SOCP backend (paper and certified rows / jerk-limited) and with Ipopt (likewise).
  constexpr double kProcessBytes = 64.0 * (1 << 20);
  constexpr double kSocpCellBytes = 10e3, kSocpJerkCellBytes = 16e3;
  constexpr double kIpoptCellBytes = 5e3, kIpoptJerkCellBytes = 1e6;
  const bool jerk = problem.limits.max_jerk.has_value();
  const double per_cell = backend == TemporalBackend::kSocp ? (jerk ? kSocpJerkCellBytes : kSocpCellBytes)
                                                            : (jerk ? kIpoptJerkCellBytes : kIpoptCellBytes);
  const double cells = static_cast<double>(problem.curve.num_pieces()) * std::max(problem.cells_per_piece, 0);
  const double bytes = kProcessBytes + cells * per_cell;
  return bytes < 9e18 ? static_cast<std::int64_t>(bytes) : std::numeric_limits<std::int64_t>::max();
}

std::unique_ptr<TemporalSolver> MakeTemporalSolver(TemporalBackend backend) {
  switch (backend) {
    case TemporalBackend::kSocp:
      return MakeSocpTemporalSolver();
    case TemporalBackend::kIpopt:
      return MakeIpoptTemporalSolver();
  }
  throw std::invalid_argument("MakeTemporalSolver: unknown backend");
}

void CheckTemporalMemory(const TemporalProblem& problem, TemporalBackend backend, std::int64_t max_memory_bytes) {
  const std::int64_t peak = TemporalPeakBytes(problem, backend);
  if (max_memory_bytes > 0 && peak > max_memory_bytes) {
    throw std::invalid_argument("the problem's " + std::to_string(problem.curve.num_pieces()) + " x " +
                                std::to_string(problem.cells_per_piece) + " cells need about " +
                                std::to_string(peak >> 20) + " MiB with " + ToString(backend) +
                                (problem.limits.max_jerk ? " and a jerk limit" : "") + ", above the memory budget of " +
                                std::to_string(max_memory_bytes >> 20) + " MiB");
  }
}

std::unique_ptr<TemporalSolver> MakeBudgetedTemporalSolver(TemporalBackend backend, std::int64_t max_memory_bytes,
                                                           std::optional<double> ipopt_seconds) {
  if (backend == TemporalBackend::kSocp) {
    SocpTemporalOptions options;
    if (max_memory_bytes > 0) options.max_memory_bytes = max_memory_bytes;
    if (ipopt_seconds) options.jerk_ipopt_fallback_seconds = *ipopt_seconds;
    return MakeSocpTemporalSolver(options);
  }
  IpoptTemporalOptions options;
  if (ipopt_seconds) options.max_solve_time_seconds = *ipopt_seconds;
  return MakeIpoptTemporalSolver(options);
}

namespace {

// The dense feasibility check: largest |v_axis|/vmax_axis, |acc_axis|/amax_axis and (with a jerk
// limit) |jerk_axis|/jmax_axis along the exact trajectory, sampling every cell at
// `samples_per_cell` + 1 evenly spaced values of s.
void DenseLimitRatios(const TemporalProblem& problem, const TemporalProfile& profile, int samples_per_cell,
                      TemporalResult* result) {
  if (samples_per_cell < 1) throw std::invalid_argument("DenseLimitRatios: samples_per_cell < 1");
  double vr = 0.0, ar = 0.0, jr = 0.0;
  const int K = profile.cells_per_piece();
  const double ds = 1.0 / K;  // the cells of a profile without a jerk limit
  const Eigen::Vector3d inv_v = problem.limits.max_velocity.cwiseInverse();
  const Eigen::Vector3d inv_a = problem.limits.max_acceleration.cwiseInverse();
  const bool jerk = problem.limits.max_jerk.has_value();
  const Eigen::Vector3d inv_j =
      jerk ? Eigen::Vector3d(problem.limits.max_jerk->cwiseInverse()) : Eigen::Vector3d::Zero();
  // The quadrotor's limits at one sample (velocity, acceleration).
  const TemporalLimits& L = problem.limits;
  const bool norms = L.HasNormLimits();
  QuadrotorExtremes quadrotor;
  const auto quad = [&](const Eigen::Vector3d& vel, const Eigen::Vector3d& acc) {
    quadrotor.Note(vel, acc, L.gravity);
  };
  std::vector<TemporalProfile::Point> states(jerk ? static_cast<size_t>(samples_per_cell) + 1 : 0);
  for (int i = 0; i < profile.num_pieces(); ++i) {
    // The derivatives' coefficients once per piece, then Horner's rule per sample: finishing a
    // result at m = 10, K = 50 took 0.27 ms (of a 6.3 ms Solve) when the piece derived its
    // coefficients at every sample, 0.18 ms this way.
    const PolynomialPiece& piece = problem.curve.piece(i);
    const PolynomialPiece::Coefficients d1 = piece.Derivative(1).coefficients();
    const PolynomialPiece::Coefficients d2 = piece.Derivative(2).coefficients();
    const PolynomialPiece::Coefficients d3 =
        piece.degree() >= 3 ? piece.Derivative(3).coefficients() : PolynomialPiece::Coefficients::Zero(3, 1);
    const auto horner = [](const PolynomialPiece::Coefficients& c, double s) {
      Eigen::Vector3d v = c.col(c.cols() - 1);
      for (Eigen::Index q = c.cols() - 2; q >= 0; --q) v = v * s + c.col(q);
      return v;
    };
    for (int k = 0; k < K; ++k) {
      const double b0 = profile.b(i, k), b1 = profile.b(i, k + 1);
      const double a = jerk ? 0.0 : profile.a(i, k);
      const double start = jerk ? profile.CellStart(i, k) : 0.0, length = jerk ? profile.CellLength(i, k) : 0.0;
      // Each cell's own state at both of its ends: the jerk's left and right limits at a grid
      // point (AtS would evaluate the next cell at this cell's end), and no search for the cell.
      if (jerk) profile.InCellSamples(i, k, samples_per_cell, states.data());
      for (int j = 0; j <= samples_per_cell; ++j) {
        const double u = static_cast<double>(j) / samples_per_cell;
        const double s = jerk ? start + u * length : (k + u) * ds;
        const Eigen::Vector3d f1 = horner(d1, s), f2 = horner(d2, s);
        if (!jerk) {
          // b is linear in s on the cell, and sddot = a constant.
          const double sdot = std::sqrt(std::max(0.0, b0 + (b1 - b0) * u));
          const Eigen::Vector3d velocity = ChainVelocity(f1, sdot), acceleration = ChainAcceleration(f1, f2, sdot, a);
          vr = std::max(vr, velocity.cwiseAbs().cwiseProduct(inv_v).maxCoeff());
          ar = std::max(ar, acceleration.cwiseAbs().cwiseProduct(inv_a).maxCoeff());
          if (norms) quad(velocity, acceleration);
          continue;
        }
        const TemporalProfile::Point& p = states[static_cast<size_t>(j)];
        const Eigen::Vector3d f3 = horner(d3, s);
        const Eigen::Vector3d velocity = ChainVelocity(f1, p.sdot);
        const Eigen::Vector3d acceleration = ChainAcceleration(f1, f2, p.sdot, p.sddot);
        vr = std::max(vr, velocity.cwiseAbs().cwiseProduct(inv_v).maxCoeff());
        ar = std::max(ar, acceleration.cwiseAbs().cwiseProduct(inv_a).maxCoeff());
        if (norms) quad(velocity, acceleration);
        const Eigen::Vector3d jerk_vector = ChainJerk(f1, f2, f3, p.sdot, p.sddot, p.sdddot);
        jr = std::max(jr, jerk_vector.cwiseAbs().cwiseProduct(inv_j).maxCoeff());
      }
    }
  }
  result->max_velocity_ratio = vr;
  result->max_acceleration_ratio = ar;
  quadrotor.WriteRatios(L, result);
  result->max_jerk_ratio = jr;
}

}  // namespace

namespace internal {

// Fills total_time, objective, piece_durations, profile and the dense feasibility ratios of an
// optimal result from the discretization's free values x (the skeleton's finishing step).
void FinishOptimalResult(const TemporalProblem& problem, const TemporalDiscretization& d, const std::vector<double>& x,
                         TemporalResult* result) {
  const int K = d.cells_per_piece;  // half cells in the jerk-limited mode
  // b at every grid value (interior-point iterates may sit a rounding error below zero); a
  // jerk-limited rest cell's middle value is q at its rest point in d, b at its middle in the profile.
  std::vector<double> flat(d.grid.size());
  for (size_t g = 0; g < d.grid.size(); ++g) flat[g] = std::max(0.0, d.GridB(static_cast<int>(g), x));
  if (d.jerk_limited) RestAlphaToMiddles(d, &flat);
  std::vector<std::vector<double>> b(static_cast<size_t>(d.num_pieces));
  for (int i = 0; i < d.num_pieces; ++i) {
    b[static_cast<size_t>(i)].assign(flat.begin() + d.GridIndex(i, 0), flat.begin() + d.GridIndex(i, K) + 1);
  }
  if (d.jerk_limited) {
    const int full = K / 2;
    std::vector<std::vector<CellShape>> shapes(static_cast<size_t>(d.num_pieces));
    for (int i = 0; i < d.num_pieces; ++i) {
      shapes[i].assign(d.shapes.begin() + i * full, d.shapes.begin() + (i + 1) * full);
    }
    result->profile = TemporalProfile::JerkLimited(std::move(b), std::move(shapes), d.cell_edges);
  } else {
    result->profile = TemporalProfile(std::move(b));
  }
  result->total_time = result->profile.total_time();
  result->piece_durations = result->profile.piece_durations();
  // The objective with the profile's exact time (the discretization's time of a jerk-limited cell
  // is an approximation; for the paper's cells the two agree).
  double time = 0.0;
  const double objective = d.Objective(x, &time);
  result->objective = d.jerk_limited ? objective - time + result->total_time : objective;
  result->status = TemporalStatus::kOptimal;
  // 32 samples per cell: the polynomials on a cell have degree <= 2n - 1, so a 1/32 spacing
  // resolves their extrema well below the cell's size.
  DenseLimitRatios(problem, result->profile, 32, result);
}

}  // namespace internal

TemporalResult TemporalSolver::Solve(const TemporalProblem& problem) {
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
