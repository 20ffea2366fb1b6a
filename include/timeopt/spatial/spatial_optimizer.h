#pragma once

// The spatial stage of Gao et al. (IROS 2018, Sect. III-B): a smooth, collision-free curve f(s) in
// the virtual parameter s, with no dynamics in it,
//
//   minimize  w_s sum_i integral_0^1 |f_i'''(s)|^2 ds                  (jerk in s, eq. 2, exact)
//           + w_c sum_i integral_0^1 c(d(f_i(s))) |f_i'(s)| ds         (collision line integral, eq. 4)
//           + w_l sum_i integral_0^1 |f_i'(s)|^2 ds                    (length term, Sect. III-A)
//
// over C2 piecewise quintics with unit-s pieces. The decision variables are the states
// (f, f', f'') at the interior joints; start and goal are fixed and at rest (f' = f'' = 0), so
// continuity holds by construction and every residual touches only its piece's two joints. d is
// the signed distance of a DistanceField (the optimizer never sees the occupancy map) and
// c(d) = (exp((d_safe - d) / decay) - 1)^2 below the safety distance d_safe, 0 above. Solved by
// Ceres' Levenberg-Marquardt with analytic Jacobians.
//
// The time-coupled baseline (the paper's Fig. 4 comparison) optimizes the same joints, but each
// piece has a fixed heuristic duration T_i (chord length / heuristic speed), the joints store
// time derivatives (so the curve is C2 in time), the jerk and length terms are integrals in time,
// and soft penalties on velocity and acceleration above the limits are added.
//
// Units: metres, seconds. Costs are in the units of their integrals times their weights.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/map/distance_field.h"

namespace timeopt {

enum class SpatialFormulation {
  kSpatial,      // the paper's decoupled spatial stage (no time, no dynamics)
  kTimeCoupled,  // the baseline: fixed piece durations and dynamic-feasibility penalties
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<SpatialFormulation, 2> kSpatialFormulations = {
    SpatialFormulation::kSpatial,
    SpatialFormulation::kTimeCoupled,
};
const char* ToString(SpatialFormulation formulation);  // "spatial", "time_coupled"
// The enumerator named `text` (as ToString writes it) into *formulation; false when none is.
bool FromString(const std::string& text, SpatialFormulation* formulation);

// The length in s that each piece spans while the spatial formulation optimizes (the output
// pieces are rescaled to unit s either way): every piece 1 (uniform), its chord over the mean
// chord (chordal), or the square root of its chord over the mean square root (centripetal).
enum class SpatialParameterization {
  kUniform,
  kChordal,
  kCentripetal,
};
inline constexpr std::array<SpatialParameterization, 3> kSpatialParameterizations = {
    SpatialParameterization::kUniform,
    SpatialParameterization::kChordal,
    SpatialParameterization::kCentripetal,
};
const char* ToString(SpatialParameterization parameterization);  // "uniform", "chordal", "centripetal"
bool FromString(const std::string& text, SpatialParameterization* parameterization);

enum class SpatialLinearSolver {
  kSparseNormalCholesky,  // Ceres SPARSE_NORMAL_CHOLESKY (SuiteSparse): linear in the joints
  kDenseQr,               // Ceres DENSE_QR: faster for a handful of joints
};

// The largest weight of a spatial cost term (SpatialOptimizerOptions::IsValid).
inline constexpr double kMaxSpatialWeight = 1e9;

struct SpatialOptimizerOptions {
  SpatialFormulation formulation = SpatialFormulation::kSpatial;
  // The spatial formulation's piece lengths in s while it optimizes (SpatialParameterization).
  // Chordal: with every piece 1 long in s (uniform), minimizing the jerk in s bends the curve
  // sharply around a short piece between long ones, and the trajectory brakes there (the default
  // forest plan slowed to 0.31 m/s twice in open space). Measured on 50 plans through the five
  // forests of the shared maps: uniform 3 plans below 0.3 vmax more than 1 s from the ends
  // (slowest 0.21 m/s), chordal none (0.94 m/s), centripetal 1 (0.50 m/s); total T -2.1% chordal,
  // -1.3% centripetal; every plan collision-free and flown within 1% with each.
  SpatialParameterization parameterization = SpatialParameterization::kChordal;

  // The curve's first and second derivative at the start, held fixed like the start itself: zero
  // for a start at rest (the default); for a start in motion (re-planning), the tangent along the
  // velocity and the curvature that gives the acceleration. In s for the spatial formulation, in
  // the first piece's time (m/s, m/s^2) for the time-coupled one.
  Eigen::Vector3d start_tangent = Eigen::Vector3d::Zero();
  Eigen::Vector3d start_curvature = Eigen::Vector3d::Zero();

  // w_s: weight of the jerk integral (m^2 per unit s^5); the other weights are relative to it.
  // 2: with 1, 2 of the 500 forest_gen plans bent over a few centimetres at a corner of the front
  // end's path and braked there below 0.3 vmax; with 2 none does, the 500 flight times sum 0.3%
  // lower, and the default plan is 1.8% slower (docs/planner.md).
  double smoothness_weight = 2.0;
  // w_c: weight of the collision line integral (per metre of curve inside the safety distance,
  // times c). 10: pushes a curve out of the safety band within a few LM steps on 10 m forest
  // paths while the jerk term still smooths it; the planner raises it when a check fails.
  double collision_weight = 10.0;
  // w_l: weight of the integral of |f'|^2 (m^2 per unit s). 0.5: keeps the free joints from
  // drifting apart (the jerk term alone is indifferent to a uniform stretch of a straight piece).
  double length_weight = 0.5;

  // d_safe: the collision penalty is zero at and above this signed distance, metres. The planner
  // sets it to robot radius + safety margin.
  double safe_distance = 0.5;
  // Decay length of the exponential penalty, metres: the penalty grows by e per this distance
  // inside the safety band. 0.1: one voxel of the forest maps, steep enough to dominate the
  // smoothness term before the curve reaches the robot radius.
  double penalty_decay_length = 0.1;
  // Gauss-Legendre nodes per piece for the collision integral. 12: exact for polynomials of degree
  // 23, and pieces of about a metre are sampled every ~8 cm (below the map resolution of 0.1 m).
  int collision_samples_per_piece = 12;
  // eps in (|f'|^2 + eps^2)^(1/4), metres per unit s: keeps the residual differentiable where the
  // tangent vanishes (the rest-to-rest ends). 1e-3 m: negligible against pieces of 0.5 m and more.
  double tangent_epsilon = 1e-3;

  // Levenberg-Marquardt limits. The iteration limit ends the solve (forest plans converge in 10-40;
  // the shipped forest's curve takes all 100 in ~15 ms), so a curve is the same on every machine and
  // under any load. The time limit only guards against a runaway solve: at 0.1 s it bound under load
  // (two processes on one busy machine planned the shipped forest 0.12% apart).
  int max_iterations = 100;
  double max_solver_time_seconds = 10.0;
  // Ceres' relative cost-change tolerance. 1e-5: the curve moves by far less than a voxel after.
  double function_tolerance = 1e-5;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  SpatialLinearSolver linear_solver = SpatialLinearSolver::kSparseNormalCholesky;

  // ---- time-coupled baseline only ----
  // Heuristic speed that fixes the piece durations T_i = max(chord_i / speed, min_duration), m/s.
  double heuristic_speed = 1.0;
  double min_piece_duration = 0.2;  // seconds, keeps T_i away from 0 for coincident joints
  // Soft limits of the dynamic-feasibility penalties, m/s and m/s^2 (per axis).
  double max_velocity = 2.0;
  double max_acceleration = 2.0;
  // Weight of the squared excess over the limits. 10: same order as the collision term.
  double dynamic_weight = 10.0;
  // Evenly spaced samples per piece for the dynamic penalties. 10.
  int dynamic_samples_per_piece = 10;

  // False, with a message naming the field, when an option is out of range.
  bool IsValid(std::string* error) const;
};

// One Levenberg-Marquardt iteration (Ceres' IterationSummary): iteration 0 is the initial point.
struct SpatialIteration {
  int iteration = 0;
  // Objective (sum of squared residuals = the weighted integrals) at the iterate after this
  // iteration: the step's cost when it was accepted, else the previous iterate's.
  double cost = 0.0;
  // Objective at the step Ceres tried in this iteration (accepted or not).
  double step_cost = 0.0;
  double time_seconds = 0.0;  // cumulative solver time, seconds
  bool step_accepted = false;
};

enum class SpatialStatus {
  kConverged,       // a Ceres convergence tolerance was met; curve usable
  kIterationLimit,  // iteration or time limit; curve usable (cost never above the initial one)
  kInvalidInput,    // bad options or waypoints; message names them; nothing usable
  kFailure,         // Ceres failed (e.g. a non-finite cost); nothing usable
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<SpatialStatus, 4> kSpatialStatuses = {
    SpatialStatus::kConverged,
    SpatialStatus::kIterationLimit,
    SpatialStatus::kInvalidInput,
    SpatialStatus::kFailure,
};
const char* ToString(SpatialStatus status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, SpatialStatus* status);

// Cost terms as they enter the objective (weights included).
struct SpatialCostBreakdown {
  double smoothness = 0.0;
  double collision = 0.0;
  double length = 0.0;
  double dynamic = 0.0;  // time-coupled baseline only
  double total() const { return smoothness + collision + length + dynamic; }
};

struct SpatialResult {
  SpatialStatus status = SpatialStatus::kFailure;
  std::string message;
  // Unit-s pieces. Spatial: C2 in s with uniform piece lengths; with chordal or centripetal ones
  // (the default is chordal) the tangent's length changes at the joints, so G1 in s (G2 as a
  // path). Time-coupled: C2 in time with the durations below, so G1 in s. The temporal stage
  // handles G1 joints through its joint ratios.
  PiecewiseCurve curve;
  std::vector<double> durations;  // time-coupled: the fixed piece durations, seconds; else empty
  SpatialCostBreakdown initial_cost, final_cost;
  std::vector<SpatialIteration> iterations;
  double solve_time_seconds = 0.0;  // problem construction and solve
  bool is_usable() const { return status == SpatialStatus::kConverged || status == SpatialStatus::kIterationLimit; }
};

// Optimizes the curve whose joints start at `waypoints` (columns; the first and last are the fixed
// start and goal). The initial curve is the minimum-jerk spline through them (rest to rest). The
// field must outlive the call. Never throws for bad input: kInvalidInput with a message.
SpatialResult OptimizeSpatialCurve(const DistanceField& field, const Waypoints& waypoints,
                                   const SpatialOptimizerOptions& options = {});

}  // namespace timeopt
