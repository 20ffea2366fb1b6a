#pragma once

// The vehicle's limits, shared by the modules that plan against them (temporal) and the ones that
// check a flight against them (sim), so that neither includes the other.

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

}  // namespace timeopt
