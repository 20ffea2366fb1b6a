#include "timeopt/planner/planner.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <limits>
#include <sstream>
#include <vector>

#include "timeopt/core/enum_strings.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/core/option_check.h"

namespace timeopt {
namespace {

using Clock = std::chrono::steady_clock;

// Metres: a goal this close to the start is the start.
constexpr double kSamePoint = 1e-6;
// The most pieces a plan's curve may have (its spatial and temporal stages grow with them; the
// default plan has 22).
constexpr double kMaxPlanPieces = 1e4;

// The parts of a segment of `length` metres at most max_length long each (as a double: counted
// before any is made, and Plan refuses counts above kMaxPlanPieces).
double SegmentParts(double length, double max_length) { return std::max(1.0, std::ceil(length / max_length)); }

// PlanResult's min_interior_speed and min_curvature_radius (see planner.h): on a 10 ms grid more
// than 1 s from either end, the speed and |v|^3 / |v x a| (the curve's radius of curvature). At
// most kQualitySamples points: a flight of 2e7 s (limits of 1e-6) took 2e9 of them, a hang.
constexpr double kQualitySamples = 1e6;
void CurveQuality(PlanResult* result) {
  const Trajectory trajectory(result->curve, result->temporal.profile);
  const double T = trajectory.duration();
  double slowest = std::numeric_limits<double>::infinity(), radius = std::numeric_limits<double>::infinity();
  const double span = T - 2.0;
  const double step = std::max(0.01, span / kQualitySamples);
  const long count = span >= 0.0 ? static_cast<long>(std::floor(span / step)) : -1;
  for (long n = 0; n <= count; ++n) {
    const double t = 1.0 + n * step;
    const TrajectoryState state = trajectory.Evaluate(t);
    const double speed = state.velocity.norm();
    slowest = std::min(slowest, speed);
    // Rounding leaves |v x a| ~ 1e-16 |v||a| on a straight line: no bend below 1e-12 of it.
    const double bend = state.velocity.cross(state.acceleration).norm();
    if (bend > 1e-12 * speed * state.acceleration.norm()) radius = std::min(radius, speed * speed * speed / bend);
  }
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  result->min_interior_speed = std::isfinite(slowest) ? slowest : kNaN;
  result->min_curvature_radius = std::isfinite(radius) ? radius : kNaN;
}

double SecondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

PlanStatus FromSearch(PathSearchStatus status) {
  switch (status) {
    case PathSearchStatus::kSuccess:
      return PlanStatus::kSuccess;
    case PathSearchStatus::kInvalidInput:
      return PlanStatus::kInvalidInput;
    case PathSearchStatus::kStartOutsideMap:
      return PlanStatus::kStartOutsideMap;
    case PathSearchStatus::kGoalOutsideMap:
      return PlanStatus::kGoalOutsideMap;
    case PathSearchStatus::kStartInCollision:
      return PlanStatus::kStartInCollision;
    case PathSearchStatus::kGoalInCollision:
      return PlanStatus::kGoalInCollision;
    case PathSearchStatus::kUnreachable:
      return PlanStatus::kUnreachable;
    case PathSearchStatus::kNodeLimit:
      return PlanStatus::kSearchLimit;
  }
  return PlanStatus::kInvalidInput;
}

}  // namespace

const char* ToString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kSuccess:
      return "success";
    case PlanStatus::kInvalidInput:
      return "invalid_input";
    case PlanStatus::kStartOutsideMap:
      return "start_outside_map";
    case PlanStatus::kGoalOutsideMap:
      return "goal_outside_map";
    case PlanStatus::kStartInCollision:
      return "start_in_collision";
    case PlanStatus::kGoalInCollision:
      return "goal_in_collision";
    case PlanStatus::kUnreachable:
      return "unreachable";
    case PlanStatus::kSearchLimit:
      return "search_limit";
    case PlanStatus::kCollision:
      return "collision";
    case PlanStatus::kSpatialFailure:
      return "spatial_failure";
    case PlanStatus::kTemporalInfeasible:
      return "temporal_infeasible";
    case PlanStatus::kTemporalFailure:
      return "temporal_failure";
  }
  return "unknown";
}

bool FromString(const std::string& text, PlanStatus* status) { return EnumFromString(text, kPlanStatuses, status); }

bool PlannerOptions::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& field, const std::string& expected, double got) {
    return internal::FailOption(error, field, expected, got);
  };
  if (!std::isfinite(robot_radius) || robot_radius < 0.0) {
    return fail("robot_radius", "a finite number >= 0 (metres)", robot_radius);
  }
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(start_velocity(a))) return fail("start_velocity", "finite numbers (m/s)", start_velocity(a));
    if (!std::isfinite(start_acceleration(a))) {
      return fail("start_acceleration", "finite numbers (m/s^2)", start_acceleration(a));
    }
  }
  if (!std::isfinite(safety_margin) || safety_margin <= 0.0) {
    return fail("safety_margin", "a positive number (metres)", safety_margin);
  }
  if (!std::isfinite(clearance_check_margin) || clearance_check_margin < 0.0) {
    return fail("clearance_check_margin", "a finite number >= 0 (metres)", clearance_check_margin);
  }
  if (!std::isfinite(clearance_check_step) || clearance_check_step <= 0.0) {
    return fail("clearance_check_step", "a positive number (metres)", clearance_check_step);
  }
  if (!std::isfinite(max_segment_length) || max_segment_length <= 0.0) {
    return fail("max_segment_length", "a positive number (metres)", max_segment_length);
  }
  if (max_attempts < 1) return fail("max_attempts", "an integer >= 1", max_attempts);
  if (!std::isfinite(retry_collision_weight_factor) || retry_collision_weight_factor < 1.0) {
    return fail("retry_collision_weight_factor", "a finite number >= 1", retry_collision_weight_factor);
  }
  if (temporal_cells_per_piece < 1) {
    return fail("temporal_cells_per_piece", "an integer >= 1", temporal_cells_per_piece);
  }
  if (limits.max_jerk && temporal_cells_per_piece < kMinJerkLimitedCellsPerPiece) {
    return fail("temporal_cells_per_piece", "an integer >= 3 with a jerk limit", temporal_cells_per_piece);
  }
  if (!std::isfinite(rho) || rho < 0.0) return fail("rho", "a finite number >= 0", rho);
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(limits.max_velocity(a)) || limits.max_velocity(a) <= 0.0) {
      return fail("limits.max_velocity[" + std::to_string(a) + "]", "a positive number (m/s)", limits.max_velocity(a));
    }
    if (!std::isfinite(limits.max_acceleration(a)) || limits.max_acceleration(a) <= 0.0) {
      return fail("limits.max_acceleration[" + std::to_string(a) + "]", "a positive number (m/s^2)",
                  limits.max_acceleration(a));
    }
  }
  if (limits.max_acceleration_change.has_value() &&
      (!std::isfinite(*limits.max_acceleration_change) || *limits.max_acceleration_change <= 0.0)) {
    return fail("limits.max_acceleration_change", "a positive number (m/s^2 per cell)",
                *limits.max_acceleration_change);
  }
  std::string sub;
  if (!socp.IsValid(&sub)) {
    if (error != nullptr) *error = "socp." + sub;
    return false;
  }
  if (!search.IsValid(&sub)) {
    if (error != nullptr) *error = "search." + sub;
    return false;
  }
  if (!spatial.IsValid(&sub)) {
    if (error != nullptr) *error = "spatial." + sub;
    return false;
  }
  return true;
}

namespace {

// Samples of a piece at chord steps of at most `step` (polygon length at 16 samples, +25%).
// The length of the 16-chord polyline through the piece, metres.
double PolylineLength(const PolynomialPiece& piece) {
  double length = 0.0;
  Eigen::Vector3d previous = piece.Evaluate(0.0);
  for (int k = 1; k <= 16; ++k) {
    const Eigen::Vector3d p = piece.Evaluate(k / 16.0);
    length += (p - previous).norm();
    previous = p;
  }
  return length;
}

// Samples the piece at most `step` apart along its chords (Plan checks first that its length is
// bounded by the field's size).
void SamplePiece(const PolynomialPiece& piece, double step, Eigen::Matrix3Xd* points) {
  const double length = PolylineLength(piece);
  const int n = std::max(16, static_cast<int>(std::ceil(1.25 * length / step)));
  points->resize(3, n + 1);
  for (int k = 0; k <= n; ++k) points->col(k) = piece.Evaluate(static_cast<double>(k) / n);
}

}  // namespace

double VoxelClearance(const Esdf& esdf, const Eigen::Vector3d& point, double reach) {
  const double r = esdf.resolution();
  const VoxelBox& box = esdf.box();
  const Eigen::Vector3i lo = ((point.array() - reach) / r).floor().cast<int>().max(box.min.array()).matrix();
  const Eigen::Vector3i hi =
      ((point.array() + reach) / r).floor().cast<int>().min((box.end() - Eigen::Vector3i::Ones()).array()).matrix();
  double best = reach;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3i index(x, y, z);
        if (esdf.VoxelDistance(index) >= 0.0) continue;  // free voxel
        const Eigen::Vector3d corner = index.cast<double>() * r;
        const Eigen::Vector3d nearest = point.cwiseMax(corner).cwiseMin(corner + Eigen::Vector3d::Constant(r));
        best = std::min(best, (point - nearest).norm());
      }
    }
  }
  return best;
}

double MinClearance(const DistanceField& field, const PiecewiseCurve& curve, double step) {
  double smallest = std::numeric_limits<double>::infinity();
  Eigen::Matrix3Xd points;
  Eigen::VectorXd distances;
  for (int i = 0; i < curve.num_pieces(); ++i) {
    SamplePiece(curve.piece(i), step, &points);
    field.Distances(points, &distances, nullptr);
    smallest = std::min(smallest, distances.minCoeff());
  }
  return smallest;
}

double MinVoxelClearance(const Esdf& esdf, const PiecewiseCurve& curve, double step, double exact_below) {
  double smallest = std::numeric_limits<double>::infinity();
  Eigen::Matrix3Xd points;
  Eigen::VectorXd distances;
  for (int i = 0; i < curve.num_pieces(); ++i) {
    SamplePiece(curve.piece(i), step, &points);
    esdf.Distances(points, &distances, nullptr);
    for (Eigen::Index k = 0; k < points.cols(); ++k) {
      double d = distances(k);
      if (d < exact_below) d = VoxelClearance(esdf, points.col(k), exact_below);
      smallest = std::min(smallest, d);
    }
  }
  return smallest;
}

Waypoints SplitSegments(const Waypoints& waypoints, double max_length) {
  std::vector<Eigen::Vector3d> out;
  for (Eigen::Index i = 0; i + 1 < waypoints.cols(); ++i) {
    const Eigen::Vector3d a = waypoints.col(i), b = waypoints.col(i + 1);
    const int parts = static_cast<int>(SegmentParts((b - a).norm(), max_length));
    for (int k = 0; k < parts; ++k) out.push_back(a + (b - a) * (static_cast<double>(k) / parts));
  }
  if (waypoints.cols() > 0) out.push_back(waypoints.col(waypoints.cols() - 1));
  Waypoints result(3, static_cast<Eigen::Index>(out.size()));
  for (size_t k = 0; k < out.size(); ++k) result.col(static_cast<Eigen::Index>(k)) = out[k];
  return result;
}

namespace {

// Reports a stage to options.on_stage, if set.
void Report(const PlannerOptions& options, const char* stage, double seconds, const std::string& outcome) {
  if (options.on_stage) options.on_stage(stage, seconds, outcome);
}

// The start state the plan flies from. A vehicle tracking at its limits overshoots them by a
// fraction of a percent (the flight criterion allows 1%): a start state a little over them is
// scaled onto them, or no profile could start there. More than 1% over is taken as given (and the
// temporal stage says why it cannot be flown, or relaxes it).
struct StartState {
  bool moving = false;
  Eigen::Vector3d velocity, acceleration;
};
StartState StartOnLimits(const PlannerOptions& options) {
  const auto onto_limits = [](const Eigen::Vector3d& value, const Eigen::Vector3d& per_axis,
                              const std::optional<double>& norm) {
    double factor = 1.0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(value(a)) > per_axis(a)) factor = std::min(factor, per_axis(a) / std::abs(value(a)));
    }
    if (norm && value.norm() > *norm) factor = std::min(factor, *norm / value.norm());
    return factor >= 1.0 / 1.01 ? Eigen::Vector3d(value * factor) : value;
  };
  StartState start;
  start.moving = !options.start_velocity.isZero(0.0) || !options.start_acceleration.isZero(0.0);
  start.velocity = onto_limits(options.start_velocity, options.limits.max_velocity, options.limits.max_speed);
  start.acceleration =
      onto_limits(options.start_acceleration, options.limits.max_acceleration, options.limits.max_acceleration_norm);
  return start;
}

// A start in motion: in s, f'(0) = v0 tau and f''(0) = a0 tau^2 give sdot = 1 / tau, the velocity
// v0 and (with sddot = 0) the acceleration a0. tau: the first piece (after splitting) at the start
// speed, so that f' matches the piece's chord (at the velocity limit for a start at rest with an
// acceleration).
void HoldStart(const StartState& start, const PlannerOptions& options, const Waypoints& joints,
               SpatialOptimizerOptions* attempt) {
  if (!start.moving) return;
  const double first = joints.cols() > 1 ? (joints.col(1) - joints.col(0)).norm() : 1.0;
  const double speed = start.velocity.norm() > 0.0 ? start.velocity.norm() : options.limits.max_velocity.minCoeff();
  const double tau = attempt->formulation == SpatialFormulation::kTimeCoupled ? 1.0 : std::max(first, 1e-3) / speed;
  attempt->start_tangent = start.velocity * tau;
  attempt->start_curvature = start.acceleration * tau * tau;
}

// The pieces of the last attempt (the shortest segments), counted before any is made: a
// max_segment_length of 1e-9 m asked for 3e10 of them (3.2 GB before the allocation failed).
// Returns the error, or "" when the count is within kMaxPlanPieces.
std::string PieceCountError(const Waypoints& path, const PlannerOptions& options) {
  const double shortest = options.max_segment_length / std::pow(2.0, options.max_attempts - 1);
  double pieces = 0.0;
  for (Eigen::Index i = 0; i + 1 < path.cols(); ++i) {
    pieces += SegmentParts((path.col(i + 1) - path.col(i)).norm(), shortest);
  }
  if (pieces <= kMaxPlanPieces) return "";
  std::ostringstream message;
  message << "options.max_segment_length: " << options.max_segment_length << " m splits the path into about " << pieces
          << " pieces by the last of " << options.max_attempts << " attempts, above the cap of " << kMaxPlanPieces
          << " (a longer max_segment_length)";
  return message.str();
}

// The spatial stage with its clearance post-check and retries (each with a larger collision weight
// and pieces half as long). Fills result's spatial, curve, min_clearance, spatial_attempts and
// times; returns kSuccess, or the failure with its message.
PlanStatus SpatialStage(const Esdf& esdf, const Eigen::Vector3d& start_point, const Eigen::Vector3d& goal,
                        const Waypoints& path, const StartState& start, const PlannerOptions& options, PlanResult* out,
                        std::string* message) {
  PlanResult& result = *out;
  SpatialOptimizerOptions spatial = options.spatial;
  spatial.safe_distance = options.robot_radius + options.safety_margin;
  if (spatial.formulation == SpatialFormulation::kTimeCoupled) {
    spatial.max_velocity = options.limits.max_velocity.minCoeff();
    spatial.max_acceleration = options.limits.max_acceleration.minCoeff();
  }
  // Exact against the voxels where the field is below radius + check margin; between samples the
  // clearance can drop by half a step. The end points are fixed: a start or goal that itself has
  // less than radius + half a step lowers the requirement to its own clearance (never below the
  // radius).
  const double exact_below = options.robot_radius + options.clearance_check_margin;
  const double half_step = 0.5 * options.clearance_check_step;
  const double required = std::max(
      options.robot_radius, std::min({options.robot_radius + half_step, VoxelClearance(esdf, start_point, exact_below),
                                      VoxelClearance(esdf, goal, exact_below)}));
  bool safe = false;
  for (int attempt = 0; attempt < options.max_attempts && !safe; ++attempt) {
    const double factor = std::pow(options.retry_collision_weight_factor, attempt);
    SpatialOptimizerOptions attempt_options = spatial;
    attempt_options.collision_weight = std::min(kMaxSpatialWeight, spatial.collision_weight * factor);
    const Waypoints joints = SplitSegments(path, options.max_segment_length / std::pow(2.0, attempt));
    HoldStart(start, options, joints, &attempt_options);
    auto t = Clock::now();
    result.spatial = OptimizeSpatialCurve(esdf, joints, attempt_options);
    result.times.spatial_seconds += SecondsSince(t);
    result.spatial_attempts = attempt + 1;
    Report(options, "spatial", SecondsSince(t),
           "attempt " + std::to_string(attempt + 1) + ", " + std::to_string(joints.cols() - 1) + " pieces, " +
               std::to_string(result.spatial.iterations.size()) + " iterations, " + ToString(result.spatial.status));
    if (!result.spatial.is_usable()) {
      *message =
          std::string("spatial optimization: ") + ToString(result.spatial.status) + ": " + result.spatial.message;
      return PlanStatus::kSpatialFailure;
    }
    result.curve = result.spatial.curve;
    // A piece longer than twice the field's diagonal has run away (it cannot stay in the field),
    // and its dense check would need a sample count without bound.
    const Eigen::AlignedBox3d field = esdf.box().Metric(esdf.resolution());
    const double reach = 2.0 * field.diagonal().norm() + 1.0;
    for (int i = 0; i < result.curve.num_pieces(); ++i) {
      const double length = PolylineLength(result.curve.piece(i));
      if (!(length <= reach)) {
        std::ostringstream s;
        s << "the optimized curve ran away: piece " << i << " is " << length
          << " m long, more than twice the distance field's diagonal (" << field.diagonal().norm() << " m)";
        *message = s.str();
        return PlanStatus::kSpatialFailure;
      }
    }
    t = Clock::now();
    result.min_clearance = MinVoxelClearance(esdf, result.curve, options.clearance_check_step, exact_below);
    safe = result.min_clearance >= required;
    if (!safe && result.min_clearance >= options.robot_radius) {
      // Above the radius at the samples but within half a step of it: a check 8 times denser
      // needs only 1/8 of the half-step margin (the curve may be fine in a tight gap).
      const double fine_step = options.clearance_check_step / 8.0;
      result.min_clearance = MinVoxelClearance(esdf, result.curve, fine_step, exact_below);
      safe = result.min_clearance >=
             std::max(options.robot_radius, std::min(required, options.robot_radius + 0.5 * fine_step));
    }
    result.times.check_seconds += SecondsSince(t);
    std::ostringstream outcome;
    outcome << "clearance " << result.min_clearance << " m (required " << required << " m)";
    Report(options, "check", SecondsSince(t), outcome.str());
  }
  result.path_length = result.curve.ArcLength(1e-6);
  if (!safe) {
    std::ostringstream s;
    s << "the optimized curve comes within " << result.min_clearance << " m of an obstacle (required: " << required
      << " m) after " << result.spatial_attempts << " attempts";
    *message = s.str();
    return PlanStatus::kCollision;
  }
  return PlanStatus::kSuccess;
}

// The plan's status and message for the temporal stage's result.
PlanStatus FromTemporal(const TemporalResult& temporal, std::string* message) {
  switch (temporal.status) {
    case TemporalStatus::kOptimal:
      *message = "";
      return PlanStatus::kSuccess;
    case TemporalStatus::kInfeasible:
      *message = "temporal stage: " + temporal.message;
      return PlanStatus::kTemporalInfeasible;
    case TemporalStatus::kInvalidInput:
      *message = "temporal stage: " + temporal.message;
      return PlanStatus::kInvalidInput;
    default:
      *message = std::string("temporal stage: ") + ToString(temporal.status) + ": " + temporal.message;
      return PlanStatus::kTemporalFailure;
  }
}

}  // namespace

Planner::Planner(const Esdf& esdf) : esdf_(&esdf), search_(esdf) {}

PlanResult Planner::Plan(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, const PlannerOptions& options) {
  const auto started = Clock::now();
  PlanResult result;
  auto finish = [&](PlanStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.times.total_seconds = SecondsSince(started);
    return result;
  };
  std::string error;
  if (!options.IsValid(&error)) return finish(PlanStatus::kInvalidInput, "options." + error);
  // A goal within a micrometre of the start (far below any map's resolution) leaves no curve to time.
  if (start.allFinite() && goal.allFinite() && (goal - start).norm() <= kSamePoint) {
    std::ostringstream message;
    message << "start and goal are the same point (" << start.transpose() << "): there is no path to plan";
    return finish(PlanStatus::kInvalidInput, message.str());
  }

  // ---- front-end ----
  PathSearchOptions search = options.search;
  search.robot_radius = options.robot_radius;
  search.clearance_margin = options.safety_margin;
  auto t = Clock::now();
  const PathSearchResult path = search_.Search(start, goal, search);
  result.times.search_seconds = SecondsSince(t);
  Report(options, "search", result.times.search_seconds,
         path.is_success() ? std::to_string(path.waypoints.cols()) + " waypoints" : path.message);
  if (!path.is_success()) return finish(FromSearch(path.status), path.message);
  result.waypoints = path.waypoints;

  // ---- spatial stage with post-check and retries ----
  const StartState held = StartOnLimits(options);
  if (std::string too_many = PieceCountError(path.waypoints, options); !too_many.empty()) {
    return finish(PlanStatus::kInvalidInput, too_many);
  }
  std::string message;
  const PlanStatus spatial = SpatialStage(*esdf_, start, goal, path.waypoints, held, options, &result, &message);
  if (spatial != PlanStatus::kSuccess) return finish(spatial, message);

  // ---- temporal stage ----
  TemporalProblem problem;
  problem.curve = result.curve;
  problem.limits = options.limits;
  problem.cells_per_piece = options.temporal_cells_per_piece;
  problem.rho = options.rho;
  problem.constraint_mode = options.constraint_mode;
  problem.boundary.start_velocity = held.velocity;
  problem.boundary.start_acceleration = held.acceleration;
  problem.relax_boundary = held.moving;
  t = Clock::now();
  // One solver per planner, kept while its options stay the same, so that a re-plan reuses its
  // workspace (the conic solver's symbolic analysis when the sparsity pattern repeats). Every field
  // of the options is compared (the memory budget had escapped a field-by-field test).
  if (!temporal_ || temporal_options_ != options.socp) {
    temporal_ = MakeSocpTemporalSolver(options.socp);
    temporal_options_ = options.socp;
  }
  // A start in motion that cannot be flown as given is relaxed by the temporal stage (the start
  // speed lowered on the paper's and certified rows, the start state scaled towards rest with a
  // jerk limit; TemporalProblem::relax_boundary).
  result.temporal = temporal_->Solve(problem);
  if (result.temporal.boundary_relaxation) result.start_scale = result.temporal.boundary_relaxation->start_scale;
  result.times.temporal_seconds = SecondsSince(t);
  {
    std::ostringstream outcome;
    outcome << ToString(result.temporal.status) << ", " << result.temporal.method << ", T "
            << result.temporal.total_time << " s";
    if (result.temporal.scp_iterations > 0) outcome << ", " << result.temporal.scp_iterations << " convex solves";
    Report(options, "temporal", result.times.temporal_seconds, outcome.str());
  }
  if (result.temporal.status == TemporalStatus::kOptimal) CurveQuality(&result);
  const PlanStatus temporal = FromTemporal(result.temporal, &message);
  return finish(temporal, message);
}

PlanResult Plan(const Esdf& esdf, const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                const PlannerOptions& options) {
  Planner planner(esdf);
  return planner.Plan(start, goal, options);
}

}  // namespace timeopt
