#include "timeopt/trajectory/yaw.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>

#include "timeopt/core/enum_strings.h"

namespace timeopt {

const char* ToString(YawMode mode) {
  switch (mode) {
    case YawMode::kFixed:
      return "fixed";
    case YawMode::kVelocity:
      return "velocity";
    case YawMode::kGoal:
      return "goal";
  }
  return "unknown";
}

bool FromString(const std::string& text, YawMode* mode) { return EnumFromString(text, kYawModes, mode); }

void YawOptions::Validate() const {
  if (!std::isfinite(fixed_yaw)) throw std::invalid_argument("yaw: fixed_yaw must be a finite number of radians");
  if (!(max_rate > 0.0) || !std::isfinite(max_rate)) {
    throw std::invalid_argument("yaw: max_rate must be a positive finite number of rad/s");
  }
}

YawOptions ParseYawSpec(const std::string& spec, double max_rate) {
  YawOptions options;
  options.max_rate = max_rate;
  const std::string fixed = "fixed:";
  if (spec.rfind(fixed, 0) == 0) {
    const std::string number = spec.substr(fixed.size());
    char* end = nullptr;
    const double value = std::strtod(number.c_str(), &end);
    if (number.empty() || *end != '\0' || !std::isfinite(value)) {
      throw std::invalid_argument("yaw: expected fixed:RAD with a finite number of radians, got '" + spec + "'");
    }
    options.mode = YawMode::kFixed;
    options.fixed_yaw = value;
  } else if (!FromString(spec, &options.mode) || options.mode == YawMode::kFixed) {
    throw std::invalid_argument("yaw: expected fixed:RAD, velocity or goal, got '" + spec + "'");
  }
  options.Validate();
  return options;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// a - b wrapped into [-pi, pi).
double Wrapped(double difference) {
  const double r = std::remainder(difference, 2.0 * kPi);  // in [-pi, pi]
  return r >= kPi ? r - 2.0 * kPi : r;
}

}  // namespace

YawProfile PlanYaw(const Trajectory& trajectory, const std::vector<double>& times, const YawOptions& options) {
  options.Validate();
  if (times.empty()) throw std::invalid_argument("yaw: no times given");
  for (size_t i = 0; i < times.size(); ++i) {
    if (!std::isfinite(times[i])) throw std::invalid_argument("yaw: time " + std::to_string(i) + " is not finite");
    if (i > 0 && !(times[i] > times[i - 1])) {
      throw std::invalid_argument("yaw: times must increase strictly (time " + std::to_string(i) + ")");
    }
  }
  const size_t n = times.size();
  YawProfile out;
  out.t = times;
  out.yaw.assign(n, options.fixed_yaw);
  out.rate.assign(n, 0.0);
  if (options.mode == YawMode::kFixed) return out;

  // The target at each time, where the mode defines one.
  std::vector<std::optional<double>> target(n);
  if (options.mode == YawMode::kVelocity) {
    std::vector<double> vx(n), vy(n);
    double fastest = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const TrajectoryState x = trajectory.Evaluate(times[i]);
      vx[i] = x.velocity.x();
      vy[i] = x.velocity.y();
      fastest = std::max(fastest, std::hypot(vx[i], vy[i]));
    }
    for (size_t i = 0; i < n; ++i) {
      if (fastest > 0.0 && std::hypot(vx[i], vy[i]) > kHoverSpeedShare * fastest) target[i] = std::atan2(vy[i], vx[i]);
    }
  } else {
    const TrajectoryState end = trajectory.Evaluate(trajectory.duration());
    std::vector<double> dx(n), dy(n);
    double extent = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const TrajectoryState x = trajectory.Evaluate(times[i]);
      dx[i] = end.position.x() - x.position.x();
      dy[i] = end.position.y() - x.position.y();
      extent = std::max(extent, std::hypot(dx[i], dy[i]));
    }
    for (size_t i = 0; i < n; ++i) {
      if (extent > 0.0 && std::hypot(dx[i], dy[i]) > kGoalHoldShare * extent) target[i] = std::atan2(dy[i], dx[i]);
    }
  }
  // Held where undefined: the first defined target before it, the last one after.
  std::optional<double> held;
  for (size_t i = 0; i < n && !held; ++i) held = target[i];
  if (!held) return out;  // nothing defines a heading: fixed_yaw throughout
  for (size_t i = 0; i < n; ++i) {
    if (target[i])
      held = target[i];
    else
      target[i] = held;
  }
  // Followed causally within the rate limit, the short way round; the start faces its target.
  out.yaw[0] = *target[0];
  for (size_t i = 0; i + 1 < n; ++i) {
    const double dt = times[i + 1] - times[i];
    const double wanted = Wrapped(*target[i + 1] - out.yaw[i]) / dt;
    out.rate[i] = std::clamp(wanted, -options.max_rate, options.max_rate);
    out.yaw[i + 1] = out.yaw[i] + out.rate[i] * dt;
  }
  return out;
}

}  // namespace timeopt
