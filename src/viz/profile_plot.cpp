#include "timeopt/viz/profile_plot.h"

#include <stdexcept>

#include "timeopt/viz/plot.h"

namespace timeopt {

void WriteProfilePlotPng(const Trajectory& trajectory, const VehicleLimits& limits, const std::string& path,
                         int samples) {
  if (samples < 2) throw std::invalid_argument("WriteProfilePlotPng: samples must be >= 2");
  const double T = trajectory.duration();
  std::vector<double> t(static_cast<size_t>(samples)), speed(t.size());
  std::vector<double> v[3], a[3];
  for (int axis = 0; axis < 3; ++axis) {
    v[axis].resize(t.size());
    a[axis].resize(t.size());
  }
  for (int i = 0; i < samples; ++i) {
    t[i] = T * i / (samples - 1);
    const TrajectoryState s = trajectory.Evaluate(t[i]);
    speed[i] = s.velocity.norm();
    for (int axis = 0; axis < 3; ++axis) {
      v[axis][i] = s.velocity(axis);
      a[axis][i] = s.acceleration(axis);
    }
  }
  const std::array<double, 3> colors[3] = {{0.85, 0.2, 0.15}, {0.15, 0.6, 0.2}, {0.15, 0.3, 0.85}};
  const char* names[3] = {"x", "y", "z"};
  const auto limit_series = [&](double value, const std::string& label, const std::array<double, 3>& rgb) {
    return PlotSeries{label, {0.0, T}, {value, value}, rgb, true};
  };

  PlotPanel speed_panel{"speed |v|", "t [s]", "m/s", {}, false};
  speed_panel.series.push_back(PlotSeries{"|v|", t, speed, {0.1, 0.1, 0.1}, false});
  if (limits.max_speed) speed_panel.series.push_back(limit_series(*limits.max_speed, "max_speed", {0.4, 0.4, 0.4}));
  PlotPanel vel_panel{"velocity per axis (dashed: +-max_velocity)", "t [s]", "m/s", {}, false};
  PlotPanel acc_panel{"acceleration per axis (dashed: +-max_acceleration)", "t [s]", "m/s^2", {}, false};
  for (int axis = 0; axis < 3; ++axis) {
    vel_panel.series.push_back(PlotSeries{std::string("v") + names[axis], t, v[axis], colors[axis], false});
    acc_panel.series.push_back(PlotSeries{std::string("a") + names[axis], t, a[axis], colors[axis], false});
  }
  for (int axis = 0; axis < 3; ++axis) {
    const bool same_v = axis > 0 && limits.max_velocity(axis) == limits.max_velocity(0);
    const bool same_a = axis > 0 && limits.max_acceleration(axis) == limits.max_acceleration(0);
    const std::array<double, 3> grey = {0.4, 0.4, 0.4};
    // No line for an axis without a per-axis limit (+infinity: the quadrotor's norms bound it).
    if (!same_v && std::isfinite(limits.max_velocity(axis))) {
      const auto rgb = limits.max_velocity.isConstant(limits.max_velocity(0)) ? grey : colors[axis];
      vel_panel.series.push_back(limit_series(limits.max_velocity(axis), "", rgb));
      vel_panel.series.push_back(limit_series(-limits.max_velocity(axis), "", rgb));
    }
    if (!same_a && std::isfinite(limits.max_acceleration(axis))) {
      const auto rgb = limits.max_acceleration.isConstant(limits.max_acceleration(0)) ? grey : colors[axis];
      acc_panel.series.push_back(limit_series(limits.max_acceleration(axis), "", rgb));
      acc_panel.series.push_back(limit_series(-limits.max_acceleration(axis), "", rgb));
    }
  }
  WritePlotPng({speed_panel, vel_panel, acc_panel}, path);
}

}  // namespace timeopt
