#pragma once

// The conic solver's result as JSON (what `timeopt conic` prints).

#include <string>

#include "timeopt/conic/cbf.h"
#include "timeopt/conic/solver.h"

namespace timeopt {

// {"status", "message", "objective" (in the file's sense: MIN or MAX; null unless optimal),
//  "iterations", "solve_time_ms", "reduced_accuracy", "primal_residual", "dual_residual", "gap",
//  "kkt_method", "num_variables", "num_equalities", "num_cone_rows", "x"}. solve_time_ms is the
// result's own time unless `solve_time_seconds` (e.g. a median over repeats) is given (>= 0).
std::string ConicResultToJson(const conic::CbfModel& model, const conic::Result& result,
                              double solve_time_seconds = -1.0, int indent = 2);

}  // namespace timeopt
