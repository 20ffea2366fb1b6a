#pragma once
// Verification by simulation: a jerk-input quadrotor (a triple integrator per axis, the flat model
// of a multirotor whose thrust and body rates are fast) flies a reference trajectory under feedback
// and the report says whether every velocity, acceleration and jerk limit held at every instant of
// the flight, not only at grid points.
//
// Model and controller, per axis:
//   p' = v,  v' = a,  a' = u,
//   u = j_ref + k_a (a_ref - a) + k_v (v_ref - v) + k_p (p_ref - p),
// with the gains that put the three poles of the tracking error at -bandwidth (k_a = 3 w,
// k_v = 3 w^2, k_p = w^3: critically damped in continuous time). The controller runs at a fixed rate:
// u is computed from the reference at the start of each step and held over the step (zero-order
// hold), optionally clipped to a jerk limit. Within a step a is linear and v quadratic in time, so
// their largest magnitudes over the step are found exactly (ends and the vertex of v), and the
// integration is exact: no error is added between steps.
//
// What it reveals: the temporal stage's profile has a constant sddot per cell, so the reference
// acceleration jumps between cells and at the ends of cruise phases. A vehicle with finite jerk
// cannot follow a jump; with these gains its acceleration overshoots a jump of size D by 0.206 D and
// its velocity by 0.23 D / bandwidth. The acceleration-change bound lambda_a of the temporal problem
// (VehicleLimits::max_acceleration_change) limits the jumps and therefore the overshoot.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "timeopt/core/vehicle_limits.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

struct QuadrotorSimOptions {
  /// Controller period, s: the jerk command is held constant over each step. 1e-3 (1 kHz, a typical
  /// attitude-loop rate). Must be > 0 and bandwidth * time_step <= 0.1 (at least 10 steps per time
  /// constant 1 / bandwidth; the held command moves the loop's poles by about (bandwidth *
  /// time_step / 2)^(1/3) relative).
  double time_step = 1e-3;
  /// Closed-loop bandwidth w of the tracking error, rad/s: all three poles at -w. 10.
  double bandwidth = 10.0;
  /// Flight time after the reference ends (see QuadrotorSim::Run), s, so that
  /// the transient of the last acceleration jump is included. 1.0 (10 time constants at w = 10).
  double settle_time = 1.0;
  /// Per-axis jerk limit of the vehicle, m/s^3; commands are clipped to it. Absent: no limit.
  std::optional<Eigen::Vector3d> max_jerk;
  /// Initial state minus the reference's initial state (position m, velocity m/s, acceleration
  /// m/s^2). Zero by default: the vehicle starts on the reference.
  Eigen::Vector3d initial_position_error = Eigen::Vector3d::Zero();
  Eigen::Vector3d initial_velocity_error = Eigen::Vector3d::Zero();
  Eigen::Vector3d initial_acceleration_error = Eigen::Vector3d::Zero();
  /// Relative slack of the verdict: a limit holds if |value| <= limit (1 + limit_tolerance). 1e-9,
  /// for rounding; every entry point of the product takes DefaultFlightTolerance instead.
  double limit_tolerance = 1e-9;
  /// The flight also fails if the vehicle strays farther than this from the reference at any step,
  /// metres: a loop too slow to follow (bandwidth 1e-9) stays within every limit while it ends far
  /// from the goal. 1 m: the tracking error of the shipped plans is below 1e-4 m, and an initial
  /// error of 0.1 m decays from there. +infinity turns the check off.
  double max_position_error = 1.0;
  /// Keep the state at every step in FeasibilityReport::states (at most 1e7 steps). False.
  bool record_states = false;

  /// False, with a message naming the first bad setting, if any setting is out of range.
  bool IsValid(std::string* error) const;
};

/// The simulated vehicle's state at the start of one controller step.
struct SimState {
  double t = 0.0;                                            ///< s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();        ///< m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();        ///< m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();    ///< m/s^2
  Eigen::Vector3d jerk = Eigen::Vector3d::Zero();            ///< command held over the step, m/s^3
  Eigen::Vector3d position_error = Eigen::Vector3d::Zero();  ///< position - reference position, m
};

/// The product's flight criterion: a reference timed with a jerk limit, or given as samples, is
/// flown within 1% of every limit. The simulated controller holds its jerk command over each
/// control step (and a sampled reference is interpolated between its samples), so it lags a
/// continuous reference by a little: 0.2-0.5% above the acceleration limit on the shipped plans.
inline constexpr double kFlightTolerance = 0.01;
/// Rounding only: a reference without a jerk limit steps its acceleration, which a jerk-input
/// vehicle cannot follow; its flight is judged as it is.
inline constexpr double kExactFlightTolerance = 1e-9;
/// The one default of the verdict's slack (QuadrotorSimOptions::limit_tolerance) for a reference
/// timed with `limits`, used by `timeopt plan`, `waypoints` and `simulate` and by Python's
/// simulate: kFlightTolerance with a jerk limit, kExactFlightTolerance without.
inline double DefaultFlightTolerance(const VehicleLimits& limits) {
  return limits.max_jerk ? kFlightTolerance : kExactFlightTolerance;
}

struct FeasibilityReport {
  /// True iff the largest velocity and acceleration ratios (and the quadrotor limits' ratios, for
  /// those given) are <= 1 + limit_tolerance and the flight stayed finite. (A jerk limit is the vehicle's: commands are
  /// clipped to it, so it always holds; see clipped_steps.)
  bool feasible = false;
  /// The verdict's slack it was judged with (QuadrotorSimOptions::limit_tolerance).
  double tolerance = 0.0;
  /// The failed limits with their largest ratio, axis and time, or "velocity and acceleration
  /// limits hold"; and how many steps clipped the jerk, if any did.
  std::string message;
  /// Largest |v_axis(t)| / max_velocity(axis) over the whole flight (exact between steps), and when.
  /// Infinite, with both times at the moment it happened, if the flight diverged.
  double max_velocity_ratio = 0.0;
  double max_velocity_time = 0.0;
  /// Largest |a_axis(t)| / max_acceleration(axis) over the whole flight (exact), and when.
  double max_acceleration_ratio = 0.0;
  double max_acceleration_time = 0.0;
  /// The quadrotor's limits (VehicleLimits::max_speed ...), each set when the limit is given: the
  /// largest ||v|| / max_speed (at step ends and middles: within |jerk| dt^2 / 8 of exact),
  /// ||a|| / max_acceleration_norm, ||a + g e3|| / max_thrust, min_thrust / ||a + g e3|| and
  /// tilt / max_tilt (exact: a is linear over a step, the first three are convex along it and the
  /// tilt quasi-convex, and the smallest thrust is found in closed form).
  std::optional<double> max_speed_ratio;
  std::optional<double> max_acceleration_norm_ratio;
  std::optional<double> max_thrust_ratio;
  std::optional<double> min_thrust_ratio;
  std::optional<double> max_tilt_ratio;
  /// Largest |u_axis| / max_jerk(axis) before clipping (> 1 means the jerk limit clipped a command);
  /// 0 without a jerk limit. Largest |u_axis| applied, m/s^3.
  double max_jerk_ratio = 0.0;
  double max_jerk = 0.0;
  /// Steps in which some axis was clipped to the jerk limit.
  int clipped_steps = 0;
  /// Largest ||position - reference position|| at the step boundaries, m, and when.
  double max_position_error = 0.0;
  double max_position_error_time = 0.0;
  /// ||position - reference position|| at the end of the settle time, m.
  double final_position_error = 0.0;
  int steps = 0;
  /// Every step's starting state and the final state, if QuadrotorSimOptions::record_states.
  std::vector<SimState> states;
};

class QuadrotorSim {
 public:
  using Options = QuadrotorSimOptions;
  /// The reference: position, velocity, acceleration and jerk at time t (t in [0, duration]).
  using Reference = std::function<TrajectoryState(double t)>;

  /// Throws std::invalid_argument with IsValid's message if the options are invalid.
  explicit QuadrotorSim(const Options& options = Options());

  /// Flies `reference` for duration() s plus the settle time and checks `limits`' velocity and
  /// acceleration, the vehicle starting in the reference's initial state plus the options' initial
  /// errors. Steps: ceil((duration + settle_time) / time_step), with 1e-6 relative slack. After the
  /// reference ends, it continues at its final velocity with zero acceleration (a hover for
  /// rest-to-rest trajectories). Throws std::invalid_argument if the limits are not positive and
  /// finite, the flight would take more than 1e8 steps, or the reference returns a non-finite state.
  FeasibilityReport Run(const Trajectory& reference, const VehicleLimits& limits) const;

  /// The same for a reference given as a function on [0, duration] (duration >= 0).
  FeasibilityReport Run(const Reference& reference, double duration, const VehicleLimits& limits) const;

  /// Flies `reference` as the solution of a temporal problem: against its limits, the vehicle
  /// starting in the problem's start state (its boundary's start velocity and acceleration, plus
  /// the options' initial errors). The profile meets the start velocity, but its acceleration at
  /// t = 0 is the first cell's unless max_acceleration_change bounds it, so a vehicle at rest
  /// starts with a jump.
  FeasibilityReport Fly(const Trajectory& reference, const VehicleLimits& limits, const Eigen::Vector3d& start_velocity,
                        const Eigen::Vector3d& start_acceleration) const;

  const Options& options() const { return options_; }

 private:
  FeasibilityReport RunFrom(const Reference& reference, double duration, const VehicleLimits& limits,
                            const Eigen::Vector3d& start_velocity, const Eigen::Vector3d& start_acceleration) const;

  Options options_;
};

/// A reference through samples (e.g. ReadSamplesCsv of another planner's output), for
/// QuadrotorSim::Run with duration samples.back().t - samples.front().t: time is shifted so that the
/// first sample is at 0, and between samples k and k+1 the reference starts in sample k with its
/// jerk and, on each axis, switches to sample k+1's jerk at the time that lands on sample k+1's
/// acceleration when that time lies between them (exact for a jerk that is piecewise constant with
/// at most one switch per interval, as a finely sampled jerk-limited profile); otherwise sample k's
/// jerk is held (exact when it is constant between samples; an acceleration step then happens at
/// sample k+1, as in the paper's profile). At and after the last sample it is the last sample's
/// state. Throws std::invalid_argument for fewer than 2 samples, times
/// not strictly increasing, or a non-finite value.
QuadrotorSim::Reference SampledReference(std::vector<TrajectoryState> samples);

}  // namespace timeopt
