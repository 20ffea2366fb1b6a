#pragma once

// The whole planner of Gao et al. (IROS 2018): front-end search, spatial optimization, a clearance
// post-check, and the temporal stage.
//
//   start, goal, ESDF -> PathSearch (A* + shortcuts) -> waypoints, split into pieces of at most
//   max_segment_length -> OptimizeSpatialCurve (Ceres) -> dense clearance check along the curve
//   (retry with a higher collision weight and more joints; never a success below the radius)
//   -> TemporalSolver (our SOCP, certified constraint mode: the velocity and acceleration limits
//   hold in continuous time, not only at the grid points) -> time-optimal trajectory.
//
// The planner reads the map only through the ESDF (grid for the search, DistanceField for the
// optimizer). Metres and seconds.

#include <array>
#include <memory>
#include <functional>
#include <limits>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/map/esdf.h"
#include "timeopt/spatial/path_search.h"
#include "timeopt/spatial/spatial_optimizer.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {

// The planner's limits: FlightLimits() (timeopt/temporal/temporal_problem.h).
inline VehicleLimits DefaultPlannerLimits() { return FlightLimits(); }

struct PlannerOptions {
  // The vehicle's state at the start, m/s and m/s^2: zero for a start at rest (hover). A start in
  // motion (re-planning in flight) makes the curve leave the start along the velocity, with the
  // curvature that gives the acceleration, and the temporal stage start at that state; if the
  // limits cannot be met from it (too fast for what lies ahead), the temporal stage answers with
  // the closest start it can fly (TemporalProblem::relax_boundary: the start speed lowered on the
  // paper's and certified rows, the start state scaled towards rest with a jerk limit), and the
  // plan says so (start_scale, the temporal result's boundary_relaxation). A state at most 1% over the per-axis or norm
  // limits (a vehicle tracking at its limits overshoots them a little) is scaled onto them first.
  Eigen::Vector3d start_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_acceleration = Eigen::Vector3d::Zero();

  // Radius of the sphere around the curve that must stay free, metres. The search never enters a
  // voxel closer than this and the post-check rejects any curve that comes closer.
  double robot_radius = 0.3;
  // Extra clearance the planner aims for, metres: the search's soft margin and the optimizer's
  // safety distance are robot_radius + safety_margin. 0.2: two voxels of the forest maps.
  double safety_margin = 0.2;
  // The post-check measures the exact distance to the cubes of the occupied voxels (the voxels
  // the ESDF was built from) wherever the interpolated ESDF is below robot_radius + this margin,
  // metres. The interpolated field can exceed the distance to the voxel cubes by at most
  // (sqrt(3) / 2 + (sqrt(3) - 1) / 2) voxel (trilinear weights over a cell of a 1-Lipschitz field,
  // plus centre-vs-face distance): 0.124 m at 0.1 m voxels, so 0.15 m covers every sample that
  // could be closer than the radius.
  double clearance_check_margin = 0.15;
  // Sampling step of the post-check along the curve, metres (upper bound; chord length). The curve
  // must keep robot_radius + step / 2 at the samples, so it keeps the radius between them. A curve
  // that keeps the radius but not the half step is checked again at step / 8 (margin step / 16).
  double clearance_check_step = 0.02;

  // Front-end. robot_radius and clearance_margin are overwritten from the fields above.
  PathSearchOptions search;
  // Waypoint segments longer than this are split evenly into pieces, metres. 1.5: on the
  // forest_gen pairs 1.0, 1.5 and 2.0 all succeeded 500/500 at 0.3 m; fewer pieces make the
  // temporal stage faster (median 17 -> 12 ms at K = 30), and retries halve it where needed.
  double max_segment_length = 1.5;
  // Spatial stage. safe_distance is overwritten (robot_radius + safety_margin); in the
  // time-coupled formulation max_velocity / max_acceleration are overwritten from `limits`
  // (smallest axis).
  SpatialOptimizerOptions spatial;
  // Called as each stage ends (the library prints nothing; `timeopt plan --verbose` prints these):
  // the stage ("search", "spatial", "check", "temporal"), its duration in seconds and a short
  // description of its outcome. Not part of the JSON configuration. Empty: not called.
  std::function<void(const std::string& stage, double seconds, const std::string& outcome)> on_stage;
  // Attempts of the spatial stage: attempt k (0-based) multiplies the collision weight by
  // retry_collision_weight_factor^k and divides max_segment_length by 2^k. 4 attempts.
  int max_attempts = 4;
  double retry_collision_weight_factor = 4.0;

  // Temporal stage. Limits: 2 m/s, 2 m/s^2 and 10 m/s^3 per axis, what `timeopt plan` flies (a
  // small quadrotor's comfortable envelope; the temporal problem alone defaults to VehicleLimits'
  // 2 m/s and 1 m/s^2 without a jerk limit). rho must be 0 with a jerk limit.
  TemporalLimits limits = DefaultPlannerLimits();
  // Cells per piece, K. 20: below the paper's 30-50, but the certified rows make the limits hold
  // between grid points anyway (only optimality is lost, a few per cent of T at most), and the
  // solve time grows linearly with K (forest_gen median 12 ms at K = 30, 7 ms at K = 20).
  int temporal_cells_per_piece = 20;
  double rho = 0.0;  // acceleration regularization (paper eq. 27)
  // kCertified (default): the limits hold on the whole trajectory. kPaper: the paper's rows.
  ConstraintMode constraint_mode = ConstraintMode::kCertified;
  // The temporal solver's options. The planner turns the jerk-limited fallback to Ipopt off
  // (jerk_ipopt_fallback_seconds 0): its pieces are short (max_segment_length), where the conic
  // solves do not fail for length, and the failures it does meet (a re-planned start exactly at a
  // limit) Ipopt does not solve either, after up to its whole CPU cap; its own start relaxation
  // answers those in milliseconds.
  SocpTemporalOptions socp = [] {
    SocpTemporalOptions o;
    o.jerk_ipopt_fallback_seconds = 0.0;
    return o;
  }();

  bool IsValid(std::string* error) const;
};

enum class PlanStatus {
  kSuccess,       // curve, temporal result and trajectory usable
  kInvalidInput,  // bad options or points; message names them
  kStartOutsideMap,
  kGoalOutsideMap,
  kStartInCollision,  // start closer than robot_radius to an obstacle
  kGoalInCollision,
  kUnreachable,         // the front-end found no path with the clearance
  kSearchLimit,         // the front-end's node limit was reached
  kCollision,           // every spatial attempt came closer than the radius (curve is the last one)
  kSpatialFailure,      // Ceres failed
  kTemporalInfeasible,  // no time allocation meets the limits
  kTemporalFailure,     // the temporal solver failed otherwise
};
// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<PlanStatus, 12> kPlanStatuses = {
    PlanStatus::kSuccess,        PlanStatus::kInvalidInput,       PlanStatus::kStartOutsideMap,
    PlanStatus::kGoalOutsideMap, PlanStatus::kStartInCollision,   PlanStatus::kGoalInCollision,
    PlanStatus::kUnreachable,    PlanStatus::kSearchLimit,        PlanStatus::kCollision,
    PlanStatus::kSpatialFailure, PlanStatus::kTemporalInfeasible, PlanStatus::kTemporalFailure,
};
// "success", "invalid_input", "start_outside_map", "goal_outside_map", "start_in_collision",
// "goal_in_collision", "unreachable", "search_limit", "collision", "spatial_failure",
// "temporal_infeasible", "temporal_failure".
const char* ToString(PlanStatus status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, PlanStatus* status);

// Wall time of each stage of a plan, seconds (the plan summary's "time_ms" gives them in ms).
struct PlanStageTimes {
  double search_seconds = 0.0;
  double spatial_seconds = 0.0;   // all attempts
  double check_seconds = 0.0;     // clearance post-checks
  double temporal_seconds = 0.0;  // building and solving the temporal problem
  double total_seconds = 0.0;
};

struct PlanResult {
  PlanStatus status = PlanStatus::kInvalidInput;
  std::string message;
  Waypoints waypoints;      // front-end waypoints (after shortcutting, before splitting)
  PiecewiseCurve curve;     // the spatial curve (unit pieces in s)
  SpatialResult spatial;    // the last spatial attempt
  TemporalResult temporal;  // set when the temporal stage ran
  int spatial_attempts = 0;
  double path_length = 0.0;  // arc length of the curve, metres
  // Smallest clearance on the dense check, metres: the exact distance to occupied voxel cubes
  // near obstacles, the ESDF elsewhere.
  double min_clearance = 0.0;
  // Curve quality, for successful plans (NaN otherwise), on a 10 ms grid more than 1 s from either
  // end (NaN for a plan shorter than 2 s): the smallest speed, m/s, and the smallest radius of
  // curvature of the path (|v|^3 / |v x a|), metres (infinite, so NaN, on a straight line). A sharp
  // bend the trajectory must brake for shows in both.
  double min_interior_speed = std::numeric_limits<double>::quiet_NaN();
  double min_curvature_radius = std::numeric_limits<double>::quiet_NaN();
  // A start in motion that cannot be flown as given: the factor on its speed that the temporal
  // stage's relaxation found (boundary_relaxation->start_scale; with a jerk limit the largest
  // lambda, within 0.01, for which the velocity times lambda and the acceleration times lambda^2
  // can be flown); the trajectory starts from that state. 1: the given state.
  double start_scale = 1.0;
  PlanStageTimes times;
  bool is_success() const { return status == PlanStatus::kSuccess; }
};

// Holds the front-end's work arrays and the temporal solver's workspace, so that repeated plans on
// one map do not allocate them again.
// Not thread-safe.
class Planner {
 public:
  explicit Planner(const Esdf& esdf);  // the ESDF must outlive the planner
  // Never throws for bad input: the status says what went wrong.
  PlanResult Plan(const Eigen::Vector3d& start, const Eigen::Vector3d& goal, const PlannerOptions& options = {});

 private:
  const Esdf* esdf_;
  PathSearch search_;
  std::unique_ptr<TemporalSolver> temporal_;  // made at the first Plan, remade when options.socp change
  SocpTemporalOptions temporal_options_;
};

// The region of interest of a plan on a large map (Esdf::FromMapRegion): the box of start and
// goal grown by `margin` metres on every axis. kDefaultRegionMargin leaves room for the detours of
// a forest or a building floor while a city-sized map costs only the region; a path that needs more
// finds a wall there (the region's cut faces count as occupied) and the plan fails as blocked.
inline constexpr double kDefaultRegionMargin = 10.0;
inline Eigen::AlignedBox3d PlanRegion(const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                                      double margin = kDefaultRegionMargin) {
  Eigen::AlignedBox3d region(start.cwiseMin(goal), start.cwiseMax(goal));
  region.min().array() -= margin;
  region.max().array() += margin;
  return region;
}

// One plan (a Planner for one call).
PlanResult Plan(const Esdf& esdf, const Eigen::Vector3d& start, const Eigen::Vector3d& goal,
                const PlannerOptions& options = {});

// Smallest field value along the curve, sampled at chord steps of at most `step` metres.
double MinClearance(const DistanceField& field, const PiecewiseCurve& curve, double step);

// Distance from `point` to the nearest cube of an occupied voxel of the ESDF's grid (voxels with a
// negative stored value), searched within `reach` metres (returns `reach` when none is closer).
// Voxels outside the ESDF's box count as free, as in the ESDF.
double VoxelClearance(const Esdf& esdf, const Eigen::Vector3d& point, double reach);

// Like MinClearance, but samples whose ESDF value is below `exact_below` get VoxelClearance.
double MinVoxelClearance(const Esdf& esdf, const PiecewiseCurve& curve, double step, double exact_below);

// Waypoints with every segment longer than max_length split evenly.
Waypoints SplitSegments(const Waypoints& waypoints, double max_length);

}  // namespace timeopt
