// The Python module's conic solver (the timeopt.conic submodule).

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
namespace {

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
    } else if (key == "max_solve_time_seconds") {
      o.max_solve_time_seconds = item.second.cast<double>();
    } else {
      throw py::type_error("conic.solve: unknown keyword '" + key +
                           "' (expected tolerance, max_iterations, max_solve_time_seconds)");
    }
  }
  std::string error;
  if (!o.IsValid(&error)) throw py::value_error("conic.solve: " + error);
  return o;
}

}  // namespace

void BindConic(py::module_& m) {
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
      .def_readonly("solve_time_seconds", &conic::Result::solve_time_seconds)
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
      "max_iterations, max_solve_time_seconds. Releases the GIL.");
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
          return sparse.attr("csc_matrix")(py::make_tuple(data, indices, indptr),
                                           py::make_tuple(csc.rows(), csc.cols()));
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
}

}  // namespace timeopt::python
