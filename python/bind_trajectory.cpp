// The Python module's trajectories.

#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>

#include "timeopt/conic/cbf.h"
#include "timeopt/conic/problem.h"
#include "timeopt/conic/solver.h"
#include "timeopt/core/enum_strings.h"
#include "timeopt/core/errors.h"
#include "timeopt/core/files.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/io/planner_io.h"
#include "timeopt/io/sim_io.h"
#include "timeopt/io/temporal_io.h"
#include "timeopt/io/trajectory_io.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/planner/planner.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/version.h"
#include "timeopt/viz/plan_page.h"
#include "bindings.h"
#include "pickle_state.h"

namespace timeopt::python {
namespace {

// Samples of a trajectory at the given times: (p, v, a, j), each (N, 3).
py::tuple Sample(const Trajectory& trajectory, const py::handle& times) {
  const auto t = AsDoubles(times, "ts");
  if (t.ndim() > 1) throw py::value_error("ts: expected a 1-D array of times, got shape " + ShapeText(t));
  const Eigen::Index n = t.ndim() == 0 ? 1 : t.shape(0);
  Eigen::Matrix3Xd p(3, n), v(3, n), a(3, n), j(3, n);
  {
    py::gil_scoped_release release;
    for (Eigen::Index i = 0; i < n; ++i) {
      const TrajectoryState s = trajectory.Evaluate(t.data()[i]);
      p.col(i) = s.position;
      v.col(i) = s.velocity;
      a.col(i) = s.acceleration;
      j.col(i) = s.jerk;
    }
  }
  return py::make_tuple(ToRows(p), ToRows(v), ToRows(a), ToRows(j));
}

}  // namespace

void BindTrajectories(py::module_& m) {
  // ---- trajectories ----
  py::class_<Trajectory>(m, "Trajectory", "A curve traversed by a temporal profile: p, v, a, j against time.")
      .def(py::init([](const PiecewiseCurve& curve, const TemporalResult& result) {
             if (!result.is_success()) {
               throw py::value_error(std::string("Trajectory: the result is ") + ToString(result.status) +
                                     ", not optimal");
             }
             return Trajectory(curve, result.profile);
           }),
           py::arg("curve"), py::arg("result"))
      .def_property_readonly("duration", &Trajectory::duration)
      .def("sample", &Sample, py::arg("ts"),
           "(p, v, a, j) at the times ts, each an (N, 3) array; times clamp to [0, duration].")
      .def(
          "sample_rate",
          [](const Trajectory& t, double rate_hz) {
            const std::vector<TrajectoryState> s = t.Sample(rate_hz);
            std::vector<double> times;
            for (const TrajectoryState& state : s) times.push_back(state.t);
            return py::make_tuple(ToArray(times), Sample(t, ToArray(times)));
          },
          py::arg("rate_hz"), "(ts, (p, v, a, j)) at rate_hz from 0, with the end.")
      .def(py::pickle([](const Trajectory& t) { return py::make_tuple("Trajectory", TrajectoryToJson(t, -1)); },
                      [](const py::tuple& state) {
                        if (state.size() != 2 || !py::isinstance<py::str>(state[0]) ||
                            state[0].cast<std::string>() != "Trajectory") {
                          throw py::value_error("unpickling Trajectory: not a timeopt Trajectory state");
                        }
                        return ParseTrajectoryJson(state[1].cast<std::string>(), "pickled trajectory");
                      }))
      .def_static("load", &ReadTrajectoryJson, py::arg("path"),
                  "Reads a trajectory file (--trajectory of plan, temporal, waypoints; docs/formats.md).")
      .def(
          "save", [](const Trajectory& t, const std::string& path) { WriteTrajectoryJson(t, path); }, py::arg("path"),
          "Writes the trajectory file: curve and profile, exact; load() gives back the same samples to the bit.")
      .def(
          "to_json", [](const Trajectory& t) { return TrajectoryToJson(t); }, "The trajectory file's JSON text.")
      .def_static(
          "from_json", [](const std::string& text) { return ParseTrajectoryJson(text); }, py::arg("text"))
      .def(
          "to_html",
          [](const Trajectory& t, const std::string& path, const VehicleLimits* limits, const OccupancyMap* map,
             const std::string& title) {
            VehicleLimits drawn;
            if (limits != nullptr) {
              drawn = *limits;
            } else {
              drawn.max_velocity.setConstant(std::numeric_limits<double>::infinity());
              drawn.max_acceleration.setConstant(std::numeric_limits<double>::infinity());
              drawn.max_jerk.reset();
            }
            PlanPageOptions page;
            page.title = title;
            page.summary = {{"T", std::to_string(t.duration()) + " s"},
                            {"profile", t.profile().jerk_limited() ? "jerk-limited" : "without a jerk limit"}};
            WritePlanPageHtml(t, drawn, map, path, page);
          },
          py::arg("path"), py::arg("limits") = nullptr, py::arg("map") = nullptr,
          py::arg("title") = "timeopt trajectory",
          "Writes the 3D page (one HTML file; docs/formats.md): the path coloured by speed, map voxels near it, "
          "playback and plots with the limits given.")
      .def(
          "yaw",
          [](const Trajectory& t, const py::handle& ts, const std::string& yaw, double max_yaw_rate) {
            const auto times = AsDoubles(ts, "ts");
            if (times.ndim() != 1)
              throw py::value_error("ts: expected a 1-D array of times, got shape " + ShapeText(times));
            const std::vector<double> grid(times.data(), times.data() + times.shape(0));
            const YawProfile profile = PlanYaw(t, grid, ParseYawSpec(yaw, max_yaw_rate));
            return py::make_tuple(ToArray(profile.yaw), ToArray(profile.rate));
          },
          py::arg("ts"), py::arg("yaw") = "velocity", py::arg("max_yaw_rate") = YawOptions().max_rate,
          "(yaw, yaw_rate) at the increasing times ts (ENU, rad and rad/s): 'fixed:RAD', 'velocity' or 'goal', "
          "continuous, within max_yaw_rate, linear between the times.");
}

}  // namespace timeopt::python
