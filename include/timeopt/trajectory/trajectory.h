#pragma once

// A time-parameterized trajectory p(t) = f(s(t)): the spatial curve composed with the temporal
// profile. By the chain rule
//   v = f' sdot,   acc = f'' sdot^2 + f' sddot,   jerk = f''' sdot^3 + 3 f'' sdot sddot + f' sdddot,
// where sdddot = 0 on the linear cells of a constructor-made profile and not on the cells of a
// jerk-limited one (see temporal_profile.h).

#include <vector>

#include <Eigen/Core>

#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt {

// The rate at which the tools write trajectory samples unless told otherwise: 100 Hz, a common
// setpoint rate of flight controllers' position loops.
inline constexpr double kDefaultSampleRateHz = 100.0;

// The chain rule above, the one place it is written: the trajectory's states (Trajectory::AtPoint)
// and the temporal stage's dense limit check both take it from here, with the curve's first,
// second and third derivatives at s and the profile's sdot, sddot, sdddot there.
inline Eigen::Vector3d ChainVelocity(const Eigen::Vector3d& f1, double sdot) { return f1 * sdot; }
inline Eigen::Vector3d ChainAcceleration(const Eigen::Vector3d& f1, const Eigen::Vector3d& f2, double sdot,
                                         double sddot) {
  return f2 * sdot * sdot + f1 * sddot;
}
inline Eigen::Vector3d ChainJerk(const Eigen::Vector3d& f1, const Eigen::Vector3d& f2, const Eigen::Vector3d& f3,
                                 double sdot, double sddot, double sdddot) {
  Eigen::Vector3d jerk = f3 * sdot * sdot * sdot + 3.0 * f2 * sdot * sddot;
  // Skipped when zero (every linear cell) so that those results stay bit-for-bit what they were
  // (adding 0 would turn a -0 into +0).
  if (sdddot != 0.0) jerk += f1 * sdddot;
  return jerk;
}

struct TrajectoryState {
  double t = 0.0;                                          // s
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // m/s
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s^2
  Eigen::Vector3d jerk = Eigen::Vector3d::Zero();          // m/s^3
};

class Trajectory {
 public:
  // Throws std::invalid_argument when the profile's piece count differs from the curve's.
  Trajectory(PiecewiseCurve curve, TemporalProfile profile);

  double duration() const { return profile_.total_time(); }
  const PiecewiseCurve& curve() const { return curve_; }
  const TemporalProfile& profile() const { return profile_; }

  // State at time t, clamped to [0, duration()].
  TrajectoryState Evaluate(double t) const;
  // The state where the parameter is at `point` (of this trajectory's profile: AtTime, AtS or
  // InCell), by the chain rule above; t is copied into the state unchanged.
  TrajectoryState AtPoint(const TemporalProfile::Point& point, double t) const;
  // States at t = 0, 1/rate, 2/rate, ... and at t = duration(). rate_hz > 0 (throws otherwise).
  // At most kMaxSamples states (throws above it, before allocating).
  std::vector<TrajectoryState> Sample(double rate_hz) const;
  // Throws std::invalid_argument where Sample(rate_hz) would (a rate that is not a positive
  // number, or more than kMaxSamples states), so that a caller can refuse a request before it
  // writes anything else.
  void CheckSampleRate(double rate_hz) const;
  static constexpr double kMaxSamples = 1e8;

 private:
  PiecewiseCurve curve_;
  TemporalProfile profile_;
};

}  // namespace timeopt
