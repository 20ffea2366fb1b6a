#pragma once

// Private to the Python module (timeopt_module.cpp and its bind_*.cpp files): numpy in and out
// with the argument's name in every error, the limits and budgets every part reads from keyword
// arguments, and the functions that bind each part of the library.

#include <algorithm>
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
#include <array>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "io/json_internal.h"

#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/temporal/temporal_solver.h"

namespace py = pybind11;

namespace timeopt::python {

using RowMatrixX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// ---- numpy in: shapes checked, with the argument's name in the message ----

inline std::string ShapeText(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) text += (i ? ", " : "") + std::to_string(a.shape(i));
  return text + (a.ndim() == 1 ? ",)" : ")");
}

// A float64 array from any array-like (lists, ints, float32), or a ValueError naming `name`.
inline py::array_t<double, py::array::c_style | py::array::forcecast> AsDoubles(const py::handle& value,
                                                                                const char* name) {
  if (value.is_none()) throw py::value_error(std::string(name) + ": expected numbers, got None");
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);  // clears its error
  if (!array) {
    throw py::value_error(std::string(name) + ": expected an array of numbers, got " +
                          std::string(py::str(py::type::of(value).attr("__name__"))));
  }
  return array;
}

// Three numbers: a scalar broadcast to the three axes when `broadcast`, or shape (3,).
inline Eigen::Vector3d Vec3(const py::handle& value, const char* name, bool broadcast = false) {
  const auto a = AsDoubles(value, name);
  if (broadcast && a.ndim() == 0) return Eigen::Vector3d::Constant(*a.data());
  if (a.ndim() != 1 || a.shape(0) != 3) {
    throw py::value_error(std::string(name) + ": expected 3 values" + (broadcast ? " or one" : "") + ", got shape " +
                          ShapeText(a));
  }
  return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
}

// A cell count K: a Python int (numpy integers too; not a bool or a float) in [1, max], or a
// ValueError naming `name` (pybind's own conversion raised TypeError for 2.5 and took -1).
inline int CellCount(const py::handle& value, const char* name, int max = kMaxCellsPerPiece) {
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
inline Eigen::Matrix3Xd Points(const py::handle& value, const char* name) {
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

inline Eigen::VectorXd Vector(const py::handle& value, const char* name) {
  const auto a = AsDoubles(value, name);
  if (a.ndim() != 1) throw py::value_error(std::string(name) + ": expected a 1-D array, got shape " + ShapeText(a));
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.shape(0));
}

// A sparse matrix from a scipy.sparse matrix (anything with tocsc()), or from a dense 2-D array.
inline Eigen::SparseMatrix<double> Sparse(const py::handle& value, const char* name, Eigen::Index cols) {
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
  if (a.ndim() != 2)
    throw py::value_error(std::string(name) + ": expected a 2-D array or a scipy.sparse matrix, got shape " +
                          ShapeText(a));
  Eigen::MatrixXd dense(a.shape(0), a.shape(1));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (py::ssize_t j = 0; j < a.shape(1); ++j) dense(i, j) = a.at(i, j);
  }
  return dense.sparseView();
}

// ---- numpy out ----

inline py::array_t<double> ToArray(const std::vector<double>& v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

inline py::array_t<double> ToArray(const Eigen::VectorXd& v) { return py::array_t<double>(v.size(), v.data()); }

inline py::array_t<double> ToArray(const Eigen::Vector3d& v) { return py::array_t<double>(3, v.data()); }

// An (N, 3) array from 3 x N columns.
inline py::array_t<double> ToRows(const Eigen::Matrix3Xd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.cols()), static_cast<py::ssize_t>(3)});
  auto r = out.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.cols(); ++i) {
    for (int k = 0; k < 3; ++k) r(i, k) = m(k, i);
  }
  return out;
}

inline py::object Optional(const std::optional<double>& value) { return value ? py::cast(*value) : py::none(); }

// One limit from a keyword argument, read as the problem files and planner configurations read
// their "limits" (internal::ReadLimits): per-axis values as one number or three, None for "not
// set" (no limit), numbers finite. Python's own part is turning the value into JSON.
inline void SetLimit(VehicleLimits* l, const std::string& key, const py::handle& value) {
  if (std::find_if(internal::kLimitKeys.begin(), internal::kLimitKeys.end(), [&](const char* k) { return key == k; }) ==
      internal::kLimitKeys.end()) {
    throw py::type_error("Limits: unknown keyword '" + key + "'");
  }
  nlohmann::json j = nlohmann::json::object();
  if (value.is_none()) {
    // (A file's null gravity leaves it as it is; here that would be a silent no-op.)
    if (key == "gravity") throw py::value_error("Limits.gravity: expected a number, got None");
    j[key] = nullptr;
  } else {
    const auto a = AsDoubles(value, key.c_str());
    if (a.ndim() == 0) {
      j[key] = *a.data();
    } else if (a.ndim() == 1 && a.shape(0) == 3) {
      j[key] = nlohmann::json::array({a.data()[0], a.data()[1], a.data()[2]});
    } else {
      throw py::value_error(key + ": expected 3 values or one, got shape " + ShapeText(a));
    }
  }
  try {
    internal::ReadLimits(j, "Limits", l);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
}

inline ConstraintMode ModeFrom(const std::string& text) {
  ConstraintMode mode;
  if (!FromString(text, &mode))
    throw py::value_error("constraint_mode: expected 'paper' or 'certified', got '" + text + "'");
  return mode;
}

// A memory budget in MiB (0: none) as bytes, or a ValueError (an infinite one would overflow the
// conversion).
inline int64_t BudgetBytes(double max_memory_mb) {
  if (!(max_memory_mb >= 0.0) || !std::isfinite(max_memory_mb)) {
    throw py::value_error("max_memory_mb: expected a number >= 0 (0: no budget)");
  }
  return static_cast<int64_t>(max_memory_mb * 1024 * 1024);
}

// A Python enum of every value, named as ToString names it.
template <typename Enum, size_t N>
void BindEnum(py::module_& m, const char* name, const std::array<Enum, N>& values, const char* doc) {
  py::enum_<Enum> e(m, name, doc);
  for (const Enum value : values) e.value(ToString(value), value);
}

// Each adds its part of the library to the module, in this order (timeopt_module.cpp).
void BindTemporal(py::module_& m);      // Limits, Curve, TemporalProblem, results, solve, Solver
void BindTrajectories(py::module_& m);  // Trajectory
void BindMaps(py::module_& m);          // OccupancyMap, export, Esdf
void BindPlanner(py::module_& m);       // PlanResult, plan, FlightReport, simulate
void BindConic(py::module_& m);         // the conic submodule

}  // namespace timeopt::python
