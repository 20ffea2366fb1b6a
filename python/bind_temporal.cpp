// The Python module's temporal part: limits, curves, temporal problems, results, solve and Solver.

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

// ---- the temporal solve ----

TemporalBackend BackendFrom(const std::string& name) {
  TemporalBackend backend;
  if (!FromString(name, &backend)) throw py::value_error("solver: expected 'socp' or 'ipopt', got '" + name + "'");
  return backend;
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
  const std::int64_t budget = BudgetBytes(max_memory_mb);
  const TemporalBackend backend = BackendFrom(solver);
  CheckTemporalBudget(problem, backend, budget);
  std::unique_ptr<TemporalSolver> s = MakeBudgetedTemporalSolver(backend, budget);
  py::gil_scoped_release release;
  return s->Solve(problem);
}

// Limits.
// The limits that are one number or none (None in Python), in the order repr writes them; each is
// an attribute set through SetLimit.
constexpr std::pair<const char*, std::optional<double> VehicleLimits::*> kOptionalLimits[] = {
    {"max_speed", &VehicleLimits::max_speed},   {"max_acceleration_norm", &VehicleLimits::max_acceleration_norm},
    {"max_thrust", &VehicleLimits::max_thrust}, {"min_thrust", &VehicleLimits::min_thrust},
    {"max_tilt", &VehicleLimits::max_tilt},     {"max_acceleration_change", &VehicleLimits::max_acceleration_change},
};

void BindLimits(py::module_& m) {
  py::class_<VehicleLimits> limits(
      m, "Limits",
      "Vehicle limits: per-axis max_velocity and max_acceleration (m/s, m/s^2; +inf for none), "
      "optional per-axis max_jerk, and the quadrotor's max_speed, max_acceleration_norm, max_thrust, "
      "min_thrust (m/s^2), max_tilt (rad), gravity.");
  limits
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
          "max_jerk",
          [](const VehicleLimits& l) -> py::object {
            return l.max_jerk ? py::object(ToArray(*l.max_jerk)) : py::none();
          },
          [](VehicleLimits& l, const py::handle& v) { SetLimit(&l, "max_jerk", v); })
      .def_property(
          "gravity", [](const VehicleLimits& l) { return l.gravity; },
          [](VehicleLimits& l, const py::handle& v) { SetLimit(&l, "gravity", v); })
      .def(py::pickle(&pickle_state::LimitsState, &pickle_state::LimitsFromState))
      .def("__repr__", [](const VehicleLimits& l) {
        std::ostringstream s;
        const auto axes = [&s](const Eigen::Vector3d& v) {
          s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
        };
        s << "Limits(max_velocity=";
        axes(l.max_velocity);
        s << ", max_acceleration=";
        axes(l.max_acceleration);
        s << ", max_jerk=";
        if (l.max_jerk)
          axes(*l.max_jerk);
        else
          s << "None";
        for (const auto& [name, field] : kOptionalLimits) {
          if (l.*field) s << ", " << name << "=" << *(l.*field);
        }
        s << ")";
        return s.str();
      });
  for (const auto& [name, field] : kOptionalLimits) {
    limits.def_property(
        name, [field = field](const VehicleLimits& l) { return Optional(l.*field); },
        [name = name](VehicleLimits& l, const py::handle& v) { SetLimit(&l, name, v); });
  }
}

// Curve.
void BindCurve(py::module_& m) {
  py::class_<PiecewiseCurve>(m, "Curve", "A piecewise polynomial curve f(s), each piece on its own s in [0, 1].")
      .def(py::init([](const py::list& pieces) {
             std::vector<PolynomialPiece> out;
             for (const py::handle& piece : pieces) {
               const auto a = AsDoubles(piece, "pieces[i]");
               if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) < 1) {
                 throw py::value_error("pieces[" + std::to_string(out.size()) +
                                       "]: expected a (3, degree + 1) array of monomial coefficients, got shape " +
                                       ShapeText(a));
               }
               PolynomialPiece::Coefficients c(3, a.shape(1));
               for (py::ssize_t k = 0; k < a.shape(1); ++k) {
                 for (int r = 0; r < 3; ++r) c(r, k) = a.at(r, k);
               }
               out.emplace_back(c);
             }
             return PiecewiseCurve(std::move(out));
           }),
           py::arg("pieces"),
           "Curve(pieces): a list of (3, degree + 1) arrays, row r = axis, column k = coefficient of s^k.")
      .def_static(
          "from_waypoints",
          [](const py::handle& waypoints, const std::string& kind) {
            const Eigen::Matrix3Xd w = MergeCoincidentWaypoints(Points(waypoints, "waypoints"));
            if (kind == "cubic") return NaturalCubicSpline(w);
            if (kind == "minjerk") return MinimumJerkSpline(w);
            throw py::value_error("kind: expected 'cubic' or 'minjerk', got '" + kind + "'");
          },
          py::arg("waypoints"), py::arg("kind") = "minjerk",
          "A curve through (N, 3) waypoints: 'minjerk' (rest to rest, C4 inside) or 'cubic' (natural, C2). A "
          "waypoint that coincides with the one before (within 1e-6 of the waypoints' extent) is dropped: "
          "the curve has a piece per distinct step.")
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
      .def(
          "arc_length", [](const PiecewiseCurve& c) { return c.ArcLength(); }, "Arc length, metres.")
      .def(
          "to_json", [](const PiecewiseCurve& c) { return CurveToJson(c); }, "The curve JSON of docs/formats.md.")
      .def(py::pickle(&pickle_state::CurveState, &pickle_state::CurveFromState));
}

// TemporalProblem, load_problem and parse_problem.
void BindProblem(py::module_& m) {
  py::class_<TemporalProblem>(
      m, "TemporalProblem",
      "The temporal problem (docs/temporal.md): a curve, limits, boundary velocities and accelerations, "
      "K cells per piece, the constraint mode and rho.")
      .def(py::init([](const PiecewiseCurve& curve, const VehicleLimits& limits, const py::object& K,
                       const std::string& mode, double rho, const py::object& start_velocity,
                       const py::object& end_velocity, const py::object& start_acceleration,
                       const py::object& end_acceleration, bool relax_boundary) {
             TemporalProblem p;
             p.curve = curve;
             p.limits = limits;
             p.cells_per_piece = CellCount(K, "K");
             p.constraint_mode = ModeFrom(mode);
             p.rho = rho;
             if (!start_velocity.is_none()) p.boundary.start_velocity = Vec3(start_velocity, "start_velocity");
             if (!end_velocity.is_none()) p.boundary.end_velocity = Vec3(end_velocity, "end_velocity");
             if (!start_acceleration.is_none())
               p.boundary.start_acceleration = Vec3(start_acceleration, "start_acceleration");
             if (!end_acceleration.is_none()) p.boundary.end_acceleration = Vec3(end_acceleration, "end_acceleration");
             p.relax_boundary = relax_boundary;
             return p;
           }),
           py::arg("curve"), py::arg("limits") = FlightLimits(), py::kw_only(), py::arg("K") = 50,
           py::arg("constraint_mode") = ToString(kFlightConstraintMode), py::arg("rho") = 0.0,
           py::arg("start_velocity") = py::none(), py::arg("end_velocity") = py::none(),
           py::arg("start_acceleration") = py::none(), py::arg("end_acceleration") = py::none(),
           py::arg("relax_boundary") = false)
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
          [](TemporalProblem& p, const py::handle& v) {
            p.boundary.start_acceleration = Vec3(v, "start_acceleration");
          })
      .def_property(
          "end_acceleration", [](const TemporalProblem& p) { return ToArray(p.boundary.end_acceleration); },
          [](TemporalProblem& p, const py::handle& v) { p.boundary.end_acceleration = Vec3(v, "end_acceleration"); })
      .def("validate", &TemporalProblem::Validate, "Raises ValueError naming the first bad field.")
      .def(py::pickle(&pickle_state::ProblemState, &pickle_state::ProblemFromState));

  m.def("load_problem", &ReadTemporalProblemJson, py::arg("path"),
        "Reads a problem JSON file (docs/formats.md), as `timeopt temporal` does.");
  m.def(
      "parse_problem", [](const std::string& text) { return ParseTemporalProblemJson(text); }, py::arg("json_text"),
      "Parses problem JSON text.");
}

// TemporalProfile and TemporalResult.
void BindResults(py::module_& m) {
  py::class_<TemporalProfile>(m, "TemporalProfile", "s(t) along the curve: b = sdot^2 on the grid.")
      .def_property_readonly("total_time", &TemporalProfile::total_time)
      .def_property_readonly("num_pieces", &TemporalProfile::num_pieces)
      .def_property_readonly("K", &TemporalProfile::cells_per_piece)
      .def_property_readonly("jerk_limited", &TemporalProfile::jerk_limited)
      .def_property_readonly(
          "b",
          [](const TemporalProfile& p) {
            py::array_t<double> out(
                {static_cast<py::ssize_t>(p.num_pieces()), static_cast<py::ssize_t>(p.cells_per_piece() + 1)});
            auto r = out.mutable_unchecked<2>();
            for (int i = 0; i < p.num_pieces(); ++i) {
              for (int k = 0; k <= p.cells_per_piece(); ++k) r(i, k) = p.b(i, k);
            }
            return out;
          },
          "b = sdot^2 at the grid points: (pieces, K + 1).")
      .def(py::pickle(&pickle_state::ProfileState, &pickle_state::ProfileFromState));

  py::class_<TemporalResult>(m, "TemporalResult",
                             "The answer of a temporal solve; usable when status is TemporalStatus.optimal.")
      .def_readonly("status", &TemporalResult::status)
      .def_readonly("message", &TemporalResult::message)
      .def_readonly("solver", &TemporalResult::solver)
      .def_readonly("total_time", &TemporalResult::total_time)
      .def_readonly("objective", &TemporalResult::objective)
      .def_property_readonly("piece_durations", [](const TemporalResult& r) { return ToArray(r.piece_durations); })
      .def_readonly("iterations", &TemporalResult::iterations)
      .def_readonly("solve_time_seconds", &TemporalResult::solve_time_seconds)
      .def_readonly("build_time_seconds", &TemporalResult::build_time_seconds)
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
      .def(
          "to_json", [](const TemporalResult& r) { return TemporalResultToJson(r); },
          "The result JSON of `timeopt temporal`.")
      .def(py::pickle(&pickle_state::ResultState, &pickle_state::ResultFromState))
      .def("__repr__", [](const TemporalResult& r) {
        std::ostringstream s;
        s << "<TemporalResult " << ToString(r.status) << " T=" << r.total_time << " s (" << r.solver << ")>";
        return s.str();
      });
}

// solve, time_solves and the shared Solver.
void BindSolve(py::module_& m) {
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
             shared->budget = BudgetBytes(max_memory_mb);
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
}

}  // namespace

void BindTemporal(py::module_& m) {
  // In this order: each part names the types of the parts before it in its signatures.
  BindLimits(m);
  BindCurve(m);
  BindProblem(m);
  BindResults(m);
  BindSolve(m);
}

}  // namespace timeopt::python
