// Pickling for the Python module (python/bind_*.cpp): the state of limits, curves, temporal
// problems, profiles, results and plan results as plain Python values (tuples of floats, ints,
// strings, None), which pickle exactly: a float crosses as its 8 bytes, so an object read back in
// another process or on another machine equals the one written, to the bit. Enums cross as their
// names (the spatial status, which has no list of names, as its number). Each state starts with
// its kind and kStateVersion; a state of another version is refused
// with a ValueError (pickles are for processes running the same build, as in a Dask cluster).
//
// Every field of each struct is carried. A field added to one of these structs must be added
// here too: tests/python/test_batch.py round-trips every attribute the module shows.

#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "timeopt/core/enum_strings.h"
#include "timeopt/planner/planner.h"
#include "timeopt/spatial/spatial_optimizer.h"
#include "timeopt/temporal/joints.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_result.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt {
namespace pickle_state {

namespace py = pybind11;

inline constexpr int kStateVersion = 2;  // 2: plan stage times in seconds

// A reader of one state tuple, field by field in the order written, with the kind's name in its
// errors.
class Reader {
 public:
  Reader(const py::tuple& state, const char* kind) : state_(state), kind_(kind) {
    if (state_.size() < 2 || !py::isinstance<py::str>(state_[0]) || state_[0].cast<std::string>() != kind ||
        !py::isinstance<py::int_>(state_[1])) {
      throw py::value_error(std::string("unpickling ") + kind + ": not a timeopt " + kind + " state");
    }
    const int version = state_[1].cast<int>();
    if (version != kStateVersion) {
      throw py::value_error(std::string("unpickling ") + kind + ": state version " + std::to_string(version) +
                            ", this build reads " + std::to_string(kStateVersion) +
                            " (pickle and unpickle with the same timeopt)");
    }
    next_ = 2;
  }
  py::handle Next() {
    if (next_ >= state_.size()) throw py::value_error(std::string("unpickling ") + kind_ + ": the state is too short");
    return state_[next_++];
  }
  template <typename T>
  T Get() {
    return Next().cast<T>();
  }
  template <typename T>
  std::optional<T> Optional() {
    const py::handle h = Next();
    if (h.is_none()) return std::nullopt;
    return h.cast<T>();
  }
  Eigen::Vector3d Vec3() {
    const auto v = Get<std::vector<double>>();
    if (v.size() != 3) throw py::value_error(std::string("unpickling ") + kind_ + ": expected 3 numbers");
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }
  template <typename E, size_t N>
  E Enum(const std::array<E, N>& values) {
    const std::string name = Get<std::string>();
    E out{};
    if (!EnumFromString(name, values, &out)) {
      throw py::value_error(std::string("unpickling ") + kind_ + ": unknown value '" + name + "'");
    }
    return out;
  }
  void Done() const {
    if (next_ != state_.size()) throw py::value_error(std::string("unpickling ") + kind_ + ": the state is too long");
  }

 private:
  py::tuple state_;
  const char* kind_;
  size_t next_ = 0;
};

inline py::tuple Vec3State(const Eigen::Vector3d& v) { return py::make_tuple(v.x(), v.y(), v.z()); }
inline py::object OptionalState(const std::optional<double>& v) { return v ? py::object(py::float_(*v)) : py::none(); }

// ---- limits ----
inline py::tuple LimitsState(const VehicleLimits& l) {
  return py::make_tuple("Limits", kStateVersion, Vec3State(l.max_velocity), Vec3State(l.max_acceleration),
                        l.max_jerk ? py::object(Vec3State(*l.max_jerk)) : py::none(), OptionalState(l.max_speed),
                        OptionalState(l.max_acceleration_norm), OptionalState(l.max_thrust),
                        OptionalState(l.min_thrust), OptionalState(l.max_tilt), l.gravity,
                        OptionalState(l.max_acceleration_change));
}
inline VehicleLimits ReadLimits(Reader& r) {
  VehicleLimits l;
  l.max_velocity = r.Vec3();
  l.max_acceleration = r.Vec3();
  const py::handle jerk = r.Next();
  if (!jerk.is_none()) {
    const auto v = jerk.cast<std::vector<double>>();
    if (v.size() != 3) throw py::value_error("unpickling Limits: max_jerk: expected 3 numbers");
    l.max_jerk = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  l.max_speed = r.Optional<double>();
  l.max_acceleration_norm = r.Optional<double>();
  l.max_thrust = r.Optional<double>();
  l.min_thrust = r.Optional<double>();
  l.max_tilt = r.Optional<double>();
  l.gravity = r.Get<double>();
  l.max_acceleration_change = r.Optional<double>();
  return l;
}
inline VehicleLimits LimitsFromState(const py::tuple& state) {
  Reader r(state, "Limits");
  VehicleLimits l = ReadLimits(r);
  r.Done();
  return l;
}

// ---- curves: each piece's coefficients, row-major (3 x (degree + 1)) ----
inline py::tuple CurveState(const PiecewiseCurve& c) {
  py::list pieces;
  for (const PolynomialPiece& p : c.pieces()) {
    const PolynomialPiece::Coefficients& k = p.coefficients();
    std::vector<double> values;
    for (int row = 0; row < 3; ++row) {
      for (Eigen::Index col = 0; col < k.cols(); ++col) values.push_back(k(row, col));
    }
    pieces.append(py::make_tuple(static_cast<int>(k.cols()), values));
  }
  return py::make_tuple("Curve", kStateVersion, pieces);
}
inline PiecewiseCurve ReadCurve(Reader& r) {
  std::vector<PolynomialPiece> pieces;
  for (const py::handle& item : r.Get<py::list>()) {
    const auto piece = item.cast<py::tuple>();
    const int columns = piece[0].cast<int>();
    const auto values = piece[1].cast<std::vector<double>>();
    if (columns < 1 || values.size() != static_cast<size_t>(3 * columns)) {
      throw py::value_error("unpickling Curve: a piece's coefficients do not match its degree");
    }
    PolynomialPiece::Coefficients k(3, columns);
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < columns; ++col) k(row, col) = values[static_cast<size_t>(row * columns + col)];
    }
    pieces.emplace_back(k);
  }
  return PiecewiseCurve(std::move(pieces));
}
inline PiecewiseCurve CurveFromState(const py::tuple& state) {
  Reader r(state, "Curve");
  PiecewiseCurve c = ReadCurve(r);
  r.Done();
  return c;
}

// ---- temporal problems ----
inline py::tuple ProblemState(const TemporalProblem& p) {
  const TemporalBoundary& b = p.boundary;
  return py::make_tuple("TemporalProblem", kStateVersion, CurveState(p.curve), LimitsState(p.limits),
                        Vec3State(b.start_velocity), Vec3State(b.start_acceleration), Vec3State(b.end_velocity),
                        Vec3State(b.end_acceleration), p.cells_per_piece, p.rho, ToString(p.constraint_mode),
                        p.parallel_tolerance, p.zero_tangent_tolerance, p.prune_redundant_rows, p.certified_thinning,
                        p.scp_tolerance, p.relax_boundary, p.max_scp_iterations);
}
inline TemporalProblem ProblemFromState(const py::tuple& state) {
  Reader r(state, "TemporalProblem");
  TemporalProblem p;
  p.curve = CurveFromState(r.Get<py::tuple>());
  p.limits = LimitsFromState(r.Get<py::tuple>());
  p.boundary.start_velocity = r.Vec3();
  p.boundary.start_acceleration = r.Vec3();
  p.boundary.end_velocity = r.Vec3();
  p.boundary.end_acceleration = r.Vec3();
  p.cells_per_piece = r.Get<int>();
  p.rho = r.Get<double>();
  p.constraint_mode = r.Enum(kConstraintModes);
  p.parallel_tolerance = r.Get<double>();
  p.zero_tangent_tolerance = r.Get<double>();
  p.prune_redundant_rows = r.Get<bool>();
  p.certified_thinning = r.Get<double>();
  p.scp_tolerance = r.Get<double>();
  p.relax_boundary = r.Get<bool>();
  p.max_scp_iterations = r.Get<int>();
  r.Done();
  return p;
}

// ---- profiles: linear cells (b), or jerk-limited ones (half-grid values, shapes, edges) ----
inline py::tuple ProfileState(const TemporalProfile& p) {
  const int m = p.num_pieces(), K = p.cells_per_piece();
  if (!p.jerk_limited()) return py::make_tuple("TemporalProfile", kStateVersion, "linear", p.b());
  std::vector<std::vector<double>> half(static_cast<size_t>(m));
  std::vector<std::vector<std::string>> shapes(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    for (int h = 0; h <= 2 * K; ++h) half[static_cast<size_t>(i)].push_back(p.half_b(i, h));
    for (int k = 0; k < K; ++k) shapes[static_cast<size_t>(i)].push_back(ToString(p.shape(i, k)));
  }
  return py::make_tuple("TemporalProfile", kStateVersion, "jerk_limited", half, shapes, p.cell_edges());
}
inline TemporalProfile ProfileFromState(const py::tuple& state) {
  Reader r(state, "TemporalProfile");
  const std::string kind = r.Get<std::string>();
  TemporalProfile profile;
  if (kind == "linear") {
    auto b = r.Get<std::vector<std::vector<double>>>();
    if (!b.empty()) profile = TemporalProfile(std::move(b));  // an empty profile: a result without an answer
  } else if (kind == "jerk_limited") {
    auto half = r.Get<std::vector<std::vector<double>>>();
    std::vector<std::vector<CellShape>> shapes;
    for (const auto& row : r.Get<std::vector<std::vector<std::string>>>()) {
      shapes.emplace_back();
      for (const std::string& name : row) {
        CellShape shape{};
        if (!EnumFromString(name, kCellShapes, &shape)) {
          throw py::value_error("unpickling TemporalProfile: unknown shape '" + name + "'");
        }
        shapes.back().push_back(shape);
      }
    }
    auto edges = r.Get<std::vector<std::vector<double>>>();
    profile = TemporalProfile::JerkLimited(std::move(half), std::move(shapes), std::move(edges));
  } else {
    throw py::value_error("unpickling TemporalProfile: unknown kind '" + kind + "'");
  }
  r.Done();
  return profile;
}

// ---- temporal results ----
inline py::tuple ResultState(const TemporalResult& t) {
  py::list joints;
  for (const JointInfo& j : t.joints)
    joints.append(py::make_tuple(j.joint, ToString(j.type), j.speed_ratio, j.angle, j.reason));
  py::object infeasibility = py::none(), relaxation = py::none();
  if (t.infeasibility) {
    infeasibility = py::make_tuple(t.infeasibility->cause, t.infeasibility->where, t.infeasibility->detail);
  }
  if (t.boundary_relaxation) {
    const TemporalResult::BoundaryRelaxation& b = *t.boundary_relaxation;
    relaxation = py::make_tuple(b.start_speed_given, b.start_speed, b.end_speed_given, b.end_speed, b.start_scale,
                                b.start_acceleration);
  }
  return py::make_tuple("TemporalResult", kStateVersion, ToString(t.status), t.message, t.solver, t.method, t.rows,
                        t.total_time, t.objective, t.piece_durations, t.iterations, t.solve_time_seconds,
                        t.build_time_seconds, ProfileState(t.profile), joints, t.max_velocity_ratio,
                        t.max_acceleration_ratio, OptionalState(t.max_speed_ratio),
                        OptionalState(t.max_acceleration_norm_ratio), OptionalState(t.max_thrust_ratio),
                        OptionalState(t.min_thrust_ratio), OptionalState(t.max_tilt_ratio), infeasibility, relaxation,
                        t.jerk_limited, t.max_jerk_ratio, t.scp_iterations, t.scp_history, t.reduced_accuracy);
}
inline TemporalResult ResultFromState(const py::tuple& state) {
  Reader r(state, "TemporalResult");
  TemporalResult t;
  t.status = r.Enum(kTemporalStatuses);
  t.message = r.Get<std::string>();
  t.solver = r.Get<std::string>();
  t.method = r.Get<std::string>();
  t.rows = r.Get<int>();
  t.total_time = r.Get<double>();
  t.objective = r.Get<double>();
  t.piece_durations = r.Get<std::vector<double>>();
  t.iterations = r.Get<int>();
  t.solve_time_seconds = r.Get<double>();
  t.build_time_seconds = r.Get<double>();
  t.profile = ProfileFromState(r.Get<py::tuple>());
  for (const py::handle& item : r.Get<py::list>()) {
    const auto j = item.cast<py::tuple>();
    JointInfo info;
    info.joint = j[0].cast<int>();
    if (!EnumFromString(j[1].cast<std::string>(), kJointTypes, &info.type)) {
      throw py::value_error("unpickling TemporalResult: unknown joint type");
    }
    info.speed_ratio = j[2].cast<double>();
    info.angle = j[3].cast<double>();
    if (j.size() > 4) info.reason = j[4].cast<std::string>();
    t.joints.push_back(info);
  }
  t.max_velocity_ratio = r.Get<double>();
  t.max_acceleration_ratio = r.Get<double>();
  t.max_speed_ratio = r.Optional<double>();
  t.max_acceleration_norm_ratio = r.Optional<double>();
  t.max_thrust_ratio = r.Optional<double>();
  t.min_thrust_ratio = r.Optional<double>();
  t.max_tilt_ratio = r.Optional<double>();
  if (const py::handle h = r.Next(); !h.is_none()) {
    const auto i = h.cast<py::tuple>();
    t.infeasibility =
        TemporalResult::Infeasibility{i[0].cast<std::string>(), i[1].cast<std::string>(), i[2].cast<std::string>()};
  }
  if (const py::handle h = r.Next(); !h.is_none()) {
    const auto b = h.cast<py::tuple>();
    TemporalResult::BoundaryRelaxation relaxation;
    relaxation.start_speed_given = b[0].cast<double>();
    relaxation.start_speed = b[1].cast<double>();
    relaxation.end_speed_given = b[2].cast<double>();
    relaxation.end_speed = b[3].cast<double>();
    relaxation.start_scale = b[4].cast<double>();
    relaxation.start_acceleration = b[5].cast<std::string>();
    t.boundary_relaxation = relaxation;
  }
  t.jerk_limited = r.Get<bool>();
  t.max_jerk_ratio = r.Get<double>();
  t.scp_iterations = r.Get<int>();
  t.scp_history = r.Get<std::vector<double>>();
  t.reduced_accuracy = r.Get<bool>();
  r.Done();
  return t;
}

// ---- plan results (with the last spatial attempt's figures and iterations) ----
inline py::tuple PlanState(const PlanResult& p) {
  std::vector<double> waypoints(p.waypoints.data(), p.waypoints.data() + p.waypoints.size());
  const SpatialResult& s = p.spatial;
  const auto cost = [](const SpatialCostBreakdown& c) {
    return py::make_tuple(c.smoothness, c.collision, c.length, c.dynamic);
  };
  py::list iterations;
  for (const SpatialIteration& i : s.iterations) {
    iterations.append(py::make_tuple(i.iteration, i.cost, i.step_cost, i.time_seconds, i.step_accepted));
  }
  const PlanStageTimes& times = p.times;
  return py::make_tuple("PlanResult", kStateVersion, ToString(p.status), p.message, waypoints, CurveState(p.curve),
                        py::make_tuple(static_cast<int>(s.status), s.message, CurveState(s.curve), s.durations,
                                       cost(s.initial_cost), cost(s.final_cost), iterations, s.solve_time_seconds),
                        ResultState(p.temporal), p.spatial_attempts, p.path_length, p.min_clearance,
                        p.min_interior_speed, p.min_curvature_radius, p.start_scale,
                        py::make_tuple(times.search_seconds, times.spatial_seconds, times.check_seconds,
                                       times.temporal_seconds, times.total_seconds));
}
inline PlanResult PlanFromState(const py::tuple& state) {
  Reader r(state, "PlanResult");
  PlanResult p;
  p.status = r.Enum(kPlanStatuses);
  p.message = r.Get<std::string>();
  const auto waypoints = r.Get<std::vector<double>>();
  if (waypoints.size() % 3 != 0) throw py::value_error("unpickling PlanResult: waypoints are not points");
  p.waypoints = Eigen::Map<const Waypoints>(waypoints.data(), 3, static_cast<Eigen::Index>(waypoints.size() / 3));
  p.curve = CurveFromState(r.Get<py::tuple>());
  {
    const auto s = r.Get<py::tuple>();
    if (s.size() != 8) throw py::value_error("unpickling PlanResult: the spatial state has the wrong size");
    const int status = s[0].cast<int>();
    if (status < 0 || status > static_cast<int>(SpatialStatus::kFailure)) {
      throw py::value_error("unpickling PlanResult: spatial status " + std::to_string(status));
    }
    p.spatial.status = static_cast<SpatialStatus>(status);
    p.spatial.message = s[1].cast<std::string>();
    p.spatial.curve = CurveFromState(s[2].cast<py::tuple>());
    p.spatial.durations = s[3].cast<std::vector<double>>();
    const auto cost = [](const py::handle& h) {
      const auto c = h.cast<std::vector<double>>();
      if (c.size() != 4) throw py::value_error("unpickling PlanResult: a spatial cost");
      return SpatialCostBreakdown{c[0], c[1], c[2], c[3]};
    };
    p.spatial.initial_cost = cost(s[4]);
    p.spatial.final_cost = cost(s[5]);
    for (const py::handle& item : s[6].cast<py::list>()) {
      const auto i = item.cast<py::tuple>();
      SpatialIteration iteration;
      iteration.iteration = i[0].cast<int>();
      iteration.cost = i[1].cast<double>();
      iteration.step_cost = i[2].cast<double>();
      iteration.time_seconds = i[3].cast<double>();
      iteration.step_accepted = i[4].cast<bool>();
      p.spatial.iterations.push_back(iteration);
    }
    p.spatial.solve_time_seconds = s[7].cast<double>();
  }
  p.temporal = ResultFromState(r.Get<py::tuple>());
  p.spatial_attempts = r.Get<int>();
  p.path_length = r.Get<double>();
  p.min_clearance = r.Get<double>();
  p.min_interior_speed = r.Get<double>();
  p.min_curvature_radius = r.Get<double>();
  p.start_scale = r.Get<double>();
  const auto times = r.Get<std::vector<double>>();
  if (times.size() != 5) throw py::value_error("unpickling PlanResult: stage times");
  p.times = PlanStageTimes{times[0], times[1], times[2], times[3], times[4]};
  r.Done();
  return p;
}

}  // namespace pickle_state
}  // namespace timeopt
