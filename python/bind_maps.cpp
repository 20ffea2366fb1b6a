// The Python module's maps, exports and distance fields.

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

namespace timeopt::python {

void BindMaps(py::module_& m) {
  // ---- maps ----
  py::class_<OccupancyMap>(m, "OccupancyMap", "An OctoMap occupancy map (.bt or .ot).")
      .def_static(
          "load",
          [](const std::string& path, const std::string& unknown) {
            UnknownSpace u;
            if (!FromString(unknown, &u))
              throw py::value_error("unknown: expected 'free' or 'occupied', got '" + unknown + "'");
            return OccupancyMap::Load(path, u);
          },
          py::arg("path"), py::arg("unknown") = "free")
      .def_property_readonly("resolution", &OccupancyMap::resolution)
      .def_property_readonly("bounds",
                             [](const OccupancyMap& map) {
                               const Eigen::AlignedBox3d b = map.Bounds();
                               return py::make_tuple(ToArray(Eigen::Vector3d(b.min())),
                                                     ToArray(Eigen::Vector3d(b.max())));
                             })
      .def(
          "is_occupied",
          [](const OccupancyMap& map, const py::handle& points) {
            const Eigen::Matrix3Xd p = Points(points, "points");
            py::array_t<bool> out(p.cols());
            auto r = out.mutable_unchecked<1>();
            for (Eigen::Index i = 0; i < p.cols(); ++i) r(i) = map.IsOccupied(p.col(i));
            return out;
          },
          py::arg("points"));

  // ---- exports ----
  m.def(
      "export",
      [](const Trajectory& trajectory, const std::string& format, const std::string& path, double rate_hz,
         const std::string& yaw, double max_yaw_rate, const OccupancyMap* map, double voxel_radius,
         double max_position_error, double max_velocity_error, double max_acceleration_error) {
        ExportFormat kind = ExportFormat::kCsv;
        if (!FromString(format, &kind)) {
          throw py::value_error("export: format must be " + EnumChoices(kExportFormats) + ", got '" + format + "'");
        }
        ExportOptions options;
        options.rate_hz = rate_hz;
        options.yaw = ParseYawSpec(yaw, max_yaw_rate);
        options.fit.max_position_error = max_position_error;
        options.fit.max_velocity_error = max_velocity_error;
        options.fit.max_acceleration_error = max_acceleration_error;
        options.map = map;
        options.voxel_radius = voxel_radius;
        WriteExport(trajectory, kind, path, options);
      },
      py::arg("trajectory"), py::arg("format"), py::arg("path"), py::arg("rate_hz") = kDefaultSampleRateHz,
      py::arg("yaw") = "velocity", py::arg("max_yaw_rate") = YawOptions().max_rate, py::arg("map") = nullptr,
      py::arg("voxel_radius") = 1.0, py::arg("max_position_error") = PolynomialFitOptions().max_position_error,
      py::arg("max_velocity_error") = PolynomialFitOptions().max_velocity_error,
      py::arg("max_acceleration_error") = PolynomialFitOptions().max_acceleration_error,
      "Writes the trajectory as `timeopt export` does: format csv, polynomial, px4 or rosbag (docs/formats.md).");

  py::class_<Esdf>(m, "Esdf", "A Euclidean signed distance field (metres; negative inside obstacles) with gradients.")
      .def_static(
          "from_map",
          [](const OccupancyMap& map, const py::object& box_min, const py::object& box_max, double max_memory_mb) {
            std::optional<Eigen::AlignedBox3d> box;
            if (!box_min.is_none() || !box_max.is_none())
              box = Eigen::AlignedBox3d(Vec3(box_min, "box_min"), Vec3(box_max, "box_max"));
            const int64_t budget = BudgetBytes(max_memory_mb);
            py::gil_scoped_release release;
            return Esdf::FromMap(map, box, budget);
          },
          py::arg("map"), py::arg("box_min") = py::none(), py::arg("box_max") = py::none(),
          py::arg("max_memory_mb") = 0.0,
          "The field over the map's known box, or over [box_min, box_max]. max_memory_mb > 0: a budget for its\n"
          "peak memory (9 bytes per voxel), refused with ValueError before allocating. Releases the GIL.")
      .def_property_readonly("resolution", &Esdf::resolution)
      .def_property_readonly("memory_bytes", &Esdf::memory_bytes)
      .def_property_readonly(
          "domain",
          [](const Esdf& e) {
            const Eigen::AlignedBox3d d = e.domain();
            return py::make_tuple(ToArray(Eigen::Vector3d(d.min())), ToArray(Eigen::Vector3d(d.max())));
          },
          "(first voxel centre, last voxel centre): where the field interpolates its centre values.")
      .def(
          "distance",
          [](const Esdf& e, const py::handle& points) {
            const Eigen::Matrix3Xd p = Points(points, "points");
            Eigen::VectorXd d(p.cols());
            for (Eigen::Index i = 0; i < p.cols(); ++i) d(i) = e.Distance(p.col(i));
            return ToArray(d);
          },
          py::arg("points"), "Distances at (N, 3) points (trilinear): (N,).")
      .def(
          "distance_and_gradient",
          [](const Esdf& e, const py::handle& points) {
            const Eigen::Matrix3Xd p = Points(points, "points");
            Eigen::VectorXd d;
            Eigen::Matrix3Xd g;
            e.Distances(p, &d, &g);
            return py::make_tuple(ToArray(d), ToRows(g));
          },
          py::arg("points"), "(distances (N,), gradients (N, 3)) at (N, 3) points.");
}

}  // namespace timeopt::python
