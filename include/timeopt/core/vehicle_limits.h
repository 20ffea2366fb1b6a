#pragma once

// The vehicle's limits, shared by the modules that plan against them (temporal) and the ones that
// check a flight against them (sim), so that neither includes the other.

#include <optional>

#include <Eigen/Core>

namespace timeopt {

struct VehicleLimits {
  // Per-axis velocity limit |v_axis| <= max_velocity(axis), m/s; each > 0 and finite.
  Eigen::Vector3d max_velocity = Eigen::Vector3d::Constant(2.0);
  // Per-axis acceleration limit |acc_axis| <= max_acceleration(axis), m/s^2; each > 0 and finite.
  Eigen::Vector3d max_acceleration = Eigen::Vector3d::Constant(1.0);
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
