#pragma once

// The vehicle's limits, shared by the modules that plan against them (temporal) and the ones that
// check a flight against them (sim), so that neither includes the other.

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Core>

namespace timeopt {

struct VehicleLimits {
  // Per-axis velocity limit |v_axis| <= max_velocity(axis), m/s; each > 0, +infinity for no limit
  // on that axis (then max_speed must bound the speed).
  Eigen::Vector3d max_velocity = Eigen::Vector3d::Constant(2.0);
  // Per-axis acceleration limit |acc_axis| <= max_acceleration(axis), m/s^2; each > 0, +infinity
  // for no limit on that axis (then max_acceleration_norm or max_thrust must bound it).
  Eigen::Vector3d max_acceleration = Eigen::Vector3d::Constant(1.0);

  // The quadrotor's own limits, each optional, with any subset of the per-axis ones (all convex in
  // the temporal problem). Speed ||v|| <= max_speed, m/s. Acceleration ||acc|| <= max_acceleration_norm,
  // m/s^2. Mass-normalized thrust min_thrust <= ||acc + gravity e3|| <= max_thrust, m/s^2 (gravity
  // along -z; min_thrust is enforced as acc_z + gravity >= min_thrust, which implies it and is
  // convex). Tilt: the angle between acc + gravity e3 and the vertical is at most max_tilt, radians
  // in (0, pi/2).
  std::optional<double> max_speed;
  std::optional<double> max_acceleration_norm;
  std::optional<double> max_thrust;
  std::optional<double> min_thrust;
  std::optional<double> max_tilt;
  double gravity = 9.81;  // m/s^2, > 0

  // True if any of the quadrotor limits above is set.
  bool HasNormLimits() const { return max_speed || max_acceleration_norm || max_thrust || min_thrust || max_tilt; }
  // Optional bound lambda_a on the change of each axis' acceleration between consecutive cells
  // (paper eqs. 44-45) and against the boundary accelerations (eqs. 48-49), m/s^2 per cell.
  // Absent: none of these rows exist.
  std::optional<double> max_acceleration_change;
  // Optional per-axis jerk limit |jerk_axis| <= max_jerk(axis), m/s^3; each > 0 and finite. When
  // set, the temporal stage plans a jerk-limited profile: acceleration continuous everywhere (at
  // piece joints and at both ends too), and velocity, acceleration and jerk within their limits on
  // every whole cell. Absent: the paper's profiles, whose acceleration steps between cells.
  std::optional<Eigen::Vector3d> max_jerk;
};

// The quadrotor's quantities, in one place for the temporal stage's dense limit check and the
// simulator's flight check: the mass-normalized thrust a + g e3 at acceleration a (gravity along
// -z), and its tilt from the vertical (rad).
inline Eigen::Vector3d ThrustVector(const Eigen::Vector3d& acceleration, double gravity) {
  return acceleration + Eigen::Vector3d(0.0, 0.0, gravity);
}
inline double Tilt(const Eigen::Vector3d& thrust) { return std::atan2(thrust.head<2>().norm(), thrust(2)); }

// The extremes of the quadrotor's quantities along a trajectory, folded in state by state, and
// their ratios to the limits.
struct QuadrotorExtremes {
  double speed = 0.0;                                           // largest ||v||, m/s
  double acceleration_norm = 0.0;                               // largest ||a||, m/s^2
  double max_thrust = 0.0;                                      // largest ||a + g e3||, m/s^2
  double min_thrust = std::numeric_limits<double>::infinity();  // smallest ||a + g e3||, m/s^2
  double tilt = 0.0;                                            // largest tilt of a + g e3, rad

  // Folds in the state (velocity v, acceleration a).
  void Note(const Eigen::Vector3d& v, const Eigen::Vector3d& a, double gravity) {
    speed = std::max(speed, v.norm());
    acceleration_norm = std::max(acceleration_norm, a.norm());
    const Eigen::Vector3d thrust = ThrustVector(a, gravity);
    max_thrust = std::max(max_thrust, thrust.norm());
    min_thrust = std::min(min_thrust, thrust.norm());
    tilt = std::max(tilt, Tilt(thrust));
  }

  // The ratios to the limits that are set, into out's max_speed_ratio, max_acceleration_norm_ratio,
  // max_thrust_ratio, min_thrust_ratio (the limit over the smallest thrust: above 1 when the thrust
  // falls below it) and max_tilt_ratio (TemporalResult, FeasibilityReport).
  template <typename Ratios>
  void WriteRatios(const VehicleLimits& limits, Ratios* out) const {
    if (limits.max_speed) out->max_speed_ratio = speed / *limits.max_speed;
    if (limits.max_acceleration_norm)
      out->max_acceleration_norm_ratio = acceleration_norm / *limits.max_acceleration_norm;
    if (limits.max_thrust) out->max_thrust_ratio = max_thrust / *limits.max_thrust;
    if (limits.min_thrust) {
      out->min_thrust_ratio =
          min_thrust > 0.0 ? *limits.min_thrust / min_thrust : std::numeric_limits<double>::infinity();
    }
    if (limits.max_tilt) out->max_tilt_ratio = tilt / *limits.max_tilt;
  }
};

}  // namespace timeopt
