#pragma once

// A heading for a trajectory: yaw(t), continuous and unwrapped, within a rate limit.
//
// Yaw is measured in the trajectory's own frame (ENU in timeopt's files): from +x toward +y,
// counter-clockwise seen from above, radians. It is computed on a grid of increasing times and is
// linear between them: rate[i] = (yaw[i + 1] - yaw[i]) / (t[i + 1] - t[i]) exactly as stored, and
// rate at the last time is 0 (the trajectory ends at rest or holds there).
//
// The heading each mode wants at time t (the target) is followed causally: from yaw[i] the next
// value turns toward the target the short way round by at most max_rate (t[i + 1] - t[i]). So the
// yaw lags the target where the target turns faster than max_rate, and never exceeds it.
// - kFixed: the target is fixed_yaw throughout (yaw is constant, rate 0).
// - kVelocity: along the horizontal velocity. Where the horizontal speed is below
//   kHoverSpeedShare of the trajectory's largest (hovering, starting, stopping, climbing straight
//   up) the target is held: the last defined one, or before the first one the first one (so the
//   vehicle starts facing where it will go). A trajectory that never moves horizontally keeps
//   fixed_yaw.
// - kGoal: toward the trajectory's end position. Within kGoalHoldShare of the path's horizontal
//   extent from the goal (or where start and goal coincide horizontally) the target is held as
//   above.

#include <array>
#include <string>
#include <vector>

#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

enum class YawMode {
  kFixed,     // a constant heading, YawOptions::fixed_yaw
  kVelocity,  // along the horizontal velocity
  kGoal,      // toward the trajectory's end position
};
inline constexpr std::array<YawMode, 3> kYawModes = {YawMode::kFixed, YawMode::kVelocity, YawMode::kGoal};
const char* ToString(YawMode mode);
bool FromString(const std::string& text, YawMode* mode);

struct YawOptions {
  YawMode mode = YawMode::kVelocity;
  double fixed_yaw = 0.0;  // rad: kFixed's heading, and the others' when nothing defines one
  double max_rate = 1.0;   // rad/s, > 0 and finite

  // Throws std::invalid_argument naming the field (a max_rate that is not a positive finite
  // number, a fixed_yaw that is not finite).
  void Validate() const;
};

// The options a heading spec names: "fixed:RAD", "velocity" or "goal", with max_rate (the
// command line's --yaw and Python's yaw=). Throws std::invalid_argument naming the spec.
YawOptions ParseYawSpec(const std::string& spec, double max_rate);

// Below this share of its largest horizontal speed, a kVelocity heading is held.
inline constexpr double kHoverSpeedShare = 0.01;
// Within this share of the path's horizontal extent from the goal, a kGoal heading is held.
inline constexpr double kGoalHoldShare = 0.01;

struct YawProfile {
  std::vector<double> t;     // s, the grid given
  std::vector<double> yaw;   // rad, unwrapped
  std::vector<double> rate;  // rad/s, |rate| <= max_rate
};

// The yaw of `trajectory` on the increasing times `times` (at least 1; each finite, strictly
// increasing; clamped to [0, duration] for the target only). Throws std::invalid_argument for bad
// options or times.
YawProfile PlanYaw(const Trajectory& trajectory, const std::vector<double>& times, const YawOptions& options);

}  // namespace timeopt
