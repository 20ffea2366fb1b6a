#pragma once

// Solvers of the temporal problem: the paper's SOCP with our own conic solver, and the same
// problem as an Ipopt NLP for comparison. Both solve the same discretization of the problem
// (private to the library: src/temporal/discretization.h), so they agree up to their tolerances.
// Their statuses and results are in temporal_result.h; the SOCP itself, for other conic solvers,
// in temporal_socp.h.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/temporal/temporal_result.h"

namespace timeopt {
// The discretized problem and how it writes the jerk limit: private to the temporal module, they
// reach a backend through SolveDiscretized below.
struct TemporalDiscretization;
enum class JerkRows;
namespace internal {
struct SolveWorkspace;
class JerkLimitedSolve;
}  // namespace internal

// The one skeleton of both backends. Solve() (not virtual) validates and discretizes the problem,
// answers what presolve already decides (infeasible, or every grid value fixed), times the stages,
// hands the rest to the backend's SolveDiscretized and finishes an optimal answer the same way for
// both. So both backends answer every bad input alike: the same status and message.
class TemporalSolver {
 public:
  TemporalSolver();
  virtual ~TemporalSolver();
  TemporalSolver(const TemporalSolver&) = delete;
  TemporalSolver& operator=(const TemporalSolver&) = delete;
  // Never throws for bad problems: they come back as kInvalidInput with a message naming the
  // field. An unexpected error inside a backend comes back as kNumericalError. An infeasible
  // problem comes back with result.infeasibility, or relaxed (TemporalProblem::relax_boundary).
  //
  // A solver keeps the working memory of its last jerk-limited solve for the next one, whose pages
  // are then already mapped (a fresh page costs a fault: 10-20% of a solve): about 10 kB per
  // cell with the rows' templates, about 8 MB for the default plan (27 pieces of 20 cells). Give
  // each thread its own solver.
  TemporalResult Solve(const TemporalProblem& problem);
  virtual TemporalBackend backend() const = 0;

 protected:
  // Solves `d`, which has free values (d.num_vars > 0) and no presolve verdict. Sets status,
  // message, iterations, solve_time_seconds and reduced_accuracy, adds the backend's own assembly
  // time to build_time_seconds, and on kOptimal sets *x to the d.num_vars free values. May throw
  // std::invalid_argument for a problem the backend cannot represent (reported as kInvalidInput).
  virtual void SolveDiscretized(const TemporalDiscretization& d, TemporalResult* result, std::vector<double>* x) = 0;
  // How the backend takes the jerk limit (limits.max_jerk set): kLinearized, the sequential convex
  // programme (the SOCP backend); kExact, one solve with the non-convex cubic rows (Ipopt).
  virtual JerkRows jerk_rows() const;
  // CPU seconds for retrying a failed jerk-limited solve with the Ipopt backend's exact rows (0:
  // no retry).
  virtual double jerk_ipopt_fallback_seconds() const { return 0.0; }
  // The memory budget of that retry, bytes (0: none; SocpTemporalOptions::max_memory_bytes).
  virtual std::int64_t jerk_ipopt_fallback_memory() const { return 0; }
  // The iteration limit of each interior-point solve of the structured sequential convex programme
  // (banded solves over the control values), which a jerk-limited problem goes to first; 0: none
  // (the general path only). The SOCP backend with `structured`.
  virtual int structured_jerk_iterations() const { return 0; }

 private:
  friend class internal::JerkLimitedSolve;  // SolveJerkLimited's steps (jerk_solver.cpp)
  // limits.max_jerk set: the sequential convex programme over DiscretizeJerkLimited, or one solve
  // of its exact rows (jerk_solver.cpp).
  TemporalResult SolveJerkLimited(const TemporalProblem& problem);
  // Without a jerk limit: discretize and solve once.
  TemporalResult SolvePaperOrCertified(const TemporalProblem& problem);
  // TemporalProblem::relax_boundary where the rows make no chain (jerk-limited, lambda_a): the
  // nearest start state that can be flown, by bisection on its scale (see temporal_solver.cpp);
  // `failed` when none is found.
  TemporalResult RelaxStartState(const TemporalProblem& problem, TemporalResult failed);
  // Set while RelaxStartState probes scaled starts: a probe's numerical failure counts as
  // infeasible, so it skips the Ipopt fallback (a probe at the edge of feasibility took its 20 s).
  bool probing_start_ = false;

  std::unique_ptr<internal::SolveWorkspace> workspace_;  // made by the first jerk-limited solve
};

// Options of the SOCP backend.
struct SocpTemporalOptions {
  // Relative feasibility and gap tolerance of the interior-point solver. 1e-8 (the conic solver's
  // default) gives T to ~1e-10 relative on the reference curves; tighter values can end in a
  // numerical error when the last iterates cannot improve further. The jerk-limited mode's convex
  // solves take a relative gap of max(tolerance, 1e-7) (their rows still to `tolerance`): their
  // last digits of the gap cost a third of their iterations (m = 10, K = 50: 39 -> 26, T within
  // 1e-8 relative), and the sequential convex programme stops at 1e-4 anyway.
  double tolerance = 1e-8;
  // Interior-point iteration limit. 100 (the temporal problem needs 15-30).
  int max_iterations = 100;
  // Solve the problem first by the structured path where it applies (no equality rows, every row
  // over one grid value or two neighbouring ones: the paper's and the certified rows, with or
  // without rho; not lambda_a and not the jerk-limited mode): a primal-dual interior-point method
  // on the unlifted problem whose Newton systems are banded along the path, started from a
  // reachability profile (src/temporal/banded_ipm.h). It answers only when it meets the same
  // tolerances; anything else goes to the conic solver, which then decides (statuses never depend
  // on it). m = 10, K = 50, paper mode: 1.3 ms against 4.5 ms. false: always the conic solver.
  bool structured = true;
  // Jerk-limited mode: when the sequential convex programme ends in a numerical error or the
  // iteration limit, solve the exact jerk rows with the Ipopt backend instead, for at most this
  // many CPU seconds (0: never). An optimal answer is taken (result.solver then says "ipopt" and
  // the message why); anything else keeps the conic status, its message naming both. The conic
  // solves lose their accuracy on long pieces, where the jerk ramps are a small fraction of the
  // time (a single 300 m quintic at vmax 2: T ~ 117 s against ramps of 0.2 s); Ipopt solves those
  // in 0.4-0.9 s. 20 s ends a problem neither can solve with a status.
  double jerk_ipopt_fallback_seconds = 20.0;
  // A memory budget, bytes (0: none): the Ipopt fallback above is skipped, saying so in the
  // message, where TemporalPeakBytes puts Ipopt's exact rows above it (they take about 1 MB per
  // cell; a jerk-limited line at K = 20,000 reached 3.2 GB in the fallback).
  std::int64_t max_memory_bytes = 0;

  // False, with "<field>: expected <what>, got <value>" in *error, unless tolerance is positive
  // and finite, max_iterations >= 1, jerk_ipopt_fallback_seconds >= 0 and max_memory_bytes >= 0.
  bool IsValid(std::string* error) const;
  // Every field equal (a planner keeps its solver while its options are).
  bool operator==(const SocpTemporalOptions& other) const;
  bool operator!=(const SocpTemporalOptions& other) const { return !(*this == other); }
};

// Options of the Ipopt backend.
struct IpoptTemporalOptions {
  // Ipopt's `tol` (scaled NLP error). 1e-10 so that T agrees with the SOCP to ~1e-9 relative.
  double tolerance = 1e-10;
  // Ipopt's `max_iter`. 3000.
  int max_iterations = 3000;
  // Ipopt's `max_cpu_time`, seconds of CPU time for one solve (Debian's Ipopt 3.11 has no wall-time
  // limit); the solve then ends with kIterationLimit. 300 by default: Ipopt's restoration phase on
  // an infeasible jerk-limited problem with the exact rows ran for more than 10 minutes at
  // m = 3, K = 100 (the property sweep), while every solve of the tests, benchmarks and
  // experiments takes under 10 s. Infinite: Ipopt's own cap of 1e6 s.
  double max_solve_time_seconds = 300.0;

  // False, with "<field>: expected <what>, got <value>" in *error, unless tolerance is positive
  // and finite and max_iterations >= 0.
  bool IsValid(std::string* error) const;
};

// An upper estimate of the peak memory (bytes) of solving `problem` with `backend`, from its cells
// (pieces x K) and measured figures per cell: peaks of one process's solve over single pieces and
// 20-piece chains (2026-12-03), rounded up. Paper and certified rows: 10 KB per cell with the SOCP
// backend (measured 1.5-8.8 KB; 882 MB at K = 100,000 on one piece), 5 KB with Ipopt (4.4 KB);
// jerk-limited: 16 KB with the SOCP backend's sequential convex programme (11-14 KB), 1 MB with
// Ipopt's exact rows (0.5-0.9 MB at K = 500-2,000); plus 64 MiB for the process. A caller with a
// budget (the CLI's --max-memory) refuses a problem above it before solving.
std::int64_t TemporalPeakBytes(const TemporalProblem& problem, TemporalBackend backend);

// The factories throw std::invalid_argument with IsValid's message for invalid options.
std::unique_ptr<TemporalSolver> MakeSocpTemporalSolver(const SocpTemporalOptions& options = {});
std::unique_ptr<TemporalSolver> MakeIpoptTemporalSolver(const IpoptTemporalOptions& options = {});
std::unique_ptr<TemporalSolver> MakeTemporalSolver(TemporalBackend backend);

// Throws std::invalid_argument ("the problem's m x K cells need about N MiB with socp, above the
// memory budget of B MiB") when TemporalPeakBytes of `problem` with `backend` is above the budget
// (bytes; 0 or less: none). For callers with a budget, before they solve.
void CheckTemporalMemory(const TemporalProblem& problem, TemporalBackend backend, std::int64_t max_memory_bytes);
// A solver of `backend` whose socp fallback to Ipopt keeps to the memory budget (bytes; 0 or less:
// none); ipopt_seconds, when set, caps Ipopt's CPU time (the ipopt backend's, or the fallback's).
std::unique_ptr<TemporalSolver> MakeBudgetedTemporalSolver(TemporalBackend backend, std::int64_t max_memory_bytes,
                                                           std::optional<double> ipopt_seconds = std::nullopt);

}  // namespace timeopt
