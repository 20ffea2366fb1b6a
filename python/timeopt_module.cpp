// The Python module `timeopt` (pybind11): the library's curves, temporal problems and both
// backends, trajectories, maps and distance fields, the planner, the simulated quadrotor and the
// conic solver, with numpy arrays in and out. Solves, plans, flights and field builds release the
// GIL. Errors of the library (std::invalid_argument, std::runtime_error) arrive as ValueError and
// RuntimeError with the library's messages; statuses are enums, as in C++.
//
// The parts are bound in bind_*.cpp (see bindings.h).

#include <string>

#include <pybind11/eval.h>
#include <pybind11/pybind11.h>

#include "timeopt/core/enum_strings.h"
#include "timeopt/core/errors.h"
#include "timeopt/planner/planner.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/version.h"
#include "bindings.h"
#include "timeopt_batch_source.h"

PYBIND11_MODULE(timeopt, m) {
  using namespace timeopt;          // NOLINT(build/namespaces): the module's own scope
  using namespace timeopt::python;  // NOLINT(build/namespaces)
  m.doc() =
      "Minimum-time quadrotor trajectories by spatial-temporal decoupling (Gao et al., IROS 2018): curves, the\n"
      "temporal problem solved by our conic solver or Ipopt, trajectories, maps, the planner, a simulated\n"
      "quadrotor and the conic solver itself. SI units; arrays are float64 numpy arrays, points (N, 3).";
  m.attr("__version__") = TIMEOPT_VERSION_STRING;

  // A file that cannot be opened or written is an OSError, as Python's own open() makes it.
  py::register_exception<FileError>(m, "FileError", PyExc_OSError);

  BindEnum(m, "TemporalStatus", kTemporalStatuses,
           "Outcome of a temporal solve (as in C++: a status, not an exception).");
  BindEnum(m, "ConstraintMode", kConstraintModes,
           "paper: the paper's rows at grid points; certified: limits on whole cells.");
  BindEnum(m, "PlanStatus", kPlanStatuses, "Outcome of a plan.");

  BindTemporal(m);
  BindTrajectories(m);
  BindMaps(m);
  BindPlanner(m);
  BindConic(m);

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
