#pragma once

// Library-internal: the structured path of the SOCP backend. The temporal problem of
// discretization.h without equality rows is
//
//   minimize    J(x) = sum over cells [ w 2 ds / (sqrt(b0) + sqrt(b1)) + rho (b1 - b0)^2 / (4 ds) ]
//   subject to  G x <= h   (the linear rows, x >= 0 and x <= var_upper)
//
// with b = scale * x (or a fixed value) at each cell's two grid points: a convex objective over
// the free grid values and linear rows. Every cell and every row touches a few neighbouring values
// along the path, so the Newton system of a primal-dual interior-point method on this problem,
// grad^2 J + G' (Z / S) G, is banded (tridiagonal for the paper's and the certified rows), and one
// iteration is a few passes over the rows plus a banded Cholesky factorization in O(n). The SOCP
// (socp_backend.cpp) is the same problem with sqrt(b) and the cell times lifted into cones; this
// path solves it without the lift, from a reachability start (GreedyProfile in banded_ipm.cpp).
//
// An empty controllable set proves the problem infeasible when it stays empty with every row's
// bound loosened by 1e-6 relative (kInfeasible): far above the solvers' tolerances, so the conic
// solver would say so too, at several times the cost. A borderline one goes to the conic solver.
//
// Used only when it applies (every row over one value or two neighbouring ones: not lambda_a's
// rows, not the jerk-limited mode's equalities, no cone or cubic rows; no cell whose two values are
// both fixed at 0; a reachability profile exists) and trusted only when it ends optimal: anything
// else (the iteration limit, a factorization that breaks down, an infeasible problem, which it
// does not try to certify) is handed to the conic solver, which decides. So statuses never depend
// on this path.

#include <string>
#include <vector>

#include "timeopt/temporal/discretization.h"

namespace timeopt::internal {

struct BandedIpmSettings {
  // Relative primal and dual residual for optimal (the conic solver's feasibility tolerance).
  double tolerance = 1e-8;
  // s'z relative to J for optimal. J - J* <= s'z at a feasible, dual-feasible point (J is
  // convex), so this bounds the objective's error.
  double gap_tolerance = 1e-10;
  int max_iterations = 60;
  // The largest half-bandwidth of the Newton system it takes on.
  int max_bandwidth = 4;
};

struct BandedIpmOutcome {
  enum class Kind {
    kNotApplicable,  // the problem has equality rows, a wide band, or an infinite cell time
    kOptimal,        // x is the answer to the tolerances
    kGaveUp,         // the conic solver decides (message says why)
    kInfeasible,     // reachability proves it: no profile, even with every bound 1e-6 looser
  };
  Kind kind = Kind::kNotApplicable;
  int iterations = 0;
  std::string message;
  std::vector<double> x;  // d.num_vars values when optimal
};

BandedIpmOutcome SolveBanded(const TemporalDiscretization& d, const BandedIpmSettings& settings);

}  // namespace timeopt::internal
