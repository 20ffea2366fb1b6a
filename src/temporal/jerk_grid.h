// Where the cells of the jerk-limited grid go (jerk_grid.cpp): each piece's rest cells, sized to
// the jerk-saturated ramp from rest, the first cell of a braking start, and the graded cells after
// them, for DiscretizeJerkLimited (jerk_discretization.cpp).

#pragma once

#include <vector>

#include "timeopt/temporal/temporal_problem.h"

namespace timeopt::internal {

// The first cell at one end of a piece (RestCellSize, BrakeCellSize).
struct RestSize {
  double cell = 0.0;  // the rest cell's length in s (0: none)
  bool halved = false;
  bool curved = false;   // a constant s-jerk over the cell keeps less than kCurvedRestShare somewhere
  bool braking = false;  // not a rest cell: the first cell of a braking start (BrakeCellSize)
  double ramp = 0.0;     // the ramp from rest before halving (RampLength), in s
};
// The rest cell at the start (end = false) or end of piece i (see jerk_grid.cpp).
RestSize RestCellSize(const TemporalProblem& p, int piece, bool end, bool rest_to_rest);
// The first cell of a braking start at the start or end of piece i, or none (see jerk_grid.cpp).
RestSize BrakeCellSize(const TemporalProblem& p, int piece, bool end, int K);
// The K + 1 cell edges of a piece in s, from 0 to 1: rest_start and rest_end first and last, each
// followed by cells graded back to the nominal size, the rest uniform.
// ramp_cells (optional): how many cells after the rest cell at the start and before the one at the
// end are ramp cells (CellShape::kRampStart / kRampEnd), uniform in w = s^(1/3) from the rest point
// with the rest cell (see jerk_grid.cpp); ramp_degree_fits: whether the piece's degree allows them.
std::vector<double> CellEdges(int K, const RestSize& rest_start, const RestSize& rest_end,
                              int (*ramp_cells)[2] = nullptr, bool ramp_degree_fits = false);

}  // namespace timeopt::internal
