#pragma once

// Library-internal: the temporal skeleton's finishing step, shared by the one-solve path
// (temporal_solver.cpp) and the jerk-limited sequential convex programme (jerk_solver.cpp).

#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "discretization.h"
#include "timeopt/temporal/temporal_result.h"

namespace timeopt::internal {

// In a backend's message of an infeasible verdict that is only local (Ipopt on the exact jerk
// rows, which are not convex): the jerk-limited solve then asks the convex problem without them.
inline constexpr const char* kLocalVerdict = "this is a local verdict";

// Fills total_time, objective, piece_durations, profile and the dense feasibility ratios (with a
// jerk limit, max_jerk_ratio too) of an optimal result from the discretization's free values x.
// May throw std::invalid_argument when the values make no profile.
void FinishOptimalResult(const TemporalProblem& problem, const TemporalDiscretization& d, const std::vector<double>& x,
                         TemporalResult* result);

// Runs body(&finishing), a solve on one discretization, and maps what it throws to a status the one
// way every temporal solve does: std::invalid_argument is the input's fault (kInvalidInput, its
// message) until the body sets finishing (then a solution that makes no profile, e.g. a cell at
// zero speed at both ends: kNumericalError); anything else is a numerical error naming the backend
// (Ipopt's own exceptions do not derive from std::exception). Returns body's value, or false when
// it threw.
template <typename Body>
bool MapSolveExceptions(const std::string& backend, TemporalResult* result, Body&& body) {
  bool finishing = false;
  try {
    return body(&finishing);
  } catch (const std::invalid_argument& e) {
    result->status = finishing ? TemporalStatus::kNumericalError : TemporalStatus::kInvalidInput;
    result->message =
        finishing ? backend + " backend: the solution makes no profile: " + e.what() : std::string(e.what());
  } catch (const std::exception& e) {
    result->status = TemporalStatus::kNumericalError;
    result->message = backend + " backend: unexpected error: " + e.what();
  } catch (...) {
    result->status = TemporalStatus::kNumericalError;
    result->message = backend + " backend: unexpected error";
  }
  return false;
}

}  // namespace timeopt::internal
