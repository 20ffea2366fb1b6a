// The jerk-limited temporal problem by sequential convex programming (TemporalSolver's
// SolveJerkLimited, declared in temporal_solver.h; the discretization is jerk_discretization.cpp).
//
// 1. Solve the jerk-limited discretization without its jerk rows: continuous sddot, velocity and
//    acceleration limits. Its T is a lower bound of the jerk-limited optimum on this grid; the
//    solution is the first linearization point.
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
//
// The SOCP backend first tries the structured path (SolveStructuredScp, structured_scp.cpp): the same programme
// over the control values of ControlBasis, which satisfy the equality rows by construction, with
// banded interior-point solves, the first one linearized at a jerk-free guess or at the answer of
// the same programme on a coarser grid (no jerk-free solve on the full grid) and each later one
// warm-started. Only when it does not answer does the general path
// above run.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "banded_ipm.h"
#include "discretization_internal.h"
#include "solver_internal.h"
#include "structured_scp.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {
namespace {

using Clock = internal::SteadyClock;
using internal::GridValues;
using internal::kGuessFraction;
using internal::kMaxWorkingSetRounds;
using internal::kUnsettledFraction;
using internal::kWorkingSetFraction;
using internal::kWorkingSetSettled;
using internal::ProfileOf;
using internal::SecondsSince;
using internal::SolveStructuredScp;
using internal::StructuredScp;

// The structured path's relative gap in J for each convex solve of the programme, as a share of
// the programme's own tolerance (scp_tolerance, 1e-4 by default), which bounds T's accuracy
// anyway. Measured (instructions; m = 10 / 20 / 10, K = 50 / 50 / 200): 67.4 M / 139.7 M /
// 287.2 M at a gap of 1e-7, 65.9 M / 134.0 M / 287.2 M at 1e-6 (a share of 1e-2), T the same to
// 9e-9 relative.
constexpr double kStructuredGapShare = 1e-2;
// The structured path first solves the programme on cells_per_piece / kCoarsening cells (when that
// is at least kMinCoarseCells), once, for its first linearization (see SolveJerkLimited).
// Measured (instructions of the whole solve; the benchmark's curves m = 10, K = 50 / m = 20, K = 50
// / m = 10, K = 200; without: 126 M / 268 M / 547 M): 99 M / 214 M / 432 M with 3, 122 M / 255 M
// / 506 M with 2, 124 M / 289 M / 759 M with 4 (the fine solve then misses rows). On the default
// plan (K = 20) 6 coarse cells per piece missed rows: the fine solves took a round each and the
// temporal stage 41.1 ms against 39.5 ms without (medians of 5 runs; 10 coarse cells: 46.1 ms).
constexpr int kCoarsening = 3;
constexpr int kMinCoarseCells = 12;
// The coarse solve's relative row and gap tolerance. Measured (instructions, the same three
// curves): 97.1 M / 209.1 M / 422.8 M at the usual 1e-8 and 1e-7, 94.3 M / 203.5 M / 410.9 M at
// 1e-5, 92.4 M / 197.9 M / 403.0 M at 1e-4, 90.6 M / 198.1 M / 398.9 M at 1e-3; T the same to
// 5e-9 relative. Again after the faster templates and passes (2026-12-03): 68.4 M / 140.0 M /
// 291.7 M at 1e-4, 67.4 M / 139.7 M / 287.2 M at 1e-3 (T the same to 1.2e-8), and at 1e-2 the
// fine solve at m = 20 missed rows (181.1 M).
constexpr double kCoarseTolerance = 1e-3;
// The structured path's jerk-free guess is solved on cells_per_piece / kGuessCoarsening cells (m = 10,
// K = 50, instructions of the whole solve: 253 M with 1, 222 M with 2, 204 M with 3, 214 M with 4).
constexpr int kGuessCoarsening = 3;
constexpr double kInf = std::numeric_limits<double>::infinity();
// How far above 1 an optimal answer's densely checked limit ratios may be (Finish): the property
// sweep's tolerance on the same check.
constexpr double kDenseLimitSlack = 1e-6;
// The general path's sequential convex programme that stops before its tolerance (a failed convex
// solve, or max_scp_iterations) answers only if its last step changed T by at most this share.
constexpr double kUnsettledShare = 1e-2;
// The jerk-free guess caps per-axis accelerations at this multiple of the largest one the jerk
// limit reaches over the path (see jerk_free_guess). On the default plan's curve at limits of 1e2
// (1e6), the structured path's convex solves took 214 iterations in the first (1e2: the iteration
// limit, and the general conic path answered) with 2, 188 (122) in all with 1 and 93 (96) with 0.5;
// the default plan itself is unchanged (its cap, 5.4 m/s^2, is above its 2).
constexpr double kGuessAccelerationMargin = 0.5;

// Upper bounds of d's free values: the velocity limit at each one's own point (a rest cell's
// middle value: the jerk limit at its rest point). The certified
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
      double& ub = d->var_upper[static_cast<size_t>(v.var)];
      const CellShape shape = d->shapes[static_cast<size_t>(i * K) + k];
      if (IsRestShape(shape) && j % 2 == 1) {
        // A rest cell's middle value is q at its rest point, not b at a point: its bound is the
        // jerk there, |f'_axis| (4 / 18) q^1.5 / L^2 <= j_axis (the other terms vanish at rest).
        const double L = edges[k + 1] - edges[k];
        const Eigen::Vector3d t =
            problem.curve.Evaluate(i, shape == CellShape::kRestStart ? edges[k] : edges[k + 1], 1);
        for (int a = 0; a < 3; ++a) {
          if (std::abs(t(a)) <= problem.zero_tangent_tolerance) continue;
          ub = std::min(
              ub, std::pow(18.0 * L * L * (*problem.limits.max_jerk)(a) / (4.0 * std::abs(t(a))), 2.0 / 3.0) / v.scale);
        }
        continue;
      }
      const double s = internal::HalfPointS(*d, i, j);
      const Eigen::Vector3d t = problem.curve.Evaluate(i, s, 1);
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

// A braking start (or an end reached while speeding up) as the first linearization point. The
// jerk-free guess keeps its speed where the vehicle must first bring its acceleration back to 0 at
// the jerk limit and slow down meanwhile; linearized there, the jerk rows (tangents of 1 / sqrt(b)
// at the guess's larger b) had no solution for a start at 0.25 m/s braking at 2 m/s^2 with a jerk
// limit of 10, which can be flown (it slows to 0.05 m/s). So b near such an end is capped by the
// fastest motion along the tangent from that state: the jerk at its limit along the tangent raises
// the acceleration from a0 < 0 (speed v0 + a0 t + j t^2 / 2), and keeps raising it. Only a starting
// point: the rows are conservative at any linearization point.
void CapAtBrakingEnds(const TemporalProblem& p, const TemporalDiscretization& d, std::vector<double>* b) {
  if (!p.limits.max_jerk || b->size() != d.grid.size() || d.cell_edges.empty()) return;
  const int m = d.num_pieces, half = d.cells_per_piece;
  for (const bool end : {false, true}) {
    const int piece = end ? m - 1 : 0;
    const double at = end ? 1.0 : 0.0;
    const Eigen::Vector3d v = end ? p.boundary.end_velocity : p.boundary.start_velocity;
    const Eigen::Vector3d acc = end ? p.boundary.end_acceleration : p.boundary.start_acceleration;
    const Eigen::Vector3d f1 = p.curve.Evaluate(piece, at, 1);
    const double speed = f1.norm();
    if (!(speed > p.zero_tangent_tolerance) || !(v.squaredNorm() > 0.0)) continue;
    const Eigen::Vector3d unit = f1 / speed;
    const double v0 = v.norm();
    // The acceleration along the path, away from the end (time runs backwards from an end).
    const double a0 = (end ? -1.0 : 1.0) * acc.dot(unit);
    if (!(a0 < 0.0)) continue;
    const double j = internal::LimitAlong(*p.limits.max_jerk, unit);
    if (!std::isfinite(j) || !(j > 0.0)) continue;
    // Speed against distance along the tangent: time for distance by bisection on the monotone
    // s(t) = v0 t + a0 t^2 / 2 + j t^3 / 6 while the speed stays >= 0 (its minimum at t = -a0 / j).
    const double t_low = -a0 / j;
    const double v_low = v0 + a0 * t_low + 0.5 * j * t_low * t_low;
    const auto speed_at = [&](double distance) {
      if (v_low <= 0.0) return 0.0;
      double lo = 0.0, hi = 1.0;
      const auto s_of = [&](double t) { return v0 * t + 0.5 * a0 * t * t + j * t * t * t / 6.0; };
      while (s_of(hi) < distance && hi < 1e12) hi *= 2.0;
      for (int n = 0; n < 60; ++n) {
        const double mid = 0.5 * (lo + hi);
        (s_of(mid) < distance ? lo : hi) = mid;
      }
      const double t = 0.5 * (lo + hi);
      return v0 + a0 * t + 0.5 * j * t * t;
    };
    for (int jh = 0; jh <= half; ++jh) {
      const int h = end ? half - jh : jh;
      const double s = internal::HalfPointS(d, piece, h);
      const double distance = speed * (end ? 1.0 - s : s);
      const double cap = speed_at(distance) / speed;
      double& value = (*b)[static_cast<size_t>(d.GridIndex(piece, h))];
      // A fixed value (the boundary's own b, which the cap equals) says nothing of the guess.
      if (d.grid[static_cast<size_t>(d.GridIndex(piece, h))].var < 0) continue;
      if (value <= cap * cap) break;  // the guess is below the fastest motion from here on
      value = cap * cap;
    }
  }
}

}  // namespace

namespace internal {

// One jerk-limited solve of a TemporalSolver (TemporalSolver::SolveJerkLimited): the steps of the
// policy (Ipopt's exact rows, or the structured path and then the general one) and what they share:
// the times, iterations and T of every convex solve, and the best answer of the general path.
class JerkLimitedSolve {
 public:
  JerkLimitedSolve(TemporalSolver& solver, const TemporalProblem& problem) : solver_(solver), problem_(problem) {
    best_.solver = ToString(solver.backend());
    name_ = best_.solver;
  }

  TemporalResult Run() {
    if (solver_.jerk_rows() == JerkRows::kExact) return SolveExact();
    if (solver_.structured_jerk_iterations() > 0) {
      if (std::optional<TemporalResult> r = SolveStructured()) return *r;
    }
    return SolveGeneral();
  }

 private:
  // The free values of `d` (the jerk-limited grid) from the jerk-free optimum on the paper's grid
  // with the rows of `mode` (paper or certified; b linear per cell, interpolated): a cheap guess of
  // the jerk-free answer, which chooses the first solve's working set. Empty when that problem has
  // no answer.
  std::vector<double> JerkFreeGuess(const TemporalDiscretization& d, int guess_cells, ConstraintMode mode);
  // One convex solve at `linearization` (null: the jerk-free first solve) into *out, and its free
  // values into *x; false with out's status and message set when it does not end optimal. With the
  // previous solve's values `previous`, only a working set of the inequality rows goes to the
  // backend (see WorkingSet); rows left out that the answer violates are added and it is solved
  // again, so the answer satisfies every row.
  bool SolveConvex(JerkRows rows, const std::vector<double>* linearization, const std::vector<double>* previous,
                   TemporalResult* out, std::vector<double>* grid_b, std::vector<double>* x_out);
  // r with this solve's solver name, times, iterations and convex solves' T.
  TemporalResult Finish(TemporalResult r) const;
  // A backend whose jerk_rows() is kExact (Ipopt): the exact rows, solved once.
  TemporalResult SolveExact();
  // The structured path (SolveStructuredScp, structured_scp.cpp), from the coarse programme's
  // answer or a jerk-free guess; nothing when it does not answer.
  std::optional<TemporalResult> SolveStructured();
  // The programme on a coarser grid first (kCoarsening times fewer cells): its answer, a
  // jerk-limited profile, is the first linearization and start on this grid, and says which
  // jerk rows can bind (the jerk-free guess says nothing of that, so its first solve takes
  // every jerk row). Empty when the coarse programme does not answer.
  std::vector<double> CoarseStart(const TemporalDiscretization& d, const BandedIpmSettings& settings,
                                  SolveWorkspace& workspace);
  // The guess on a coarser grid: it only chooses the first linearization, start and working
  // set.
  std::vector<double> JerkFreeStart(const TemporalDiscretization& d);
  // The general path: the sequential convex programme over the free values on the conic solver.
  TemporalResult SolveGeneral();

  TemporalSolver& solver_;
  const TemporalProblem& problem_;
  std::string name_;
  double build_time_ = 0.0, solve_time_ = 0.0;
  int iterations_ = 0;
  std::vector<double> history_;
  TemporalResult best_;
};

std::vector<double> JerkLimitedSolve::JerkFreeGuess(const TemporalDiscretization& d, int guess_cells,
                                                    ConstraintMode mode) {
  std::vector<double> x;
  const Clock::time_point start = Clock::now();
  TemporalProblem jerk_free = problem_;
  // Per-axis accelerations the jerk limit cannot reach over this path do not shape the guess: a
  // line of length P from rest to rest peaks at (P j^2 / 2)^(1/3) (jerk +j, -j, -j, +j). Above it,
  // the jerk-free guess flew far faster than the answer, and the first linearization there took
  // the structured path past its iteration limit (limits of 1e2-1e6 on the default plan's curve).
  {
    double length = 0.0;
    for (int i = 0; i < problem_.curve.num_pieces(); ++i) length += internal::PieceLengthEstimate(problem_.curve, i);
    const double j = problem_.limits.max_jerk->minCoeff();
    const double reachable = std::cbrt(0.5 * length * j * j);
    if (std::isfinite(reachable) && reachable > 0.0) {
      for (int a = 0; a < 3; ++a) {
        double& limit = jerk_free.limits.max_acceleration(a);
        if (limit > kGuessAccelerationMargin * reachable) limit = kGuessAccelerationMargin * reachable;
      }
    }
  }
  jerk_free.limits.max_jerk.reset();
  jerk_free.constraint_mode = mode;
  jerk_free.cells_per_piece = guess_cells;
  TemporalDiscretization cd;
  try {
    cd = Discretize(jerk_free);
  } catch (const std::exception&) {
    return x;
  }
  build_time_ += SecondsSince(start);
  if (cd.infeasible_reason || cd.num_vars == 0) return x;
  TemporalResult r;
  std::vector<double> cx;
  try {
    solver_.SolveDiscretized(cd, &r, &cx);
  } catch (const std::exception&) {
    return x;
  }
  build_time_ += r.build_time_seconds;
  solve_time_ += r.solve_time_seconds;
  iterations_ += r.iterations;
  if (r.status != TemporalStatus::kOptimal || static_cast<int>(cx.size()) != cd.num_vars) return x;
  const int K = d.cells_per_piece / 2;  // d's cells (it has K half cells of each)
  x.assign(static_cast<size_t>(d.num_vars), 0.0);
  for (int i = 0; i < d.num_pieces; ++i) {
    for (int j = 0; j <= 2 * K; ++j) {
      const GridValue& g = d.grid[static_cast<size_t>(d.GridIndex(i, j))];
      if (g.var < 0) continue;
      const double at = guess_cells * internal::HalfPointS(d, i, j);
      const int c = std::min(static_cast<int>(at), guess_cells - 1);
      const double w = at - c;
      const double b = (1.0 - w) * std::max(0.0, cd.GridB(cd.GridIndex(i, c), cx)) +
                       w * std::max(0.0, cd.GridB(cd.GridIndex(i, c + 1), cx));
      x[static_cast<size_t>(g.var)] = b / g.scale;
    }
  }
  // Rest cells hold q at their rest point in the middle: that of a constant s-jerk, q = b at the
  // far end (the jerk-free profile's b ~ s near rest would make it about twice that, a first
  // linearization far too cautious: on the units test's quintic 4 convex solves, not 3).
  std::vector<double> grid_b = GridValues(d, x);
  internal::RestAlphaOfConstantJerk(d, &grid_b);
  for (size_t g = 0; g < d.grid.size(); ++g) {
    if (d.grid[g].var >= 0) x[static_cast<size_t>(d.grid[g].var)] = grid_b[g] / d.grid[g].scale;
  }
  return x;
}

bool JerkLimitedSolve::SolveConvex(JerkRows rows, const std::vector<double>* linearization,
                                   const std::vector<double>* previous, TemporalResult* out,
                                   std::vector<double>* grid_b, std::vector<double>* x_out) {
  const Clock::time_point start = Clock::now();
  TemporalDiscretization d;
  try {
    d = DiscretizeJerkLimited(problem_, rows, linearization);
  } catch (const std::invalid_argument& e) {
    out->status = TemporalStatus::kInvalidInput;
    out->message = e.what();
    return false;
  }
  out->joints = d.joints;
  if (d.infeasible_reason) {
    build_time_ += SecondsSince(start);
    out->status = TemporalStatus::kInfeasible;
    out->message = *d.infeasible_reason;
    return false;
  }
  std::vector<char> keep;
  std::vector<double> guess;
  // The general path: the conic solver over the free values with the equality rows (the
  // structured path over the control values already had its turn).
  d.controls.reset();
  if (rows == JerkRows::kNone && d.num_vars > 0) {
    guess = JerkFreeGuess(d, problem_.cells_per_piece, ConstraintMode::kCertified);
    if (!guess.empty()) previous = &guess;
  }
  // How near its bound a row must be to enter the working set depends on how far the answer may
  // still move: a previous answer whose T is within kWorkingSetSettled of the one before has
  // nearly settled; one still moving far (and the certified guess) picks rows that may not bind
  // at the next answer, and each row it misses costs a solve again.
  const size_t h = history_.size();
  const bool settled = h < 2 || std::abs(history_[h - 1] - history_[h - 2]) <= kWorkingSetSettled * history_[h - 1];
  if (previous != nullptr && static_cast<int>(previous->size()) == d.num_vars && d.num_vars > 0) {
    // The first linearized solve starts from the jerk-free answer, which says nothing of where
    // the jerk rows will bind: it takes all of them.
    const double fraction = rows == JerkRows::kNone ? kGuessFraction
                            : settled               ? kWorkingSetFraction
                                                    : kUnsettledFraction;
    keep = WorkingSet(d, *previous, h == 1, fraction);
  }
  build_time_ += SecondsSince(start);
  std::vector<double>& x = *x_out;
  x.clear();
  const bool solved = internal::MapSolveExceptions(name_, out, [&](bool* finishing) {
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
        BoundByPointVelocity(problem_, &d);
      }
      for (int round = 0;; ++round) {
        if (!keep.empty()) {
          const Clock::time_point select = Clock::now();
          d.rows.clear();
          for (size_t r = 0; r < all_rows.size(); ++r) {
            if (keep[r]) d.rows.push_back(all_rows[r]);
          }
          build_time_ += SecondsSince(select);
        }
        out->build_time_seconds = 0.0;
        solver_.SolveDiscretized(d, out, &x);
        build_time_ += out->build_time_seconds;
        solve_time_ += out->solve_time_seconds;
        iterations_ += out->iterations;
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
          out->message = name_ + " backend: optimal without a solution of the right size";
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
    *finishing = true;
    const std::string message = out->message;
    const bool reduced = out->reduced_accuracy;
    internal::FinishOptimalResult(problem_, d, x, out);
    out->message = message;
    out->reduced_accuracy = reduced;
    return true;
  });
  if (!solved) return false;
  grid_b->resize(d.grid.size());
  for (size_t g = 0; g < d.grid.size(); ++g) {
    (*grid_b)[g] = std::max(0.0, d.GridB(static_cast<int>(g), x));
  }
  return true;
}

TemporalResult JerkLimitedSolve::Finish(TemporalResult r) const {
  // An answer is taken only if it is what its rows say. A tied piece crossed too fast for the
  // rounding in its b (TiedPieceTooShortForItsSpeed) had rows that rounding moved: answers held
  // every limit but were up to 7.9% slow. And every row holds on whole cells, so the dense check
  // along the exact trajectory can only find rounding (~1e-12) above a limit; more (a jerk of 1.49 x
  // the limit on a 1 um tied piece, b ~1e12 there) is no answer rather than a false one.
  if (r.status == TemporalStatus::kOptimal) {
    if (std::optional<std::string> why = internal::TiedPieceTooShortForItsSpeed(problem_, r.profile)) {
      r.status = TemporalStatus::kNumericalError;
      r.message = *why;
    }
  } else if (r.status != TemporalStatus::kInfeasible) {
    // No answer: say so where rounding on a short tied piece may be the cause.
    if (std::optional<std::string> why = internal::TiedPieceMayBeTooShort(problem_)) r.message += "; " + *why;
  }
  const struct {
    double ratio;
    const char* name;
  } checks[] = {
      {r.max_velocity_ratio, "velocity"}, {r.max_acceleration_ratio, "acceleration"}, {r.max_jerk_ratio, "jerk"}};
  for (const auto& check : checks) {
    if (r.status != TemporalStatus::kOptimal) break;
    if (!(check.ratio <= 1.0 + kDenseLimitSlack)) {
      r.status = TemporalStatus::kNumericalError;
      r.message = "the answer exceeds its " + std::string(check.name) + " limit by a factor " +
                  std::to_string(check.ratio) + " between its rows (rounding, where b spans many orders of magnitude)";
    }
  }
  r.solver = name_;
  r.jerk_limited = true;
  r.build_time_seconds = build_time_;
  r.solve_time_seconds = solve_time_;
  r.iterations = iterations_;
  r.scp_iterations = static_cast<int>(history_.size());
  r.scp_history = history_;
  return r;
}

TemporalResult JerkLimitedSolve::SolveExact() {
  TemporalResult first;
  std::vector<double> linearization, x;
  if (!SolveConvex(JerkRows::kExact, nullptr, nullptr, &first, &linearization, &x) &&
      first.status == TemporalStatus::kInfeasible && first.message.find(internal::kLocalVerdict) != std::string::npos) {
    // A point of local infeasibility of the exact jerk rows, which are not convex, proves
    // nothing (a line from 0.09 to 0.06 m/s at a jerk limit of 0.018 m/s^3 got this verdict, and
    // the sequential convex programme's answer holds every limit). The problem without the jerk
    // rows, convex, decides: infeasible too, and that is a proof; otherwise no verdict.
    TemporalResult relaxed;
    std::vector<double> relaxed_b, relaxed_x;
    const TemporalResult local = first;
    if (SolveConvex(JerkRows::kNone, nullptr, nullptr, &relaxed, &relaxed_b, &relaxed_x)) {
      first = local;
      first.status = TemporalStatus::kNumericalError;
      first.message = local.message +
                      "; without the jerk limit the problem has a solution, so this is no "
                      "proof that none exists with it";
    } else if (relaxed.status == TemporalStatus::kInfeasible) {
      first = relaxed;
      first.message =
          "no profile with continuous acceleration meets the limits and the boundary states, even "
          "without the jerk limit (" +
          relaxed.message + ")";
    } else {
      first = local;
      first.status = TemporalStatus::kNumericalError;
      first.message =
          local.message + "; the problem without the jerk limit did not solve either (" + relaxed.message + ")";
    }
  }
  return Finish(first);
}

std::optional<TemporalResult> JerkLimitedSolve::SolveStructured() {
  // The structured path first (SolveStructuredScp); the general one below whenever it does not
  // answer.
  const Clock::time_point start = Clock::now();
  // The working memory of every banded solve below, kept for the next Solve.
  if (!solver_.workspace_) solver_.workspace_ = std::make_unique<internal::SolveWorkspace>();
  internal::SolveWorkspace& workspace = *solver_.workspace_;
  const internal::JerkTemplates& templates = workspace.templates;
  TemporalDiscretization d;
  try {
    d = internal::DiscretizeJerkLimitedTemplates(problem_, &workspace.templates);
  } catch (const std::exception&) {
    d = TemporalDiscretization();
  }
  if (d.controls && !d.infeasible_reason && d.num_vars > 0) BoundByPointVelocity(problem_, &d);
  build_time_ += SecondsSince(start);
  internal::BandedIpmSettings settings;
  settings.gap_tolerance = kStructuredGapShare * problem_.scp_tolerance;
  settings.max_iterations = solver_.structured_jerk_iterations();
  if (d.controls && !d.infeasible_reason && d.num_vars > 0) {
    std::vector<double> first = CoarseStart(d, settings, workspace);
    bool jerk_aware = !first.empty();
    if (!jerk_aware) first = JerkFreeStart(d);
    if (!first.empty()) {
      StructuredScp scp;
      bool answered =
          SolveStructuredScp(problem_, d, templates, std::move(first), settings, jerk_aware, &workspace, &scp);
      if (!answered && jerk_aware) {
        // From the coarse answer it did not answer: once more from the jerk-free guess, as
        // without the coarse start, before the general path.
        build_time_ += scp.build_seconds;
        solve_time_ += scp.solve_seconds;
        iterations_ += scp.iterations;
        scp = StructuredScp();
        jerk_aware = false;
        first = JerkFreeStart(d);
        answered = !first.empty() &&
                   SolveStructuredScp(problem_, d, templates, std::move(first), settings, false, &workspace, &scp);
      }
      build_time_ += scp.build_seconds;
      solve_time_ += scp.solve_seconds;
      iterations_ += scp.iterations;
      if (answered) {
        TemporalResult r;
        const Clock::time_point finishing = Clock::now();
        try {
          internal::FinishOptimalResult(problem_, d, scp.x, &r);
        } catch (const std::exception&) {
          r.status = TemporalStatus::kNumericalError;
        }
        build_time_ += SecondsSince(finishing);
        if (r.status == TemporalStatus::kOptimal) {
          r.message = "tolerances met (structured path)";
          r.method = "structured";
          r.rows = scp.rows;
          r.joints = d.joints;
          history_ = scp.history;
          return Finish(r);
        }
      }
    }
  }
  return std::nullopt;
}

std::vector<double> JerkLimitedSolve::CoarseStart(const TemporalDiscretization& d, const BandedIpmSettings& settings,
                                                  SolveWorkspace& workspace) {
  std::vector<double> b;
  const int coarse_cells = problem_.cells_per_piece / kCoarsening;
  if (coarse_cells < kMinCoarseCells) return b;
  TemporalProblem coarse = problem_;
  coarse.cells_per_piece = coarse_cells;
  // One solve, linearized at the jerk-free guess: a linearization point, not an answer.
  coarse.max_scp_iterations = 1;
  internal::JerkTemplates& coarse_templates = workspace.coarse_templates;
  TemporalDiscretization dc;
  try {
    dc = internal::DiscretizeJerkLimitedTemplates(coarse, &coarse_templates);
  } catch (const std::exception&) {
    return b;
  }
  if (!dc.controls || dc.infeasible_reason || dc.num_vars == 0) return b;
  BoundByPointVelocity(coarse, &dc);
  const std::vector<double> guess =
      JerkFreeGuess(dc, std::max(2, (coarse_cells + 1) / kGuessCoarsening), ConstraintMode::kCertified);
  if (guess.empty()) return b;
  StructuredScp scp;
  // Its answer is only a linearization point: loose tolerances (kCoarseTolerance).
  internal::BandedIpmSettings coarse_settings = settings;
  coarse_settings.tolerance = std::max(settings.tolerance, kCoarseTolerance);
  coarse_settings.gap_tolerance = std::max(settings.gap_tolerance, kCoarseTolerance);
  std::vector<double> coarse_first = GridValues(dc, guess);
  CapAtBrakingEnds(coarse, dc, &coarse_first);
  const bool answered = SolveStructuredScp(coarse, dc, coarse_templates, std::move(coarse_first), coarse_settings,
                                           false, &workspace, &scp, true);
  build_time_ += scp.build_seconds;
  solve_time_ += scp.solve_seconds;
  iterations_ += scp.iterations;
  if (!answered) return b;
  // b of the coarse profile at every half-grid value of d.
  std::optional<TemporalProfile> profile;
  try {
    profile = ProfileOf(dc, GridValues(dc, scp.x));
  } catch (const std::exception&) {
    return b;
  }
  const int K = problem_.cells_per_piece;
  b.assign(d.grid.size(), 0.0);
  for (int i = 0; i < d.num_pieces; ++i) {
    for (int j = 0; j <= 2 * K; ++j) {
      const double at = internal::HalfPointS(d, i, j);
      const GridValue& g = d.grid[static_cast<size_t>(d.GridIndex(i, j))];
      double value = g.fixed;
      if (g.var >= 0) {
        const double sdot = profile->AtS(i, std::clamp(at, 0.0, 1.0)).sdot;
        value = sdot * sdot;
      }
      b[static_cast<size_t>(d.GridIndex(i, j))] = value;
    }
  }
  internal::RestMiddlesToAlpha(d, &b);
  return b;
}

std::vector<double> JerkLimitedSolve::JerkFreeStart(const TemporalDiscretization& d) {
  // Under the paper's rows, a rougher guess of the same optimum. Measured on the default plan
  // (27 pieces, K = 20): the guess took 10 interior-point iterations over 735 rows, not 39
  // over 1,232 with the certified rows, and the first convex solve 21 iterations, not 17; the
  // temporal stage 33.5 ms, not 35.1 ms (medians of 11 interleaved runs), T the same to 2e-6
  // relative; the 100 m forest 148.7 ms, not 151.0 ms. The coarse programme above keeps the
  // certified guess (the paper's took 34 -> 41 / 37 -> 46 / 40 -> 42 iterations on the
  // benchmark's curves).
  const std::vector<double> guess =
      JerkFreeGuess(d, std::max(2, (problem_.cells_per_piece + 1) / kGuessCoarsening), ConstraintMode::kPaper);
  if (guess.empty()) return std::vector<double>();
  std::vector<double> b = GridValues(d, guess);
  CapAtBrakingEnds(problem_, d, &b);
  return b;
}

TemporalResult JerkLimitedSolve::SolveGeneral() {
  TemporalResult first;
  std::vector<double> linearization, x;
  if (!SolveConvex(JerkRows::kNone, nullptr, nullptr, &first, &linearization, &x)) {
    if (first.status == TemporalStatus::kInfeasible && first.message.rfind("no time", 0) == 0) {
      first.message =
          "no profile with continuous acceleration meets the limits and the boundary "
          "states (" +
          first.message + ")";
    }
    return Finish(first);
  }
  history_.push_back(first.total_time);
  // Braking ends linearized where the vehicle can be (CapAtBrakingEnds), as on the structured path.
  try {
    CapAtBrakingEnds(problem_, DiscretizeJerkLimited(problem_, JerkRows::kNone), &linearization);
  } catch (const std::invalid_argument&) {
  }

  bool have_best = false, converged_once = false;
  std::optional<TemporalResult> stopped;  // the failed solve that ended the programme early
  for (int n = 0; n < problem_.max_scp_iterations; ++n) {
    TemporalResult next;
    std::vector<double> next_b, next_x;
    if (!SolveConvex(JerkRows::kLinearized, &linearization, &x, &next, &next_b, &next_x)) {
      if (have_best) {
        best_.message = "stopped at convex solve " + std::to_string(history_.size() + 1) + ": " +
                        ToString(next.status) + ": " + next.message;
        stopped = next;
        break;
      }
      if (next.status == TemporalStatus::kInfeasible) {
        // The linearized jerk rows are conservative (an inner approximation), so their having no
        // solution at the jerk-free answer proves nothing about the problem: the property sweep
        // found such a case that Ipopt's exact rows solve (a polyline started at speed, K = 6).
        // Not a certificate, then, but a failure of the method, which the Ipopt fallback takes.
        next.status = TemporalStatus::kNumericalError;
        next.message =
            "the first convex approximation of the jerk rows (at the jerk-free answer) has no "
            "solution, which does not prove the problem infeasible (" +
            next.message + ")";
      }
      return Finish(next);
    }
    const double previous = history_.back();
    history_.push_back(next.total_time);
    const bool converged =
        have_best && std::abs(previous - next.total_time) <= problem_.scp_tolerance * next.total_time;
    if (!have_best || next.total_time < best_.total_time) {
      best_ = std::move(next);
      have_best = true;
    }
    linearization = std::move(next_b);
    x = std::move(next_x);
    if (converged) {
      converged_once = true;
      break;
    }
  }
  if (!converged_once) {
    // Stopped early (a convex solve failed) or out of iterations: the best profile is flyable but
    // is an optimum only if the programme had about settled. Its last step's change of T says so:
    // above kUnsettledShare (or with a single linearized solve, no step at all) it is not returned
    // as optimal (a 2 m line in pieces of 1 m, 1 mm and 1 m was "optimal" at 5 x its time).
    const size_t n = history_.size();
    const double change = n >= 3 ? std::abs(history_[n - 1] - history_[n - 2]) / history_[n - 1] : kInf;
    if (!(change <= kUnsettledShare)) {
      TemporalResult failed;
      failed.status = stopped ? TemporalStatus::kNumericalError : TemporalStatus::kIterationLimit;
      failed.joints = best_.joints;
      std::ostringstream m;
      m << "the sequential convex programme " << (stopped ? best_.message : "ran out of iterations")
        << " before it settled (T " << best_.total_time << " s, its last change "
        << (std::isfinite(change) ? std::to_string(100.0 * change) + "%" : std::string("unknown")) << ")";
      failed.message = m.str();
      return Finish(failed);
    }
    best_.reduced_accuracy = true;
  }
  return Finish(best_);
}

}  // namespace internal

TemporalResult TemporalSolver::SolveJerkLimited(const TemporalProblem& problem) {
  return internal::JerkLimitedSolve(*this, problem).Run();
}

}  // namespace timeopt
