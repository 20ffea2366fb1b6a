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
// Each solve sees only the rows that can bind (working sets, see WorkingSet below): the first one
// those near their bound at the jerk-free certified optimum on the paper's grid (one cheap solve,
// interpolated onto this grid), later ones those near their bound at the previous answer. An
// answer that violates a row left out is solved again with it, so every answer satisfies every row.
// On the benchmark's curves (m = 10, K = 50) this keeps ~15-45% of the rows and halves the time.
//
// A backend whose jerk_rows() is kExact (Ipopt) instead solves the discretization with the exact,
// non-convex jerk rows once: a local optimum of the same grid, for comparison.

#include <algorithm>
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

// Working sets. Of a convex solve's inequality rows (~60 per cell, the Bernstein coefficients of
// every limit on every axis) only a few are near their bound at the answer, and successive solves
// of the programme move little, so a solve starts from the rows that reach a fraction of their
// bound at the previous answer (measured on the benchmark's curves, m = 10, K = 50: 17% of the
// rows reach 0.5 of their bound at the answer, 5.5% reach 0.99): kWorkingSetFraction when that
// answer has settled, kUnsettledFraction when it still moved by more than kWorkingSetSettled, and
// kGuessFraction for the first solve, whose "previous answer" is the certified guess. Equalities,
// two-sided rows and rows with a bound <= 0 are always in. An answer that violates a row left out
// adds it (with the rows of its cells, and those near their bound at that answer) and is solved
// again; after kMaxWorkingSetRounds solves every row is in. Measured (BM_SocpJerkLimited
// m = 10, K = 50; the shipped waypoints with j = 10; the forest plan, K = 20): 224 / 244 / ~450 ms
// with every row, 90-100 / 145 / 363 ms with these fractions; 0.7 / 0.7 / 0.7 gave 90 / 175 /
// 410 ms, with more re-solves and, before the point velocity bounds, failed solves.
constexpr double kWorkingSetFraction = 0.7;
constexpr double kUnsettledFraction = 0.3;
constexpr double kGuessFraction = 0.5;
constexpr int kMaxWorkingSetRounds = 3;
constexpr double kWorkingSetSettled = 0.01;

// Upper bounds of d's free values: the velocity limit at each one's own point. The certified
// velocity rows imply them (they bound f'^2 b on whole cells, and b at a cell's middle point is
// the profile's own), so the answer does not change; a working set needs them, since without the
// rows it leaves out a value could grow without bound (shorter and shorter time). Only working
// sets get them: on the full problem they would duplicate rows that are active at the same point.
void BoundByPointVelocity(const TemporalProblem& problem, TemporalDiscretization* d) {
  const int K = problem.cells_per_piece;
  const Eigen::Vector3d vmax2 = problem.limits.max_velocity.cwiseProduct(problem.limits.max_velocity);
  for (int i = 0; i < d->num_pieces; ++i) {
    const std::vector<double>& edges = d->cell_edges[static_cast<size_t>(i)];
    for (int j = 0; j <= 2 * K; ++j) {
      const GridValue& v = d->grid[static_cast<size_t>(d->GridIndex(i, j))];
      if (v.var < 0) continue;
      const size_t k = static_cast<size_t>(std::min(j / 2, K - 1));
      const double s = edges[k] + 0.5 * (j - 2 * static_cast<int>(k)) * (edges[k + 1] - edges[k]);
      const Eigen::Vector3d t = problem.curve.Evaluate(i, s, 1);
      double& ub = d->var_upper[static_cast<size_t>(v.var)];
      if (problem.limits.max_speed && t.norm() > problem.zero_tangent_tolerance) {
        ub = std::min(ub, *problem.limits.max_speed * *problem.limits.max_speed / (t.squaredNorm() * v.scale));
      }
      for (int a = 0; a < 3; ++a) {
        if (std::abs(t(a)) <= problem.zero_tangent_tolerance) continue;
        ub = std::min(ub, vmax2(a) / (t(a) * t(a) * v.scale));
      }
    }
  }
}

double RowValue(const LinearRow& row, const std::vector<double>& x) {
  double value = 0.0;
  for (const auto& t : row.terms) value += t.second * x[static_cast<size_t>(t.first)];
  return value;
}

bool AlwaysKept(const LinearRow& row) {
  return std::isfinite(row.lower) || !(row.upper > 0.0) || !std::isfinite(row.upper);
}

std::vector<char> WorkingSet(const TemporalDiscretization& d, const std::vector<double>& x, bool every_jerk_row,
                             double fraction) {
  std::vector<char> keep(d.rows.size(), 0);
  for (size_t r = 0; r < d.rows.size(); ++r) {
    const LinearRow& row = d.rows[r];
    keep[r] = AlwaysKept(row) || (every_jerk_row && row.kind == LinearRow::Kind::kJerk) ||
              RowValue(row, x) >= fraction * row.upper;
  }
  return keep;
}

// Adds to *keep the rows that x violates and, when there are any, every row on a variable of a
// violated row (the cells where the answer moved most) and those near their bound at x; every row
// when `all`. Returns the number added (0: x satisfies every row). A row left out counts as
// violated when it exceeds its bound by more than the worst row the solver was given: the
// interior-point answer meets its rows only to its tolerance, and a left-out row next to a kept
// one (Bernstein coefficients of one limit often are) may be over by as much.
int GrowWorkingSet(const std::vector<LinearRow>& rows, const std::vector<double>& x, bool all,
                   std::vector<char>* keep) {
  double given = 0.0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if ((*keep)[r] && std::isfinite(rows[r].upper)) given = std::max(given, RowValue(rows[r], x) - rows[r].upper);
  }
  std::vector<char> moved(x.size(), 0);
  bool violated = false;
  for (size_t r = 0; r < rows.size(); ++r) {
    if ((*keep)[r] || !(RowValue(rows[r], x) - rows[r].upper > given)) continue;
    violated = true;
    for (const auto& t : rows[r].terms) moved[static_cast<size_t>(t.first)] = 1;
  }
  if (!violated) return 0;
  int added = 0;
  for (size_t r = 0; r < rows.size(); ++r) {
    if ((*keep)[r]) continue;
    bool add = all || RowValue(rows[r], x) >= kUnsettledFraction * rows[r].upper;
    for (const auto& t : rows[r].terms) add = add || moved[static_cast<size_t>(t.first)];
    if (add) {
      (*keep)[r] = 1;
      ++added;
    }
  }
  return added;
}

}  // namespace

TemporalResult TemporalSolver::SolveJerkLimited(const TemporalProblem& problem) {
  TemporalResult best;
  best.solver = ToString(backend());
  const std::string name = best.solver;
  double build_time = 0.0, solve_time = 0.0;
  int iterations = 0;
  std::vector<double> history;

  // The free values of `d` (the jerk-limited grid) from the jerk-free certified optimum on the
  // paper's grid (b linear per cell, interpolated): a cheap guess of the jerk-free answer, which
  // chooses the first solve's working set. Empty when that problem has no answer.
  const auto certified_guess = [&](const TemporalDiscretization& d) {
    std::vector<double> x;
    const Clock::time_point start = Clock::now();
    TemporalProblem certified = problem;
    certified.limits.max_jerk.reset();
    certified.constraint_mode = ConstraintMode::kCertified;
    TemporalDiscretization cd;
    try {
      cd = Discretize(certified);
    } catch (const std::exception&) {
      return x;
    }
    build_time += SecondsSince(start);
    if (cd.infeasible_reason || cd.num_vars == 0) return x;
    TemporalResult r;
    std::vector<double> cx;
    try {
      SolveDiscretized(cd, &r, &cx);
    } catch (const std::exception&) {
      return x;
    }
    build_time += r.build_time_seconds;
    solve_time += r.solve_time_seconds;
    iterations += r.iterations;
    if (r.status != TemporalStatus::kOptimal || static_cast<int>(cx.size()) != cd.num_vars) return x;
    const int K = problem.cells_per_piece;
    x.assign(static_cast<size_t>(d.num_vars), 0.0);
    for (int i = 0; i < d.num_pieces; ++i) {
      const std::vector<double>& edges = d.cell_edges[static_cast<size_t>(i)];
      for (int j = 0; j <= 2 * K; ++j) {
        const GridValue& g = d.grid[static_cast<size_t>(d.GridIndex(i, j))];
        if (g.var < 0) continue;
        const int k = std::min(j / 2, K - 1);
        const double u = 0.5 * (j - 2 * k);
        const double at = K * (edges[static_cast<size_t>(k)] + u * (edges[static_cast<size_t>(k) + 1] - edges[static_cast<size_t>(k)]));
        const int c = std::min(static_cast<int>(at), K - 1);
        const double w = at - c;
        const double b = (1.0 - w) * std::max(0.0, cd.GridB(cd.GridIndex(i, c), cx)) +
                         w * std::max(0.0, cd.GridB(cd.GridIndex(i, c + 1), cx));
        x[static_cast<size_t>(g.var)] = b / g.scale;
      }
    }
    return x;
  };

  // One convex solve at `linearization` (null: the jerk-free first solve) into *out, and its free
  // values into *x; false with out's status and message set when it does not end optimal. With the
  // previous solve's values `previous`, only a working set of the inequality rows goes to the
  // backend (see WorkingSet); rows left out that the answer violates are added and it is solved
  // again, so the answer satisfies every row.
  const auto solve = [&](JerkRows rows, const std::vector<double>* linearization,
                         const std::vector<double>* previous, TemporalResult* out,
                         std::vector<double>* grid_b, std::vector<double>* x_out) {
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
    if (d.infeasible_reason) {
      build_time += SecondsSince(start);
      out->status = TemporalStatus::kInfeasible;
      out->message = *d.infeasible_reason;
      return false;
    }
    std::vector<char> keep;
    std::vector<double> guess;
    if (rows == JerkRows::kNone && d.num_vars > 0) {
      guess = certified_guess(d);
      if (!guess.empty()) previous = &guess;
    }
    // How near its bound a row must be to enter the working set depends on how far the answer may
    // still move: a previous answer whose T is within kWorkingSetSettled of the one before has
    // nearly settled; one still moving far (and the certified guess) picks rows that may not bind
    // at the next answer, and each row it misses costs a solve again.
    const size_t h = history.size();
    const bool settled = h < 2 || std::abs(history[h - 1] - history[h - 2]) <= kWorkingSetSettled * history[h - 1];
    if (previous != nullptr && static_cast<int>(previous->size()) == d.num_vars && d.num_vars > 0) {
      // The first linearized solve starts from the jerk-free answer, which says nothing of where
      // the jerk rows will bind: it takes all of them.
      const double fraction = rows == JerkRows::kNone ? kGuessFraction : settled ? kWorkingSetFraction : kUnsettledFraction;
      keep = WorkingSet(d, *previous, h == 1, fraction);
    }
    build_time += SecondsSince(start);
    std::vector<double>& x = *x_out;
    x.clear();
    bool finishing = false;
    try {
      if (d.num_vars == 0) {
        if (d.MaxViolation(x) > 0.0) {
          out->status = TemporalStatus::kInfeasible;
          out->message = "the fixed speeds violate a limit";
          return false;
        }
      } else {
        std::vector<LinearRow> all_rows;
        std::vector<double> var_upper = d.var_upper;
        if (!keep.empty()) {
          all_rows = std::move(d.rows);
          BoundByPointVelocity(problem, &d);
        }
        for (int round = 0;; ++round) {
          if (!keep.empty()) {
            const Clock::time_point select = Clock::now();
            d.rows.clear();
            for (size_t r = 0; r < all_rows.size(); ++r) {
              if (keep[r]) d.rows.push_back(all_rows[r]);
            }
            build_time += SecondsSince(select);
          }
          out->build_time_seconds = 0.0;
          SolveDiscretized(d, out, &x);
          build_time += out->build_time_seconds;
          solve_time += out->solve_time_seconds;
          iterations += out->iterations;
          if (out->status != TemporalStatus::kOptimal && !keep.empty() &&
              std::count(keep.begin(), keep.end(), 1) < static_cast<std::ptrdiff_t>(keep.size())) {
            // A working set the solver could not finish (not seen since the point velocity bounds,
            // over 120 random problems): the same solve with every row decides.
            std::fill(keep.begin(), keep.end(), 1);
            continue;
          }
          if (out->status != TemporalStatus::kOptimal) return false;
          if (static_cast<int>(x.size()) != d.num_vars) {
            out->status = TemporalStatus::kNumericalError;
            out->message = name + " backend: optimal without a solution of the right size";
            return false;
          }
          if (keep.empty()) break;
          // Rows left out that x violates, and those near their bound at x, join the set; the
          // last round (kMaxWorkingSetRounds) takes every row.
          const int added = GrowWorkingSet(all_rows, x, round + 1 >= kMaxWorkingSetRounds, &keep);
          if (added == 0) {
            d.rows = std::move(all_rows);
            d.var_upper = std::move(var_upper);
            break;
          }
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
  std::vector<double> linearization, x;
  if (jerk_rows() == JerkRows::kExact) {
    solve(JerkRows::kExact, nullptr, nullptr, &first, &linearization, &x);
    return finish(first);
  }
  if (!solve(JerkRows::kNone, nullptr, nullptr, &first, &linearization, &x)) {
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
    std::vector<double> next_b, next_x;
    if (!solve(JerkRows::kLinearized, &linearization, &x, &next, &next_b, &next_x)) {
      if (have_best) {
        best.message = "stopped at convex solve " + std::to_string(history.size() + 1) + ": " +
                       ToString(next.status) + ": " + next.message;
        break;
      }
      if (next.status == TemporalStatus::kInfeasible) {
        // The linearized jerk rows are conservative (an inner approximation), so their having no
        // solution at the jerk-free answer proves nothing about the problem: the property sweep
        // found such a case that Ipopt's exact rows solve (a polyline started at speed, K = 6).
        // Not a certificate, then, but a failure of the method, which the Ipopt fallback takes.
        next.status = TemporalStatus::kNumericalError;
        next.message = "the first convex approximation of the jerk rows (at the jerk-free answer) has no "
                       "solution, which does not prove the problem infeasible (" + next.message + ")";
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
    x = std::move(next_x);
    if (converged) break;
  }
  return finish(best);
}

}  // namespace timeopt
