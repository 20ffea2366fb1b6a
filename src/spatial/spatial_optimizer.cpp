#include "timeopt/spatial/spatial_optimizer.h"

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include <ceres/ceres.h>

#include "spatial_costs.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/core/option_check.h"

namespace timeopt {
namespace {

using spatial_internal::kJointSize;

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }
bool NonNegative(double v) { return std::isfinite(v) && v >= 0.0; }

// Records cost and time of every iteration for the convergence figure.
class RecordingCallback final : public ceres::IterationCallback {
 public:
  explicit RecordingCallback(std::vector<SpatialIteration>* out) : out_(out) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    SpatialIteration it;
    it.iteration = summary.iteration;
    // Ceres minimizes 1/2 sum r^2; our objective is sum r^2. Its `cost` is the tried point's.
    it.step_cost = 2.0 * summary.cost;
    it.step_accepted = summary.iteration == 0 || summary.step_is_successful;
    it.cost = it.step_accepted || out_->empty() ? it.step_cost : out_->back().cost;
    it.time_seconds = summary.cumulative_time_in_seconds;
    out_->push_back(it);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::vector<SpatialIteration>* out_;
};

double GroupCost(ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& blocks) {
  if (blocks.empty()) return 0.0;
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = blocks;
  evaluate.apply_loss_function = false;
  double cost = 0.0;
  problem.Evaluate(evaluate, &cost, nullptr, nullptr, nullptr);
  return 2.0 * cost;
}

}  // namespace

const char* ToString(SpatialFormulation formulation) {
  return formulation == SpatialFormulation::kSpatial ? "spatial" : "time_coupled";
}

bool FromString(const std::string& text, SpatialFormulation* formulation) {
  return EnumFromString(text, kSpatialFormulations, formulation);
}

const char* ToString(SpatialParameterization parameterization) {
  switch (parameterization) {
    case SpatialParameterization::kUniform:
      return "uniform";
    case SpatialParameterization::kChordal:
      return "chordal";
    case SpatialParameterization::kCentripetal:
      return "centripetal";
  }
  return "unknown";
}

bool FromString(const std::string& text, SpatialParameterization* parameterization) {
  return EnumFromString(text, kSpatialParameterizations, parameterization);
}

const char* ToString(SpatialStatus status) {
  switch (status) {
    case SpatialStatus::kConverged:
      return "converged";
    case SpatialStatus::kIterationLimit:
      return "iteration_limit";
    case SpatialStatus::kInvalidInput:
      return "invalid_input";
    case SpatialStatus::kFailure:
      return "failure";
  }
  return "unknown";
}

bool FromString(const std::string& text, SpatialStatus* status) {
  return EnumFromString(text, kSpatialStatuses, status);
}

bool SpatialOptimizerOptions::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& field, const std::string& expected, double got) {
    return internal::FailOption(error, field, expected, got);
  };
  // Weights are relative to each other; above kMaxSpatialWeight a term's squared residuals leave
  // double precision's useful range (the sum of squares overflows, or swamps the other terms by
  // more than 16 digits), and the optimizer returns non-finite curves.
  const auto weight = [&](const char* name, double value) {
    return NonNegative(value) && value <= kMaxSpatialWeight ? true : fail(name, "a number in [0, 1e9]", value);
  };
  if (!weight("smoothness_weight", smoothness_weight)) return false;
  if (!weight("collision_weight", collision_weight)) return false;
  if (!weight("length_weight", length_weight)) return false;
  if (!std::isfinite(safe_distance)) return fail("safe_distance", "a finite number", safe_distance);
  if (!Positive(penalty_decay_length)) return fail("penalty_decay_length", "a positive number", penalty_decay_length);
  if (collision_samples_per_piece < 1 || collision_samples_per_piece > 64) {
    return fail("collision_samples_per_piece", "an integer in [1, 64]", collision_samples_per_piece);
  }
  if (!Positive(tangent_epsilon)) return fail("tangent_epsilon", "a positive number", tangent_epsilon);
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(start_tangent(a))) return fail("start_tangent", "finite numbers", start_tangent(a));
    if (!std::isfinite(start_curvature(a))) return fail("start_curvature", "finite numbers", start_curvature(a));
  }
  if (max_iterations < 0) return fail("max_iterations", "an integer >= 0", max_iterations);
  if (!Positive(max_solver_time_seconds)) {
    return fail("max_solver_time_seconds", "a positive number", max_solver_time_seconds);
  }
  if (!NonNegative(function_tolerance)) return fail("function_tolerance", "a number >= 0", function_tolerance);
  if (!NonNegative(gradient_tolerance)) return fail("gradient_tolerance", "a number >= 0", gradient_tolerance);
  if (!NonNegative(parameter_tolerance)) return fail("parameter_tolerance", "a number >= 0", parameter_tolerance);
  if (formulation == SpatialFormulation::kTimeCoupled) {
    if (!Positive(heuristic_speed)) return fail("heuristic_speed", "a positive number", heuristic_speed);
    if (!Positive(min_piece_duration)) return fail("min_piece_duration", "a positive number", min_piece_duration);
    if (!Positive(max_velocity)) return fail("max_velocity", "a positive number", max_velocity);
    if (!Positive(max_acceleration)) return fail("max_acceleration", "a positive number", max_acceleration);
    if (!weight("dynamic_weight", dynamic_weight)) return false;
    if (dynamic_samples_per_piece < 1) {
      return fail("dynamic_samples_per_piece", "an integer >= 1", dynamic_samples_per_piece);
    }
  }
  return true;
}

namespace {

// Piece durations: in s for the spatial formulation (1, or by chord; mean 1), heuristic times in
// the time-coupled baseline.
std::vector<double> PieceDurations(const Waypoints& waypoints, const SpatialOptimizerOptions& options) {
  const int m = static_cast<int>(waypoints.cols()) - 1;
  std::vector<double> durations(m, 1.0);
  if (options.formulation == SpatialFormulation::kTimeCoupled) {
    for (int i = 0; i < m; ++i) {
      const double chord = (waypoints.col(i + 1) - waypoints.col(i)).norm();
      durations[i] = std::max(chord / options.heuristic_speed, options.min_piece_duration);
    }
  } else if (options.parameterization != SpatialParameterization::kUniform) {
    double sum = 0.0;
    for (int i = 0; i < m; ++i) {
      const double chord = (waypoints.col(i + 1) - waypoints.col(i)).norm();
      durations[i] = options.parameterization == SpatialParameterization::kChordal ? chord : std::sqrt(chord);
      sum += durations[i];
    }
    // Coincident joints (a zero chord) keep a small length: 1% of the mean.
    const double mean = sum > 0.0 ? sum / m : 1.0;
    for (double& d : durations) d = std::max(d / mean, 0.01);
  }
  return durations;
}

// Initial joint states (kJointSize values per joint: position, first and second derivative) from
// the minimum-jerk spline in s (rest to rest, or from the given start derivatives).
std::vector<double> InitialJoints(const Waypoints& waypoints, const SpatialOptimizerOptions& options,
                                  const std::vector<double>& durations) {
  const int m = static_cast<int>(waypoints.cols()) - 1;
  const bool coupled = options.formulation == SpatialFormulation::kTimeCoupled;
  const bool scaled = coupled || options.parameterization != SpatialParameterization::kUniform;
  EndDerivatives ends = EndDerivatives::RestToRest();
  if (!coupled) {
    ends.start_velocity = options.start_tangent;
    ends.start_acceleration = options.start_curvature;
  }
  const PiecewiseCurve initial = MinimumJerkSpline(waypoints, ends);
  std::vector<double> joints(static_cast<size_t>(kJointSize) * (m + 1), 0.0);
  for (int j = 0; j <= m; ++j) {
    double* x = &joints[static_cast<size_t>(kJointSize) * j];
    Eigen::Map<Eigen::Vector3d> position(x);
    position = waypoints.col(j);
    if (j == 0) {  // the fixed start: at rest, or in motion
      // Given per unit s of the first output piece (spatial) or per second (baseline); the joints
      // hold derivatives per unit of the optimized parameter, in which that piece spans durations[0].
      const double d0 = coupled ? 1.0 : durations[0];
      Eigen::Map<Eigen::Vector3d>(x + 3, 3) = options.start_tangent / d0;
      Eigen::Map<Eigen::Vector3d>(x + 6, 3) = options.start_curvature / (d0 * d0);
      continue;
    }
    if (j == m) continue;  // rest at the fixed goal
    Eigen::Vector3d d1 = initial.Evaluate(j, 0.0, 1), d2 = initial.Evaluate(j, 0.0, 2);
    if (scaled) {
      const double t = 0.5 * (durations[j - 1] + durations[j]);
      d1 /= t;
      d2 /= t * t;
    }
    Eigen::Map<Eigen::Vector3d>(x + 3, 3) = d1;
    Eigen::Map<Eigen::Vector3d>(x + 6, 3) = d2;
  }
  return joints;
}

// The residual blocks of each cost term, for the cost breakdown.
struct CostGroups {
  std::vector<ceres::ResidualBlockId> smooth, collision, length, dynamic;

  SpatialCostBreakdown Breakdown(ceres::Problem& problem) const {
    SpatialCostBreakdown b;
    b.smoothness = GroupCost(problem, smooth);
    b.collision = GroupCost(problem, collision);
    b.length = GroupCost(problem, length);
    b.dynamic = GroupCost(problem, dynamic);
    return b;
  }
};

// Every piece's cost terms over its two joints; the end joints are held constant.
CostGroups AddCosts(const DistanceField& field, const SpatialOptimizerOptions& options,
                    const std::vector<double>& durations, std::vector<double>* joints, ceres::Problem* problem) {
  const int m = static_cast<int>(durations.size());
  const bool coupled = options.formulation == SpatialFormulation::kTimeCoupled;
  const auto& hermite = spatial_internal::QuinticHermite::Get();
  const Eigen::MatrixXd jerk_factor = hermite.Factor(3);
  const Eigen::MatrixXd length_factor = hermite.Factor(1);
  spatial_internal::CollisionPenalty penalty;
  penalty.safe_distance = options.safe_distance;
  penalty.decay_length = options.penalty_decay_length;
  CostGroups groups;
  for (int i = 0; i < m; ++i) {
    double* x0 = &(*joints)[static_cast<size_t>(kJointSize) * i];
    double* x1 = x0 + kJointSize;
    const double t = durations[i];
    const Eigen::Matrix<double, 6, 1> scale = spatial_internal::PieceScale(t);
    // In time: integral_0^T |d3p/dt3|^2 dt = J_s / T^5 and integral_0^T |dp/dt|^2 dt = L_s / T.
    if (options.smoothness_weight > 0.0) {
      groups.smooth.push_back(problem->AddResidualBlock(
          new spatial_internal::QuadraticFormCost(jerk_factor, scale, options.smoothness_weight / std::pow(t, 5)),
          nullptr, x0, x1));
    }
    if (options.length_weight > 0.0) {
      groups.length.push_back(problem->AddResidualBlock(
          new spatial_internal::QuadraticFormCost(length_factor, scale, options.length_weight / t), nullptr, x0, x1));
    }
    if (options.collision_weight > 0.0) {
      groups.collision.push_back(problem->AddResidualBlock(
          new spatial_internal::CollisionCost(&field, penalty, options.collision_samples_per_piece, scale,
                                              options.collision_weight, options.tangent_epsilon),
          nullptr, x0, x1));
    }
    if (coupled && options.dynamic_weight > 0.0) {
      groups.dynamic.push_back(problem->AddResidualBlock(
          new spatial_internal::DynamicPenaltyCost(t, options.max_velocity, options.max_acceleration,
                                                   options.dynamic_samples_per_piece, options.dynamic_weight),
          nullptr, x0, x1));
    }
  }
  for (int j = 0; j <= m; ++j) {
    double* x = &(*joints)[static_cast<size_t>(kJointSize) * j];
    if (!problem->HasParameterBlock(x)) problem->AddParameterBlock(x, kJointSize);
  }
  problem->SetParameterBlockConstant(joints->data());
  problem->SetParameterBlockConstant(&(*joints)[static_cast<size_t>(kJointSize) * m]);
  return groups;
}

// Levenberg-Marquardt on the problem; sets result's status, message and iterations.
void Minimize(const SpatialOptimizerOptions& options, ceres::Problem* problem, SpatialResult* result) {
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type =
      options.linear_solver == SpatialLinearSolver::kDenseQr ? ceres::DENSE_QR : ceres::SPARSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.max_solver_time_in_seconds = options.max_solver_time_seconds;
  solver.function_tolerance = options.function_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  RecordingCallback callback(&result->iterations);
  solver.callbacks.push_back(&callback);
  std::string solver_error;
  if (!solver.IsValid(&solver_error)) {
    result->status = SpatialStatus::kInvalidInput;
    result->message = "ceres options: " + solver_error;
    return;
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem, &summary);
  switch (summary.termination_type) {
    case ceres::CONVERGENCE:
    case ceres::USER_SUCCESS:
      result->status = SpatialStatus::kConverged;
      break;
    case ceres::NO_CONVERGENCE:
      result->status = SpatialStatus::kIterationLimit;
      break;
    default:
      result->status = SpatialStatus::kFailure;
      break;
  }
  result->message = summary.message;
  if (!summary.IsSolutionUsable()) result->status = SpatialStatus::kFailure;
}

// The curve of the joint states: one quintic Hermite piece per pair of joints.
PiecewiseCurve CurveFromJoints(const std::vector<double>& joints, const std::vector<double>& durations) {
  const auto& hermite = spatial_internal::QuinticHermite::Get();
  const int m = static_cast<int>(durations.size());
  std::vector<PolynomialPiece> pieces;
  pieces.reserve(m);
  for (int i = 0; i < m; ++i) {
    const double* x0 = &joints[static_cast<size_t>(kJointSize) * i];
    const Eigen::Matrix<double, 3, 6> q =
        spatial_internal::PieceData(x0, x0 + kJointSize, spatial_internal::PieceScale(durations[i]));
    pieces.emplace_back(PolynomialPiece::Coefficients(q * hermite.monomials().transpose()));
  }
  return PiecewiseCurve(std::move(pieces));
}

}  // namespace

SpatialResult OptimizeSpatialCurve(const DistanceField& field, const Waypoints& waypoints,
                                   const SpatialOptimizerOptions& options) {
  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  SpatialResult result;
  std::string error;
  if (!options.IsValid(&error)) {
    result.status = SpatialStatus::kInvalidInput;
    result.message = "options." + error;
    return result;
  }
  if (waypoints.cols() < 2 || !waypoints.allFinite()) {
    result.status = SpatialStatus::kInvalidInput;
    std::ostringstream s;
    s << "waypoints: expected at least 2 finite columns, got " << waypoints.cols();
    if (waypoints.cols() >= 2) s << " with a non-finite value";
    result.message = s.str();
    return result;
  }
  const int m = static_cast<int>(waypoints.cols()) - 1;
  const std::vector<double> durations = PieceDurations(waypoints, options);
  if (options.formulation == SpatialFormulation::kTimeCoupled) result.durations = durations;
  std::vector<double> joints = InitialJoints(waypoints, options, durations);

  ceres::Problem problem;
  const CostGroups groups = AddCosts(field, options, durations, &joints, &problem);
  result.initial_cost = groups.Breakdown(problem);
  if (!std::isfinite(result.initial_cost.total())) {
    result.status = SpatialStatus::kFailure;
    result.message = "the initial cost is not finite";
    return result;
  }

  if (m >= 2 && problem.NumResidualBlocks() > 0) {
    Minimize(options, &problem, &result);
    if (result.status == SpatialStatus::kInvalidInput) return result;
  } else {
    // One piece between fixed end states: nothing to optimize.
    result.status = SpatialStatus::kConverged;
    result.message = "no free joint";
    result.iterations.push_back({0, result.initial_cost.total(), result.initial_cost.total(), 0.0, true});
  }
  if (result.status == SpatialStatus::kFailure) {
    result.solve_time_seconds = std::chrono::duration<double>(Clock::now() - started).count();
    return result;
  }
  result.final_cost = groups.Breakdown(problem);
  result.curve = CurveFromJoints(joints, durations);
  result.solve_time_seconds = std::chrono::duration<double>(Clock::now() - started).count();
  for (int i = 0; i < result.curve.num_pieces(); ++i) {
    if (!result.curve.piece(i).coefficients().allFinite()) {
      result.status = SpatialStatus::kFailure;
      result.message = "the optimized curve is not finite (piece " + std::to_string(i) + ")";
      break;
    }
  }
  return result;
}

}  // namespace timeopt
