#pragma once

// Library-internal: reachability along the path (TOPP-RA's controllable sets, on our rows), for
// problems whose every row touches one free value or two neighbouring ones (the paper's and the
// certified rows, with or without rho). Used for the structured path's start (banded_ipm.cpp),
// for naming why a problem is infeasible and for the closest feasible boundary speeds
// (temporal_solver.cpp).

#include <vector>

#include "discretization.h"

namespace timeopt::internal {

// The rows as a chain over the free values x_0 .. x_{n-1}: bounds l_v <= x_v <= u_v and rows
// a x_v + b x_{v+1} <= h between neighbours.
struct ChainRows {
  struct Pair {
    double a = 0.0, b = 0.0, h = 0.0;
  };
  std::vector<double> l, u;
  std::vector<std::vector<Pair>> pairs;  // pairs[v]: the rows over (v, v + 1)

  explicit ChainRows(int n)
      : l(static_cast<size_t>(n), 0.0), u(static_cast<size_t>(n), kUnbounded), pairs(static_cast<size_t>(n)) {}
  int size() const { return static_cast<int>(l.size()); }
  // Adds c0 x_v0 + c1 x_v1 <= h (c1 = 0 and v1 = v0 for a bound); false unless |v1 - v0| <= 1.
  bool Add(int v0, double c0, int v1, double c1, double h);
  // A value with no upper bound of its own (a vanishing tangent) gets 1e3 times the largest one:
  // its neighbours' rows bound it anyway, and the polygons of the backward pass stay bounded.
  // False if some l_v > u_v.
  bool CapUnbounded();

  static constexpr double kUnbounded = 1.7976931348623157e308;
};

// The chain of a discretization: x >= 0, x <= var_upper and its linear rows. False (not a chain)
// with equality, cubic or cone rows, or a row over values that are not neighbours.
bool ChainFromDiscretization(const TemporalDiscretization& d, ChainRows* chain);

// Backward: K_v = [lo_v, hi_v], the values of x_v from which the rest of the path stays feasible.
// Returns -1, or the value v (the largest) whose set came out empty.
int ControllableSets(const ChainRows& c, std::vector<double>* lo, std::vector<double>* hi);

// Forward from x_0 = `start` (in K_0): the largest x_v in K_v that the rows with x_{v-1} allow
// (the time-optimal profile of this chain, pointwise largest).
std::vector<double> GreedyForward(const ChainRows& c, const std::vector<double>& lo, const std::vector<double>& hi,
                                  double start);

// Forward from x_0 = `start` braking as hard as the rows allow (the smallest x_v they allow after
// x_{v-1}): the first v where even that is above what the rows allow there (its own bound, or the
// rows with x_{v-1}): where braking fails (a stop, a slower part), or -1.
int BrakingFailure(const ChainRows& c, double start);

}  // namespace timeopt::internal
