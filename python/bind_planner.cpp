// The Python module's planner and simulated flights.

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

// ---- the planner ----

PlannerOptions PlannerOptionsFrom(const py::kwargs& kwargs, double* region_margin, bool* whole_map,
                                  double* max_memory_mb) {
  PlannerOptions o;
  if (kwargs.contains("config")) o = ReadPlannerConfigJson(kwargs["config"].cast<std::string>(), o);
  for (const auto& item : kwargs) {
    const std::string key = item.first.cast<std::string>();
    const py::handle value = item.second;
    if (key == "config") continue;
    if (key == "max_velocity" || key == "max_acceleration" || key == "max_jerk" || key == "max_speed" ||
        key == "max_acceleration_norm" || key == "max_thrust" || key == "min_thrust" || key == "max_tilt") {
      SetLimit(&o.limits, key, value);
    } else if (key == "robot_radius") {
      o.robot_radius = value.cast<double>();
    } else if (key == "safety_margin") {
      o.safety_margin = value.cast<double>();
    } else if (key == "K") {
      o.temporal_cells_per_piece = CellCount(value, "K");
    } else if (key == "constraint_mode") {
      o.constraint_mode = ModeFrom(value.cast<std::string>());
    } else if (key == "start_velocity") {
      o.start_velocity = Vec3(value, "start_velocity");
    } else if (key == "start_acceleration") {
      o.start_acceleration = Vec3(value, "start_acceleration");
    } else if (key == "max_attempts") {
      o.max_attempts = value.cast<int>();
    } else if (key == "region_margin") {
      *region_margin = value.cast<double>();
    } else if (key == "whole_map") {
      *whole_map = value.cast<bool>();
    } else if (key == "max_memory_mb") {
      *max_memory_mb = value.cast<double>();
    } else {
      throw py::type_error(
          "plan: unknown keyword '" + key +
          "' (expected config, max_velocity, max_acceleration, max_jerk, max_speed, "
          "max_acceleration_norm, max_thrust, min_thrust, max_tilt, robot_radius, safety_margin, K, "
          "constraint_mode, start_velocity, start_acceleration, max_attempts, region_margin, whole_map, "
          "max_memory_mb)");
    }
  }
  std::string error;
  if (!o.IsValid(&error)) throw py::value_error("plan: " + error);
  return o;
}

}  // namespace

void BindPlanner(py::module_& m) {
  // ---- planning ----
  py::class_<PlanResult>(m, "PlanResult",
                         "A plan: status, the spatial curve, the temporal result and the stages' figures.")
      .def_readonly("status", &PlanResult::status)
      .def_readonly("message", &PlanResult::message)
      .def_readonly("curve", &PlanResult::curve)
      .def_readonly("temporal", &PlanResult::temporal)
      .def_property_readonly("waypoints", [](const PlanResult& r) { return ToRows(r.waypoints); })
      .def_readonly("path_length", &PlanResult::path_length)
      .def_readonly("min_clearance", &PlanResult::min_clearance)
      .def_readonly("min_interior_speed", &PlanResult::min_interior_speed)
      .def_readonly("min_curvature_radius", &PlanResult::min_curvature_radius)
      .def_readonly("start_scale", &PlanResult::start_scale)
      .def_property_readonly("total_time", [](const PlanResult& r) { return r.temporal.total_time; })
      .def("is_success", &PlanResult::is_success)
      .def(
          "trajectory",
          [](const PlanResult& r) {
            if (!r.is_success())
              throw py::value_error(std::string("PlanResult.trajectory: the plan is ") + ToString(r.status));
            return Trajectory(r.curve, r.temporal.profile);
          },
          "The planned trajectory (successful plans only).")
      .def(
          "summary", [](const PlanResult& r) { return py::module_::import("json").attr("loads")(PlanResultToJson(r)); },
          "The plan's summary as a dict (the plan's own keys of `timeopt plan`'s JSON).")
      .def(
          "to_json", [](const PlanResult& r) { return PlanResultToJson(r); }, "The plan's summary as JSON text.")
      .def(
          "to_html",
          [](const PlanResult& r, const std::string& path, const OccupancyMap* map, const VehicleLimits* limits) {
            if (!r.is_success())
              throw py::value_error(std::string("PlanResult.to_html: the plan is ") + ToString(r.status));
            const VehicleLimits drawn = limits != nullptr ? *limits : PlannerOptions().limits;
            PlanPageOptions page;
            page.title = "timeopt plan";
            std::ostringstream T, length, clearance;
            T << r.temporal.total_time << " s";
            length << r.path_length << " m";
            clearance << r.min_clearance << " m";
            page.summary = {{"T", T.str()},
                            {"status", ToString(r.status)},
                            {"path length", length.str()},
                            {"clearance", clearance.str()},
                            {"profile", r.temporal.profile.jerk_limited() ? "jerk-limited" : "without a jerk limit"}};
            WritePlanPageHtml(Trajectory(r.curve, r.temporal.profile), drawn, map, path, page);
          },
          py::arg("path"), py::arg("map") = nullptr, py::arg("limits") = nullptr,
          "Writes the 3D page of a successful plan (docs/formats.md): pass the map for its voxels and the limits "
          "the plan was made with (default: the planner's defaults).")
      .def(py::pickle(&pickle_state::PlanState, &pickle_state::PlanFromState))
      .def("__repr__", [](const PlanResult& r) {
        std::ostringstream s;
        s << "<PlanResult " << ToString(r.status);
        if (r.is_success())
          s << " T=" << r.temporal.total_time << " s, " << r.path_length << " m, " << r.curve.num_pieces() << " pieces";
        s << ">";
        return s.str();
      });

  m.def(
      "plan",
      [](const py::object& map, const py::handle& start, const py::handle& goal, const py::kwargs& kwargs) {
        const Eigen::Vector3d s = Vec3(start, "start"), g = Vec3(goal, "goal");
        double region_margin = kDefaultRegionMargin;
        bool whole_map = false;
        double max_memory_mb = 0.0;
        const PlannerOptions options = PlannerOptionsFrom(kwargs, &region_margin, &whole_map, &max_memory_mb);
        const int64_t budget = BudgetBytes(max_memory_mb);
        if (py::isinstance<Esdf>(map)) {
          const Esdf& esdf = map.cast<const Esdf&>();
          py::gil_scoped_release release;
          return Plan(esdf, s, g, options);
        }
        const OccupancyMap occupancy =
            py::isinstance<OccupancyMap>(map) ? map.cast<OccupancyMap>() : OccupancyMap::Load(map.cast<std::string>());
        if (!(region_margin >= 0.0)) throw py::value_error("region_margin: expected >= 0");
        py::gil_scoped_release release;
        const Eigen::AlignedBox3d region = PlanRegion(s, g, region_margin);
        const Esdf esdf =
            whole_map ? Esdf::FromMap(occupancy, std::nullopt, budget) : Esdf::FromMapRegion(occupancy, region, budget);
        return Plan(esdf, s, g, options);
      },
      py::arg("map"), py::arg("start"), py::arg("goal"),
      "Plans from start to goal on a map (an Esdf, an OccupancyMap or a .bt/.ot path; the field then covers the\n"
      "start-goal box grown by region_margin = 10 m unless whole_map=True), as `timeopt plan` does. Keywords:\n"
      "config (a planner config JSON path), max_velocity, max_acceleration, max_jerk, quadrotor limits, robot_radius,\n"
      "safety_margin, K, constraint_mode, start_velocity, start_acceleration, max_attempts, max_memory_mb (a budget\n"
      "for the field's peak memory; 0, the default: none). Releases the GIL.");

  // ---- simulation ----
  py::class_<FeasibilityReport>(m, "FlightReport",
                                "A simulated flight: whether every limit held, and the largest ratios.")
      .def_readonly("feasible", &FeasibilityReport::feasible)
      .def_readonly("tolerance", &FeasibilityReport::tolerance,
                    "The verdict's relative slack: 0.01 with a jerk limit, 1e-9 without, unless given.")
      .def_readonly("message", &FeasibilityReport::message)
      .def_readonly("max_velocity_ratio", &FeasibilityReport::max_velocity_ratio)
      .def_readonly("max_acceleration_ratio", &FeasibilityReport::max_acceleration_ratio)
      .def_readonly("max_jerk_ratio", &FeasibilityReport::max_jerk_ratio)
      .def_readonly("max_position_error", &FeasibilityReport::max_position_error)
      .def_readonly("final_position_error", &FeasibilityReport::final_position_error)
      .def_readonly("steps", &FeasibilityReport::steps)
      .def("to_json", [](const FeasibilityReport& r) { return FeasibilityReportToJson(r); })
      .def("__repr__", [](const FeasibilityReport& r) {
        std::ostringstream s;
        s << "<FlightReport " << (r.feasible ? "feasible" : "infeasible") << " |v|/vmax=" << r.max_velocity_ratio
          << " |a|/amax=" << r.max_acceleration_ratio << " tolerance=" << r.tolerance << ">";
        return s.str();
      });

  m.def(
      "simulate",
      [](const Trajectory& trajectory, const VehicleLimits& limits, double bandwidth, double time_step,
         const py::object& vehicle_max_jerk, const py::object& tolerance) {
        QuadrotorSimOptions o;
        o.bandwidth = bandwidth;
        o.time_step = time_step;
        o.limit_tolerance = tolerance.is_none() ? DefaultFlightTolerance(limits) : tolerance.cast<double>();
        if (!vehicle_max_jerk.is_none()) o.max_jerk = Vec3(vehicle_max_jerk, "vehicle_max_jerk", true);
        std::string error;
        if (!o.IsValid(&error)) throw py::value_error("simulate: " + error);
        const QuadrotorSim sim(o);
        py::gil_scoped_release release;
        return sim.Run(trajectory, limits);
      },
      py::arg("trajectory"), py::arg("limits"), py::kw_only(), py::arg("bandwidth") = 10.0, py::arg("time_step") = 1e-3,
      py::arg("vehicle_max_jerk") = py::none(), py::arg("tolerance") = py::none(),
      "Flies the trajectory with the simulated jerk-input quadrotor and checks the limits in continuous time. "
      "tolerance: the verdict's relative slack; None: 0.01 when limits has a jerk limit (the product's flight "
      "criterion, as timeopt plan, waypoints and simulate), 1e-9 otherwise.");
}

}  // namespace timeopt::python
