// The jerk-limited programme on the structured path (structured_scp.cpp), for the jerk-limited
// solve (jerk_solver.cpp): the sequential convex programme over a discretization's control values
// with banded interior-point solves, and what both files share (the working sets' fractions, the
// grid values and profile of an answer).

#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "banded_ipm.h"
#include "discretization_internal.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt::internal {

using SteadyClock = std::chrono::steady_clock;
inline double SecondsSince(SteadyClock::time_point from) {
  return std::chrono::duration<double>(SteadyClock::now() - from).count();
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
inline constexpr double kWorkingSetFraction = 0.7;
inline constexpr double kUnsettledFraction = 0.3;
inline constexpr double kGuessFraction = 0.5;
inline constexpr int kMaxWorkingSetRounds = 3;
inline constexpr double kWorkingSetSettled = 0.01;

// b at every grid value of d for its free values x (never below 0).
std::vector<double> GridValues(const TemporalDiscretization& d, const std::vector<double>& x);
// The profile of b at every half-grid value of the jerk-limited d (std::invalid_argument for
// values that make none).
TemporalProfile ProfileOf(const TemporalDiscretization& d, std::vector<double> b);

// The sequential convex programme on the structured path (banded_ipm.h), over d's control values:
// d (from DiscretizeJerkLimitedTemplates) and the velocity and acceleration templates become a
// BandedProblem once; each convex solve adds the jerk rows linearized at the previous answer (from
// `templates`, no new discretization) and starts from that answer and its multipliers. The first
// linearization is `linearization` (b at every half-grid value: the jerk-free certified optimum).
// Each solve gets a working set (see the loop); an answer that violates a row left out is solved
// again with it. False, with the reason in *why, when a solve does not end optimal: the general
// path then decides, so statuses never depend on this one. thin_jerk: a programme whose answer is
// only a linearization point (the coarse one) leaves out the jerk rows marked `thin`, so it bounds
// the jerk at every other Bernstein coefficient (m = 10, K = 50: its solve over 3,800 rows instead
// of 4,750, in as many iterations, and the fine solve unchanged).
struct StructuredScp {
  double build_seconds = 0.0, solve_seconds = 0.0;
  int iterations = 0, rows = 0;
  std::vector<double> history;
  std::vector<double> x;  // the best answer's free values
  std::string why;
};

bool SolveStructuredScp(const TemporalProblem& problem, const TemporalDiscretization& d,
                        const internal::JerkTemplates& templates, std::vector<double> linearization,
                        const internal::BandedIpmSettings& settings, bool jerk_aware,
                        internal::SolveWorkspace* workspace, StructuredScp* out, bool thin_jerk = false);

}  // namespace timeopt::internal
