// The Python module `timeopt` (pybind11): the library's curves, temporal problems and both
// backends, trajectories, maps and distance fields, the planner, the simulated quadrotor and the
// conic solver, with numpy arrays in and out. Solves, plans, flights and field builds release the
// GIL. Errors of the library (std::invalid_argument, std::runtime_error) arrive as ValueError and
// RuntimeError with the library's messages; statuses are enums, as in C++.

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

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <pybind11/eigen.h>
#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "timeopt/conic/cbf.h"
#include "timeopt/version.h"
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
#include "timeopt/viz/plan_page.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/planner/planner.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"
#include "pickle_state.h"
#include "timeopt_batch_source.h"

namespace py = pybind11;

namespace timeopt {
namespace {

using RowMatrixX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// ---- numpy in: shapes checked, with the argument's name in the message ----

std::string ShapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) text += (i ? ", " : "") + std::to_string(a.shape(i));
  return text + (a.ndim() == 1 ? ",)" : ")");
}

// A float64 array from any array-like (lists, ints, float32), or a ValueError naming `name`.
py::array_t<double, py::array::c_style | py::array::forcecast> AsDoubles(const py::handle& value, const char* name) {
  if (value.is_none()) throw py::value_error(std::string(name) + ": expected numbers, got None");
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);  // clears its error
  if (!array) {
    throw py::value_error(std::string(name) + ": expected an array of numbers, got " +
                          std::string(py::str(py::type::of(value).attr("__name__"))));
  }
  return array;
}

// Three numbers: a scalar broadcast to the three axes when `broadcast`, or shape (3,).
Eigen::Vector3d Vec3(const py::handle& value, const char* name, bool broadcast = false) {
  const auto a = AsDoubles(value, name);
  if (broadcast && a.ndim() == 0) return Eigen::Vector3d::Constant(*a.data());
  if (a.ndim() != 1 || a.shape(0) != 3) {
    throw py::value_error(std::string(name) + ": expected 3 values" + (broadcast ? " or one" : "") +
                          ", got shape " + ShapeText(a));
  }
  return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
}

// A cell count K: a Python int (numpy integers too; not a bool or a float) in [1, max], or a
// ValueError naming `name` (pybind's own conversion raised TypeError for 2.5 and took -1).
int CellCount(const py::handle& value, const char* name, int max = kMaxCellsPerPiece) {
  const auto fail = [&](const std::string& got) {
    return py::value_error(std::string(name) + ": expected an integer in [1, " + std::to_string(max) + "], got " + got);
  };
  if (value.is_none() || PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr())) {
    throw fail(std::string(py::str(py::repr(value))));
  }
  const py::int_ integer(py::reinterpret_borrow<py::object>(value));
  int overflow = 0;
  const long long k = PyLong_AsLongLongAndOverflow(integer.ptr(), &overflow);
  if (overflow != 0 || k < 1 || k > max) throw fail(py::repr(integer).cast<std::string>());
  return static_cast<int>(k);
}

// Points as an (N, 3) array (one point of shape (3,) is N = 1).
Eigen::Matrix3Xd Points(const py::handle& value, const char* name) {
  const auto a = AsDoubles(value, name);
  if (a.ndim() == 1 && a.shape(0) == 3) return Eigen::Map<const Eigen::Vector3d>(a.data());
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw py::value_error(std::string(name) + ": expected an (N, 3) array, got shape " + ShapeText(a));
  }
  Eigen::Matrix3Xd points(3, a.shape(0));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (int k = 0; k < 3; ++k) points(k, i) = a.at(i, k);
  }
  return points;
}

Eigen::VectorXd Vector(const py::handle& value, const char* name) {
  const auto a = AsDoubles(value, name);
  if (a.ndim() != 1) throw py::value_error(std::string(name) + ": expected a 1-D array, got shape " + ShapeText(a));
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

// A sparse matrix from a scipy.sparse matrix (anything with tocsc()), or from a dense 2-D array.
Eigen::SparseMatrix<double> Sparse(const py::handle& value, const char* name, Eigen::Index cols) {
  if (value.is_none()) return Eigen::SparseMatrix<double>(0, cols);
  if (py::hasattr(value, "tocsc")) {
    const py::object csc = value.attr("tocsc")();
    const auto shape = csc.attr("shape").cast<std::pair<Eigen::Index, Eigen::Index>>();
    const auto data = AsDoubles(csc.attr("data"), name);
    const auto indices = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(csc.attr("indices"));
    const auto indptr = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(csc.attr("indptr"));
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(static_cast<size_t>(data.size()));
    for (Eigen::Index j = 0; j < shape.second; ++j) {
      for (int64_t k = indptr.at(j); k < indptr.at(j + 1); ++k) {
        if (indices.at(k) < 0 || indices.at(k) >= shape.first) {
          throw py::value_error(std::string(name) + ": a row index is out of range");
        }
        triplets.emplace_back(static_cast<int>(indices.at(k)), static_cast<int>(j), data.at(k));
      }
    }
    Eigen::SparseMatrix<double> m(shape.first, shape.second);
    m.setFromTriplets(triplets.begin(), triplets.end());
    return m;
  }
  const auto a = AsDoubles(value, name);
  if (a.ndim() != 2) throw py::value_error(std::string(name) + ": expected a 2-D array or a scipy.sparse matrix, got shape " + ShapeText(a));
  Eigen::MatrixXd dense(a.shape(0), a.shape(1));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (py::ssize_t j = 0; j < a.shape(1); ++j) dense(i, j) = a.at(i, j);
  }
  return dense.sparseView();
}

// ---- numpy out ----

py::array_t<double> ToArray(const std::vector<double>& v) { return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data()); }

py::array_t<double> ToArray(const Eigen::VectorXd& v) { return py::array_t<double>(v.size(), v.data()); }

py::array_t<double> ToArray(const Eigen::Vector3d& v) { return py::array_t<double>(3, v.data()); }

// An (N, 3) array from 3 x N columns.
py::array_t<double> ToRows(const Eigen::Matrix3Xd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.cols()), static_cast<py::ssize_t>(3)});
  auto r = out.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.cols(); ++i) {
    for (int k = 0; k < 3; ++k) r(i, k) = m(k, i);
  }
  return out;
}

py::object Optional(const std::optional<double>& value) { return value ? py::cast(*value) : py::none(); }

// ---- the temporal solve ----

TemporalBackend BackendFrom(const std::string& name) {
  TemporalBackend backend;
  if (!FromString(name, &backend)) throw py::value_error("solver: expected 'socp' or 'ipopt', got '" + name + "'");
  return backend;
}

// A budget in bytes from max_memory_mb (0: none), or ValueError.
std::int64_t TemporalBudget(double max_memory_mb) {
  if (!(max_memory_mb >= 0.0) || !std::isfinite(max_memory_mb)) {
    throw py::value_error("max_memory_mb: expected a number >= 0 (0: no budget)");
  }
  return static_cast<std::int64_t>(max_memory_mb * 1024 * 1024);
}

// ValueError ("max_memory_mb: ...") when the problem's estimated peak with this backend is above
// the budget (> 0).
void CheckTemporalBudget(const TemporalProblem& problem, TemporalBackend backend, std::int64_t budget) {
  try {
    CheckTemporalMemory(problem, backend, budget);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(std::string("max_memory_mb: ") + e.what());
  }
}

// max_memory_mb > 0: a problem whose TemporalPeakBytes is above it raises ValueError before it is
// solved, and the socp solver's Ipopt fallback keeps to it (as `timeopt temporal --max-memory`).
TemporalResult SolveProblem(const TemporalProblem& problem, const std::string& solver, double max_memory_mb) {
  const std::int64_t budget = TemporalBudget(max_memory_mb);
  const TemporalBackend backend = BackendFrom(solver);
  CheckTemporalBudget(problem, backend, budget);
  std::unique_ptr<TemporalSolver> s = MakeBudgetedTemporalSolver(backend, budget);
  py::gil_scoped_release release;
  return s->Solve(problem);
}

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

// Limits from keyword arguments: per-axis values broadcast from scalars, None for "not set".
void SetLimit(VehicleLimits* l, const std::string& key, const py::handle& value) {
  const auto scalar = [&](std::optional<double>* field) {
    *field = value.is_none() ? std::nullopt : std::optional<double>(value.cast<double>());
  };
  if (key == "max_velocity") {
    l->max_velocity = Vec3(value, "max_velocity", true);
  } else if (key == "max_acceleration") {
    l->max_acceleration = Vec3(value, "max_acceleration", true);
  } else if (key == "max_jerk") {
    l->max_jerk = value.is_none() ? std::nullopt : std::optional<Eigen::Vector3d>(Vec3(value, "max_jerk", true));
  } else if (key == "max_speed") {
    scalar(&l->max_speed);
  } else if (key == "max_acceleration_norm") {
    scalar(&l->max_acceleration_norm);
  } else if (key == "max_thrust") {
    scalar(&l->max_thrust);
  } else if (key == "min_thrust") {
    scalar(&l->min_thrust);
  } else if (key == "max_tilt") {
    scalar(&l->max_tilt);
  } else if (key == "max_acceleration_change") {
    scalar(&l->max_acceleration_change);
  } else if (key == "gravity") {
    l->gravity = value.cast<double>();
  } else {
    throw py::type_error("Limits: unknown keyword '" + key + "'");
  }
}

ConstraintMode ModeFrom(const std::string& text) {
  ConstraintMode mode;
  if (!FromString(text, &mode)) throw py::value_error("constraint_mode: expected 'paper' or 'certified', got '" + text + "'");
  return mode;
}

// ---- the planner ----

// A memory budget in MiB (0: none) as bytes, or a ValueError.
int64_t BudgetBytes(double max_memory_mb) {
  if (!(max_memory_mb >= 0.0)) throw py::value_error("max_memory_mb: expected >= 0 (0: no budget)");
  return static_cast<int64_t>(max_memory_mb * 1024 * 1024);
}

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
      throw py::type_error("plan: unknown keyword '" + key +
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

// ---- the conic solver ----

conic::ConeSpec ConesFrom(const py::dict& cones) {
  conic::ConeSpec spec;
  for (const auto& item : cones) {
    const std::string key = item.first.cast<std::string>();
    if (key == "l") {
      spec.num_nonnegative = item.second.cast<int>();
    } else if (key == "q") {
      spec.soc_dims = item.second.cast<std::vector<int>>();
    } else if (key == "r") {
      spec.rotated_dims = item.second.cast<std::vector<int>>();
    } else {
      throw py::value_error("cones: unknown key '" + key + "' (expected 'l', 'q', 'r')");
    }
  }
  return spec;
}

py::dict ConesTo(const conic::ConeSpec& spec) {
  py::dict d;
  d["l"] = spec.num_nonnegative;
  d["q"] = spec.soc_dims;
  d["r"] = spec.rotated_dims;
  return d;
}

conic::Problem ConicProblemFrom(const py::handle& c, const py::handle& G, const py::handle& h, const py::handle& A,
                                const py::handle& b, const py::dict& cones) {
  conic::Problem p;
  p.c = Vector(c, "c");
  p.G = Sparse(G, "G", p.c.size());
  p.h = Vector(h, "h");
  p.A = Sparse(A, "A", p.c.size());
  p.b = b.is_none() ? Eigen::VectorXd(0) : Vector(b, "b");
  p.cones = ConesFrom(cones);
  p.Validate();  // sizes and cones, std::invalid_argument naming the field
  return p;
}

// The conic solver's options from keyword arguments.
conic::Solver::Options ConicOptionsFrom(const py::kwargs& kwargs) {
  conic::Solver::Options o;
  for (const auto& item : kwargs) {
    const std::string key = item.first.cast<std::string>();
    if (key == "tolerance") {
      const double t = item.second.cast<double>();
      o.feasibility_tolerance = o.absolute_gap_tolerance = o.relative_gap_tolerance = o.infeasibility_tolerance = t;
    } else if (key == "max_iterations") {
      o.max_iterations = item.second.cast<int>();
    } else if (key == "max_solve_time") {
      o.max_solve_time_in_seconds = item.second.cast<double>();
    } else {
      throw py::type_error("conic.solve: unknown keyword '" + key + "' (expected tolerance, max_iterations, max_solve_time)");
    }
  }
  std::string error;
  if (!o.IsValid(&error)) throw py::value_error("conic.solve: " + error);
  return o;
}

template <typename Enum, size_t N>
void BindEnum(py::module_& m, const char* name, const std::array<Enum, N>& values, const char* doc) {
  py::enum_<Enum> e(m, name, doc);
  for (const Enum value : values) e.value(ToString(value), value);
}

}  // namespace
}  // namespace timeopt

PYBIND11_MODULE(timeopt, m) {
  using namespace timeopt;  // NOLINT(build/namespaces): the module's own scope
  m.doc() =
      "Minimum-time quadrotor trajectories by spatial-temporal decoupling (Gao et al., IROS 2018): curves, the\n"
      "temporal problem solved by our conic solver or Ipopt, trajectories, maps, the planner, a simulated\n"
      "quadrotor and the conic solver itself. SI units; arrays are float64 numpy arrays, points (N, 3).";
  m.attr("__version__") = TIMEOPT_VERSION_STRING;

  // A file that cannot be opened or written is an OSError, as Python's own open() makes it.
  py::register_exception<FileError>(m, "FileError", PyExc_OSError);

  BindEnum(m, "TemporalStatus", kTemporalStatuses, "Outcome of a temporal solve (as in C++: a status, not an exception).");
  BindEnum(m, "ConstraintMode", kConstraintModes, "paper: the paper's rows at grid points; certified: limits on whole cells.");
  BindEnum(m, "PlanStatus", kPlanStatuses, "Outcome of a plan.");

  // ---- limits ----
  py::class_<VehicleLimits>(m, "Limits",
                            "Vehicle limits: per-axis max_velocity and max_acceleration (m/s, m/s^2; +inf for none), "
                            "optional per-axis max_jerk, and the quadrotor's max_speed, max_acceleration_norm, max_thrust, "
                            "min_thrust (m/s^2), max_tilt (rad), gravity.")
      .def(py::init([](const py::kwargs& kwargs) {
             VehicleLimits l = FlightLimits();
             for (const auto& item : kwargs) SetLimit(&l, item.first.cast<std::string>(), item.second);
             return l;
           }),
           "Limits(max_velocity=2, max_acceleration=2, max_jerk=10, max_speed=None, ...): scalars apply to all axes; "
           "the defaults are the planner's, a flyable trajectory; max_jerk=None for none (the paper's profile).")
      .def_property(
          "max_velocity", [](const VehicleLimits& l) { return ToArray(l.max_velocity); },
          [](VehicleLimits& l, const py::handle& v) { SetLimit(&l, "max_velocity", v); })
      .def_property(
          "max_acceleration", [](const VehicleLimits& l) { return ToArray(l.max_acceleration); },
          [](VehicleLimits& l, const py::handle& v) { SetLimit(&l, "max_acceleration", v); })
      .def_property(
          "max_jerk", [](const VehicleLimits& l) -> py::object { return l.max_jerk ? py::object(ToArray(*l.max_jerk)) : py::none(); },
          [](VehicleLimits& l, const py::handle& v) { SetLimit(&l, "max_jerk", v); })
      .def_readwrite("max_speed", &VehicleLimits::max_speed)
      .def_readwrite("max_acceleration_norm", &VehicleLimits::max_acceleration_norm)
      .def_readwrite("max_thrust", &VehicleLimits::max_thrust)
      .def_readwrite("min_thrust", &VehicleLimits::min_thrust)
      .def_readwrite("max_tilt", &VehicleLimits::max_tilt)
      .def_readwrite("gravity", &VehicleLimits::gravity)
      .def(py::pickle(&pickle_state::LimitsState, &pickle_state::LimitsFromState))
      .def("__repr__", [](const VehicleLimits& l) {
        std::ostringstream s;
        const auto axes = [&s](const Eigen::Vector3d& v) { s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]"; };
        s << "Limits(max_velocity=";
        axes(l.max_velocity);
        s << ", max_acceleration=";
        axes(l.max_acceleration);
        s << ", max_jerk=";
        if (l.max_jerk) axes(*l.max_jerk);
        else s << "None";
        const auto optional = [&s](const char* name, const std::optional<double>& v) {
          if (v) s << ", " << name << "=" << *v;
        };
        optional("max_speed", l.max_speed);
        optional("max_acceleration_norm", l.max_acceleration_norm);
        optional("max_thrust", l.max_thrust);
        optional("min_thrust", l.min_thrust);
        optional("max_tilt", l.max_tilt);
        optional("max_acceleration_change", l.max_acceleration_change);
        s << ")";
        return s.str();
      });

  // ---- curves ----
  py::class_<PiecewiseCurve>(m, "Curve", "A piecewise polynomial curve f(s), each piece on its own s in [0, 1].")
      .def(py::init([](const py::list& pieces) {
             std::vector<PolynomialPiece> out;
             for (const py::handle& piece : pieces) {
               const auto a = AsDoubles(piece, "pieces[i]");
               if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) < 1) {
                 throw py::value_error("pieces[" + std::to_string(out.size()) +
                                       "]: expected a (3, degree + 1) array of monomial coefficients, got shape " + ShapeText(a));
               }
               PolynomialPiece::Coefficients c(3, a.shape(1));
               for (py::ssize_t k = 0; k < a.shape(1); ++k) {
                 for (int r = 0; r < 3; ++r) c(r, k) = a.at(r, k);
               }
               out.emplace_back(c);
             }
             return PiecewiseCurve(std::move(out));
           }),
           py::arg("pieces"), "Curve(pieces): a list of (3, degree + 1) arrays, row r = axis, column k = coefficient of s^k.")
      .def_static(
          "from_waypoints",
          [](const py::handle& waypoints, const std::string& kind) {
            const Eigen::Matrix3Xd w = Points(waypoints, "waypoints");
            if (kind == "cubic") return NaturalCubicSpline(w);
            if (kind == "minjerk") return MinimumJerkSpline(w);
            throw py::value_error("kind: expected 'cubic' or 'minjerk', got '" + kind + "'");
          },
          py::arg("waypoints"), py::arg("kind") = "minjerk",
          "A curve through (N, 3) waypoints: 'minjerk' (rest to rest, C4 inside) or 'cubic' (natural, C2).")
      .def_static(
          "load", [](const std::string& path) { return ReadCurveJson(path).curve; }, py::arg("path"),
          "A curve from a curve JSON file (docs/formats.md).")
      .def_property_readonly("num_pieces", &PiecewiseCurve::num_pieces)
      .def_property_readonly(
          "pieces",
          [](const PiecewiseCurve& c) {
            py::list out;
            for (const PolynomialPiece& p : c.pieces()) {
              const PolynomialPiece::Coefficients& k = p.coefficients();
              py::array_t<double> a({static_cast<py::ssize_t>(3), static_cast<py::ssize_t>(k.cols())});
              auto r = a.mutable_unchecked<2>();
              for (int row = 0; row < 3; ++row) {
                for (Eigen::Index col = 0; col < k.cols(); ++col) r(row, col) = k(row, col);
              }
              out.append(a);
            }
            return out;
          },
          "The pieces' (3, degree + 1) coefficient arrays.")
      .def(
          "evaluate",
          [](const PiecewiseCurve& c, const py::handle& sigma, int derivative) {
            const auto s = AsDoubles(sigma, "sigma");
            if (s.ndim() > 1) throw py::value_error("sigma: expected a 1-D array, got shape " + ShapeText(s));
            if (derivative < 0) throw py::value_error("derivative: expected >= 0, got " + std::to_string(derivative));
            const Eigen::Index n = s.ndim() == 0 ? 1 : s.shape(0);
            Eigen::Matrix3Xd out(3, n);
            for (Eigen::Index i = 0; i < n; ++i) out.col(i) = c.EvaluateGlobal(s.data()[i], derivative);
            return ToRows(out);
          },
          py::arg("sigma"), py::arg("derivative") = 0,
          "f or its derivative in s at global parameters sigma in [0, num_pieces] (piece floor(sigma)): (N, 3).")
      .def("arc_length", [](const PiecewiseCurve& c) { return c.ArcLength(); }, "Arc length, metres.")
      .def("to_json", [](const PiecewiseCurve& c) { return CurveToJson(c); }, "The curve JSON of docs/formats.md.")
      .def(py::pickle(&pickle_state::CurveState, &pickle_state::CurveFromState));

  // ---- temporal problem ----
  py::class_<TemporalProblem>(m, "TemporalProblem",
                              "The temporal problem (docs/temporal.md): a curve, limits, boundary velocities and accelerations, "
                              "K cells per piece, the constraint mode and rho.")
      .def(py::init([](const PiecewiseCurve& curve, const VehicleLimits& limits, const py::object& K, const std::string& mode, double rho,
                       const py::object& start_velocity, const py::object& end_velocity,
                       const py::object& start_acceleration, const py::object& end_acceleration, bool relax_boundary) {
             TemporalProblem p;
             p.curve = curve;
             p.limits = limits;
             p.cells_per_piece = CellCount(K, "K");
             p.constraint_mode = ModeFrom(mode);
             p.rho = rho;
             if (!start_velocity.is_none()) p.boundary.start_velocity = Vec3(start_velocity, "start_velocity");
             if (!end_velocity.is_none()) p.boundary.end_velocity = Vec3(end_velocity, "end_velocity");
             if (!start_acceleration.is_none()) p.boundary.start_acceleration = Vec3(start_acceleration, "start_acceleration");
             if (!end_acceleration.is_none()) p.boundary.end_acceleration = Vec3(end_acceleration, "end_acceleration");
             p.relax_boundary = relax_boundary;
             return p;
           }),
           py::arg("curve"), py::arg("limits") = FlightLimits(), py::kw_only(), py::arg("K") = 50,
           py::arg("constraint_mode") = ToString(kFlightConstraintMode), py::arg("rho") = 0.0, py::arg("start_velocity") = py::none(),
           py::arg("end_velocity") = py::none(), py::arg("start_acceleration") = py::none(),
           py::arg("end_acceleration") = py::none(), py::arg("relax_boundary") = false)
      .def_readwrite("curve", &TemporalProblem::curve)
      .def_readwrite("limits", &TemporalProblem::limits)
      .def_property(
          "K", [](const TemporalProblem& p) { return p.cells_per_piece; },
          [](TemporalProblem& p, const py::handle& v) { p.cells_per_piece = CellCount(v, "K"); })
      .def_readwrite("constraint_mode", &TemporalProblem::constraint_mode)
      .def_readwrite("rho", &TemporalProblem::rho)
      .def_readwrite("relax_boundary", &TemporalProblem::relax_boundary)
      .def_property(
          "start_velocity", [](const TemporalProblem& p) { return ToArray(p.boundary.start_velocity); },
          [](TemporalProblem& p, const py::handle& v) { p.boundary.start_velocity = Vec3(v, "start_velocity"); })
      .def_property(
          "end_velocity", [](const TemporalProblem& p) { return ToArray(p.boundary.end_velocity); },
          [](TemporalProblem& p, const py::handle& v) { p.boundary.end_velocity = Vec3(v, "end_velocity"); })
      .def_property(
          "start_acceleration", [](const TemporalProblem& p) { return ToArray(p.boundary.start_acceleration); },
          [](TemporalProblem& p, const py::handle& v) { p.boundary.start_acceleration = Vec3(v, "start_acceleration"); })
      .def_property(
          "end_acceleration", [](const TemporalProblem& p) { return ToArray(p.boundary.end_acceleration); },
          [](TemporalProblem& p, const py::handle& v) { p.boundary.end_acceleration = Vec3(v, "end_acceleration"); })
      .def("validate", &TemporalProblem::Validate, "Raises ValueError naming the first bad field.")
      .def(py::pickle(&pickle_state::ProblemState, &pickle_state::ProblemFromState));

  m.def("load_problem", &ReadTemporalProblemJson, py::arg("path"), "Reads a problem JSON file (docs/formats.md), as `timeopt temporal` does.");
  m.def(
      "parse_problem", [](const std::string& text) { return ParseTemporalProblemJson(text); }, py::arg("json_text"),
      "Parses problem JSON text.");

  // ---- temporal result ----
  py::class_<TemporalProfile>(m, "TemporalProfile", "s(t) along the curve: b = sdot^2 on the grid.")
      .def_property_readonly("total_time", &TemporalProfile::total_time)
      .def_property_readonly("num_pieces", &TemporalProfile::num_pieces)
      .def_property_readonly("K", &TemporalProfile::cells_per_piece)
      .def_property_readonly("jerk_limited", &TemporalProfile::jerk_limited)
      .def_property_readonly(
          "b",
          [](const TemporalProfile& p) {
            py::array_t<double> out({static_cast<py::ssize_t>(p.num_pieces()), static_cast<py::ssize_t>(p.cells_per_piece() + 1)});
            auto r = out.mutable_unchecked<2>();
            for (int i = 0; i < p.num_pieces(); ++i) {
              for (int k = 0; k <= p.cells_per_piece(); ++k) r(i, k) = p.b(i, k);
            }
            return out;
          },
          "b = sdot^2 at the grid points: (pieces, K + 1).")
      .def(py::pickle(&pickle_state::ProfileState, &pickle_state::ProfileFromState));

  py::class_<TemporalResult>(m, "TemporalResult", "The answer of a temporal solve; usable when status is TemporalStatus.optimal.")
      .def_readonly("status", &TemporalResult::status)
      .def_readonly("message", &TemporalResult::message)
      .def_readonly("solver", &TemporalResult::solver)
      .def_readonly("total_time", &TemporalResult::total_time)
      .def_readonly("objective", &TemporalResult::objective)
      .def_property_readonly("piece_durations", [](const TemporalResult& r) { return ToArray(r.piece_durations); })
      .def_readonly("iterations", &TemporalResult::iterations)
      .def_readonly("solve_time", &TemporalResult::solve_time_seconds)
      .def_readonly("build_time", &TemporalResult::build_time_seconds)
      .def_readonly("profile", &TemporalResult::profile)
      .def_readonly("max_velocity_ratio", &TemporalResult::max_velocity_ratio)
      .def_readonly("max_acceleration_ratio", &TemporalResult::max_acceleration_ratio)
      .def_readonly("max_jerk_ratio", &TemporalResult::max_jerk_ratio)
      .def_property_readonly("max_speed_ratio", [](const TemporalResult& r) { return Optional(r.max_speed_ratio); })
      .def_property_readonly("max_thrust_ratio", [](const TemporalResult& r) { return Optional(r.max_thrust_ratio); })
      .def_property_readonly("max_tilt_ratio", [](const TemporalResult& r) { return Optional(r.max_tilt_ratio); })
      .def_readonly("jerk_limited", &TemporalResult::jerk_limited)
      .def_readonly("scp_iterations", &TemporalResult::scp_iterations)
      .def_readonly("reduced_accuracy", &TemporalResult::reduced_accuracy)
      .def_readonly("method", &TemporalResult::method)
      .def_property_readonly(
          "infeasibility",
          [](const TemporalResult& r) -> py::object {
            if (!r.infeasibility) return py::none();
            py::dict d;
            d["cause"] = r.infeasibility->cause;
            d["where"] = r.infeasibility->where;
            d["detail"] = r.infeasibility->detail;
            return d;
          },
          "Why it is infeasible (cause, where, detail), or None.")
      .def_property_readonly(
          "boundary_relaxation",
          [](const TemporalResult& r) -> py::object {
            if (!r.boundary_relaxation) return py::none();
            const TemporalResult::BoundaryRelaxation& b = *r.boundary_relaxation;
            py::dict d;
            d["start_speed_given"] = b.start_speed_given;
            d["start_speed"] = b.start_speed;
            d["end_speed_given"] = b.end_speed_given;
            d["end_speed"] = b.end_speed;
            d["start_scale"] = b.start_scale;
            d["start_acceleration"] = b.start_acceleration;
            return d;
          },
          "With relax_boundary on an infeasible problem: the given and flown boundary speeds (m/s), "
          "start_scale and what became of the start acceleration; or None.")
      .def("is_success", &TemporalResult::is_success)
      .def("to_json", [](const TemporalResult& r) { return TemporalResultToJson(r); }, "The result JSON of `timeopt temporal`.")
      .def(py::pickle(&pickle_state::ResultState, &pickle_state::ResultFromState))
      .def("__repr__", [](const TemporalResult& r) {
        std::ostringstream s;
        s << "<TemporalResult " << ToString(r.status) << " T=" << r.total_time << " s (" << r.solver << ")>";
        return s.str();
      });

  m.def("solve", &SolveProblem, py::arg("problem"), py::arg("solver") = "socp", py::arg("max_memory_mb") = 0.0,
        "Solves a TemporalProblem with 'socp' (our conic solver) or 'ipopt'. max_memory_mb > 0: a problem whose "
        "estimated peak is above it raises ValueError before it is solved. The GIL is released while it runs.");

  m.def(
      "time_solves",
      [](const TemporalProblem& problem, const std::string& solver, int repeats) {
        if (repeats < 1) throw py::value_error("repeats: expected >= 1");
        std::unique_ptr<TemporalSolver> s = MakeTemporalSolver(BackendFrom(solver));
        std::vector<double> seconds;
        py::gil_scoped_release release;
        for (int i = 0; i < repeats; ++i) {
          const auto start = std::chrono::steady_clock::now();
          const TemporalResult r = s->Solve(problem);
          seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        }
        return seconds;
      },
      py::arg("problem"), py::arg("solver") = "socp", py::arg("repeats") = 20,
      "Wall seconds of `repeats` solves timed inside C++ by one reusable solver (no Python in the loop): the\n"
      "reference for the module's own overhead (benchmarks/python_overhead.py).");

  // A TemporalSolver keeps workspaces between solves and is not safe to call from two threads at
  // once: the Python object serializes its own solves (a second thread waits, with the GIL
  // released, for the first to finish). Threads that should solve in parallel use a Solver each.
  struct SharedSolver {
    std::unique_ptr<TemporalSolver> solver;
    TemporalBackend backend = TemporalBackend::kSocp;
    std::int64_t budget = 0;  // bytes (0: none)
    std::mutex mutex;
  };
  py::class_<SharedSolver>(m, "Solver",
                           "A reusable temporal solver (keeps its workspaces between solves). Safe to share between "
                           "threads: its solves run one at a time; use one Solver per thread to solve in parallel. "
                           "max_memory_mb > 0: each solve is held to it as timeopt.solve's is.")
      .def(py::init([](const std::string& solver, double max_memory_mb) {
             auto shared = std::make_unique<SharedSolver>();
             shared->backend = BackendFrom(solver);
             shared->budget = TemporalBudget(max_memory_mb);
             shared->solver = MakeBudgetedTemporalSolver(shared->backend, shared->budget);
             return shared;
           }),
           py::arg("solver") = "socp", py::arg("max_memory_mb") = 0.0)
      .def(
          "solve",
          [](SharedSolver& s, const TemporalProblem& p) {
            CheckTemporalBudget(p, s.backend, s.budget);
            py::gil_scoped_release release;
            const std::lock_guard<std::mutex> lock(s.mutex);
            return s.solver->Solve(p);
          },
          py::arg("problem"),
          "Solves, releasing the GIL; concurrent calls on one Solver run one after the other. ValueError before "
          "solving a problem above the Solver's max_memory_mb.");

  // ---- trajectories ----
  py::class_<Trajectory>(m, "Trajectory", "A curve traversed by a temporal profile: p, v, a, j against time.")
      .def(py::init([](const PiecewiseCurve& curve, const TemporalResult& result) {
             if (!result.is_success()) {
               throw py::value_error(std::string("Trajectory: the result is ") + ToString(result.status) + ", not optimal");
             }
             return Trajectory(curve, result.profile);
           }),
           py::arg("curve"), py::arg("result"))
      .def_property_readonly("duration", &Trajectory::duration)
      .def("sample", &Sample, py::arg("ts"), "(p, v, a, j) at the times ts, each an (N, 3) array; times clamp to [0, duration].")
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
                        if (state.size() != 2 || !py::isinstance<py::str>(state[0]) || state[0].cast<std::string>() != "Trajectory") {
                          throw py::value_error("unpickling Trajectory: not a timeopt Trajectory state");
                        }
                        return ParseTrajectoryJson(state[1].cast<std::string>(), "pickled trajectory");
                      }))
      .def_static("load", &ReadTrajectoryJson, py::arg("path"),
                  "Reads a trajectory file (--trajectory of plan, temporal, waypoints; docs/formats.md).")
      .def("save", [](const Trajectory& t, const std::string& path) { WriteTrajectoryJson(t, path); }, py::arg("path"),
           "Writes the trajectory file: curve and profile, exact; load() gives back the same samples to the bit.")
      .def("to_json", [](const Trajectory& t) { return TrajectoryToJson(t); }, "The trajectory file's JSON text.")
      .def_static("from_json", [](const std::string& text) { return ParseTrajectoryJson(text); }, py::arg("text"))
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
          py::arg("path"), py::arg("limits") = nullptr, py::arg("map") = nullptr, py::arg("title") = "timeopt trajectory",
          "Writes the 3D page (one HTML file; docs/formats.md): the path coloured by speed, map voxels near it, "
          "playback and plots with the limits given.")
      .def(
          "yaw",
          [](const Trajectory& t, const py::handle& ts, const std::string& yaw, double max_yaw_rate) {
            const auto times = AsDoubles(ts, "ts");
            if (times.ndim() != 1) throw py::value_error("ts: expected a 1-D array of times, got shape " + ShapeText(times));
            const std::vector<double> grid(times.data(), times.data() + times.shape(0));
            const YawProfile profile = PlanYaw(t, grid, ParseYawSpec(yaw, max_yaw_rate));
            return py::make_tuple(ToArray(profile.yaw), ToArray(profile.rate));
          },
          py::arg("ts"), py::arg("yaw") = "velocity", py::arg("max_yaw_rate") = YawOptions().max_rate,
          "(yaw, yaw_rate) at the increasing times ts (ENU, rad and rad/s): 'fixed:RAD', 'velocity' or 'goal', "
          "continuous, within max_yaw_rate, linear between the times.");

  // ---- maps ----
  py::class_<OccupancyMap>(m, "OccupancyMap", "An OctoMap occupancy map (.bt or .ot).")
      .def_static(
          "load",
          [](const std::string& path, const std::string& unknown) {
            UnknownSpace u;
            if (!FromString(unknown, &u)) throw py::value_error("unknown: expected 'free' or 'occupied', got '" + unknown + "'");
            return OccupancyMap::Load(path, u);
          },
          py::arg("path"), py::arg("unknown") = "free")
      .def_property_readonly("resolution", &OccupancyMap::resolution)
      .def_property_readonly("bounds",
                             [](const OccupancyMap& map) {
                               const Eigen::AlignedBox3d b = map.Bounds();
                               return py::make_tuple(ToArray(Eigen::Vector3d(b.min())), ToArray(Eigen::Vector3d(b.max())));
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
      [](const Trajectory& trajectory, const std::string& format, const std::string& path, double rate,
         const std::string& yaw, double max_yaw_rate, const OccupancyMap* map, double voxel_radius,
         double max_position_error, double max_velocity_error, double max_acceleration_error) {
        ExportFormat kind = ExportFormat::kCsv;
        if (!FromString(format, &kind)) {
          throw py::value_error("export: format must be " + EnumChoices(kExportFormats) + ", got '" + format + "'");
        }
        ExportOptions options;
        options.rate_hz = rate;
        options.yaw = ParseYawSpec(yaw, max_yaw_rate);
        options.fit.max_position_error = max_position_error;
        options.fit.max_velocity_error = max_velocity_error;
        options.fit.max_acceleration_error = max_acceleration_error;
        options.map = map;
        options.voxel_radius = voxel_radius;
        WriteExport(trajectory, kind, path, options);
      },
      py::arg("trajectory"), py::arg("format"), py::arg("path"), py::arg("rate") = kDefaultSampleRateHz,
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
            if (!box_min.is_none() || !box_max.is_none()) box = Eigen::AlignedBox3d(Vec3(box_min, "box_min"), Vec3(box_max, "box_max"));
            const int64_t budget = BudgetBytes(max_memory_mb);
            py::gil_scoped_release release;
            return Esdf::FromMap(map, box, budget);
          },
          py::arg("map"), py::arg("box_min") = py::none(), py::arg("box_max") = py::none(), py::arg("max_memory_mb") = 0.0,
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

  // ---- planning ----
  py::class_<PlanResult>(m, "PlanResult", "A plan: status, the spatial curve, the temporal result and the stages' figures.")
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
            if (!r.is_success()) throw py::value_error(std::string("PlanResult.trajectory: the plan is ") + ToString(r.status));
            return Trajectory(r.curve, r.temporal.profile);
          },
          "The planned trajectory (successful plans only).")
      .def(
          "summary",
          [](const PlanResult& r) { return py::module_::import("json").attr("loads")(PlanResultToJson(r)); },
          "The plan's summary as a dict (the plan's own keys of `timeopt plan`'s JSON).")
      .def("to_json", [](const PlanResult& r) { return PlanResultToJson(r); }, "The plan's summary as JSON text.")
      .def(
          "to_html",
          [](const PlanResult& r, const std::string& path, const OccupancyMap* map, const VehicleLimits* limits) {
            if (!r.is_success()) throw py::value_error(std::string("PlanResult.to_html: the plan is ") + ToString(r.status));
            const VehicleLimits drawn = limits != nullptr ? *limits : PlannerOptions().limits;
            PlanPageOptions page;
            page.title = "timeopt plan";
            std::ostringstream T, length, clearance;
            T << r.temporal.total_time << " s";
            length << r.path_length << " m";
            clearance << r.min_clearance << " m";
            page.summary = {{"T", T.str()}, {"status", ToString(r.status)}, {"path length", length.str()},
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
        if (r.is_success()) s << " T=" << r.temporal.total_time << " s, " << r.path_length << " m, " << r.curve.num_pieces() << " pieces";
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
  py::class_<FeasibilityReport>(m, "FlightReport", "A simulated flight: whether every limit held, and the largest ratios.")
      .def_readonly("feasible", &FeasibilityReport::feasible)
      .def_readonly("tolerance", &FeasibilityReport::tolerance, "The verdict's relative slack: 0.01 with a jerk limit, 1e-9 without, unless given.")
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

  // ---- the conic solver ----
  py::module_ conic_module = m.def_submodule("conic", "Our interior-point solver for LP / SOCP / rotated cones.");
  BindEnum(conic_module, "Status",
           std::array<conic::Status, 5>{conic::Status::kOptimal, conic::Status::kPrimalInfeasible,
                                        conic::Status::kDualInfeasible, conic::Status::kIterationLimit,
                                        conic::Status::kNumericalError},
           "Outcome of a conic solve.");
  py::class_<conic::Result>(conic_module, "Result", "x, y, z, s and the figures of a conic solve.")
      .def_readonly("status", &conic::Result::status)
      .def_readonly("message", &conic::Result::message)
      .def_property_readonly("x", [](const conic::Result& r) { return ToArray(r.x); })
      .def_property_readonly("y", [](const conic::Result& r) { return ToArray(r.y); })
      .def_property_readonly("z", [](const conic::Result& r) { return ToArray(r.z); })
      .def_property_readonly("s", [](const conic::Result& r) { return ToArray(r.s); })
      .def_readonly("primal_objective", &conic::Result::primal_objective)
      .def_readonly("dual_objective", &conic::Result::dual_objective)
      .def_readonly("iterations", &conic::Result::iterations)
      .def_readonly("solve_time", &conic::Result::solve_time_seconds)
      .def_readonly("reduced_accuracy", &conic::Result::reduced_accuracy);
  conic_module.def(
      "solve",
      [](const py::handle& c, const py::handle& G, const py::handle& h, const py::handle& A, const py::handle& b,
         const py::dict& cones, const py::kwargs& kwargs) {
        const conic::Problem p = ConicProblemFrom(c, G, h, A, b, cones);
        conic::Solver solver(ConicOptionsFrom(kwargs));
        py::gil_scoped_release release;
        return solver.Solve(p);
      },
      py::arg("c"), py::arg("G"), py::arg("h"), py::arg("A") = py::none(), py::arg("b") = py::none(),
      py::arg("cones") = py::dict(),
      "min c'x s.t. A x = b, G x + s = h, s in K, with K = {'l': orthant rows, 'q': [second-order cone sizes],\n"
      "'r': [rotated cone sizes]} in that row order. G and A: scipy.sparse or dense. Keywords: tolerance,\n"
      "max_iterations, max_solve_time. Releases the GIL.");
  conic_module.def(
      "read_cbf",
      [](const std::string& path) {
        std::ifstream in(path);
        if (!in) throw py::value_error("read_cbf: cannot open '" + path + "'");
        const conic::CbfModel model = conic::ReadCbf(in);
        const conic::Problem& p = model.problem;
        py::module_ sparse = py::module_::import("scipy.sparse");
        const auto to_scipy = [&](const Eigen::SparseMatrix<double>& mat) {
          Eigen::SparseMatrix<double> csc = mat;
          csc.makeCompressed();
          py::array_t<double> data(csc.nonZeros(), csc.valuePtr());
          py::array_t<int> indices(csc.nonZeros(), csc.innerIndexPtr());
          py::array_t<int> indptr(csc.cols() + 1, csc.outerIndexPtr());
          return sparse.attr("csc_matrix")(py::make_tuple(data, indices, indptr), py::make_tuple(csc.rows(), csc.cols()));
        };
        py::dict out;
        out["c"] = ToArray(p.c);
        out["G"] = to_scipy(p.G);
        out["h"] = ToArray(p.h);
        out["A"] = to_scipy(p.A);
        out["b"] = ToArray(p.b);
        out["cones"] = ConesTo(p.cones);
        out["maximize"] = model.maximize;
        out["objective_constant"] = model.objective_constant;
        return out;
      },
      py::arg("path"), "A CBF file as a dict of c, G, h, A, b (scipy.sparse), cones, maximize, objective_constant.");
  conic_module.def(
      "write_cbf",
      [](const std::string& path, const py::handle& c, const py::handle& G, const py::handle& h, const py::handle& A,
         const py::handle& b, const py::dict& cones) {
        const conic::Problem p = ConicProblemFrom(c, G, h, A, b, cones);
        std::ofstream out(path);
        if (!out) throw py::value_error("write_cbf: cannot write '" + path + "'");
        conic::WriteCbf(p, out);
      },
      py::arg("path"), py::arg("c"), py::arg("G"), py::arg("h"), py::arg("A") = py::none(), py::arg("b") = py::none(),
      py::arg("cones") = py::dict(), "Writes the problem of conic.solve's arguments as a CBF file.");

  // ---- many problems at once (timeopt_batch.py, run in this module's namespace) ----
  m.def(
      "_failed_result",
      [](const std::string& solver, const std::string& message) {
        TemporalResult r;
        r.status = TemporalStatus::kInvalidInput;
        r.solver = solver;
        r.message = message;
        return r;
      },
      py::arg("solver"), py::arg("message"), "A TemporalResult for a problem of a batch that raised (invalid_input).");
  m.def(
      "_failed_plan",
      [](const std::string& message) {
        PlanResult r;
        r.status = PlanStatus::kInvalidInput;
        r.message = message;
        return r;
      },
      py::arg("message"), "A PlanResult for a query of a batch that raised (invalid_input).");
  py::exec(kTimeoptBatchSource, m.attr("__dict__"));
}
