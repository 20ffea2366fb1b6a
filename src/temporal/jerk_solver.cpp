// The jerk-limited temporal problem by sequential convex programming (TemporalSolver's
// SolveJerkLimited, declared in temporal_solver.h; the discretization is jerk_discretization.cpp).
//
// 1. Solve the jerk-limited discretization without the jerk rows of regular cells: continuous
//    sddot, velocity and acceleration limits, the exact jerk bounds of rest cells. Its T is a lower
//    bound of the jerk-limited optimum on this grid; the solution is the first linearization point.
// 2. Repeat: linearize the jerk rows at the last solution (largest b per cell), solve. Every
//    solution satisfies the true jerk limit (the linearized rows are conservative for any
//    linearization point), so each one is a valid answer.
// 3. Stop when T changes by less than problem.scp_tolerance relative, when a solve does not lower
//    T (the previous solution is kept: T never increases over the reported answers), or after
//    problem.max_scp_iterations jerk-feasible solves.
// Every solve has the same sparsity pattern, so the conic solver reuses its symbolic analysis.
//
// A backend whose jerk_rows() is kExact (Ipopt) instead solves the discretization with the exact,
// non-convex jerk rows once: a local optimum of the same grid, for comparison.

#include <chrono>
#include <cmath>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver_internal.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point from) {
  return std::chrono::duration<double>(Clock::now() - from).count();
}

}  // namespace

TemporalResult TemporalSolver::SolveJerkLimited(const TemporalProblem& problem) {
  TemporalResult best;
  best.solver = ToString(backend());
  const std::string name = best.solver;
  double build_time = 0.0, solve_time = 0.0;
  int iterations = 0;
  std::vector<double> history;

  // One convex solve at `linearization` (null: the jerk-free first solve) into *out; false with
  // out's status and message set when it does not end optimal.
  const auto solve = [&](JerkRows rows, const std::vector<double>* linearization, TemporalResult* out,
                         std::vector<double>* grid_b) {
    const Clock::time_point start = Clock::now();
    TemporalDiscretization d;
    try {
      d = DiscretizeJerkLimited(problem, rows, linearization);
    } catch (const std::invalid_argument& e) {
      out->status = TemporalStatus::kInvalidInput;
      out->message = e.what();
      return false;
    }
    out->joints = d.joints;
    build_time += SecondsSince(start);
    if (d.infeasible_reason) {
      out->status = TemporalStatus::kInfeasible;
      out->message = *d.infeasible_reason;
      return false;
    }
    std::vector<double> x;
    bool finishing = false;
    try {
      if (d.num_vars == 0) {
        if (d.MaxViolation(x) > 0.0) {
          out->status = TemporalStatus::kInfeasible;
          out->message = "the fixed speeds violate a limit";
          return false;
        }
      } else {
        out->build_time_seconds = 0.0;
        SolveDiscretized(d, out, &x);
        build_time += out->build_time_seconds;
        solve_time += out->solve_time_seconds;
        iterations += out->iterations;
        if (out->status != TemporalStatus::kOptimal) return false;
        if (static_cast<int>(x.size()) != d.num_vars) {
          out->status = TemporalStatus::kNumericalError;
          out->message = name + " backend: optimal without a solution of the right size";
          return false;
        }
      }
      finishing = true;
      const std::string message = out->message;
      const bool reduced = out->reduced_accuracy;
      internal::FinishOptimalResult(problem, d, x, out);
      out->message = message;
      out->reduced_accuracy = reduced;
    } catch (const std::invalid_argument& e) {
      out->status = finishing ? TemporalStatus::kNumericalError : TemporalStatus::kInvalidInput;
      out->message = finishing ? name + " backend: the solution makes no profile: " + e.what()
                               : std::string(e.what());
      return false;
    } catch (const std::exception& e) {
      out->status = TemporalStatus::kNumericalError;
      out->message = name + " backend: unexpected error: " + e.what();
      return false;
    } catch (...) {
      out->status = TemporalStatus::kNumericalError;
      out->message = name + " backend: unexpected error";
      return false;
    }
    grid_b->resize(d.grid.size());
    for (size_t g = 0; g < d.grid.size(); ++g) {
      (*grid_b)[g] = std::max(0.0, d.GridB(static_cast<int>(g), x));
    }
    return true;
  };
  const auto finish = [&](TemporalResult r) {
    r.solver = name;
    r.jerk_limited = true;
    r.build_time_seconds = build_time;
    r.solve_time_seconds = solve_time;
    r.iterations = iterations;
    r.scp_iterations = static_cast<int>(history.size());
    r.scp_history = history;
    return r;
  };

  TemporalResult first;
  std::vector<double> linearization;
  if (jerk_rows() == JerkRows::kExact) {
    solve(JerkRows::kExact, nullptr, &first, &linearization);
    return finish(first);
  }
  if (!solve(JerkRows::kNone, nullptr, &first, &linearization)) {
    if (first.status == TemporalStatus::kInfeasible && first.message.rfind("no time", 0) == 0) {
      first.message = "no profile with continuous acceleration meets the limits and the boundary "
                      "states (" + first.message + ")";
    }
    return finish(first);
  }
  history.push_back(first.total_time);

  bool have_best = false;
  for (int n = 0; n < problem.max_scp_iterations; ++n) {
    TemporalResult next;
    std::vector<double> next_b;
    if (!solve(JerkRows::kLinearized, &linearization, &next, &next_b)) {
      if (have_best) {
        best.message = "stopped at convex solve " + std::to_string(history.size() + 1) + ": " +
                       ToString(next.status) + ": " + next.message;
        break;
      }
      return finish(next);
    }
    const double previous = history.back();
    history.push_back(next.total_time);
    const bool converged = have_best && std::abs(previous - next.total_time) <= problem.scp_tolerance * next.total_time;
    if (!have_best || next.total_time < best.total_time) {
      best = std::move(next);
      have_best = true;
    }
    linearization = std::move(next_b);
    if (converged) break;
  }
  return finish(best);
}

}  // namespace timeopt
