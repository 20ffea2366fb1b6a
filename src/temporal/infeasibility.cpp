// Why a temporal problem is infeasible, and the closest boundary speeds that are not
// (infeasibility.h).
//
// The problem is discretized again with the boundary speeds free below the given ones
// (DiscretizeWithFreeBoundaries). Where its rows make a chain along the path, reachability
// (reachability.h) answers exactly on the grid:
// - no controllable profile even so: the limits themselves (a row that no speed meets);
// - the given start above its controllable set: above the limit at the start (boundary_speed), or
//   too fast to brake for a slower part ahead (braking; braking as hard as the rows allow from the
//   given start, the first grid point whose rows cannot be met names where: the stop, or the
//   slower part);
// - the given end above what the fastest profile from the (relaxed) start reaches: end_speed.
// The relaxed speeds are the controllable set's top at the start and the fastest profile's value
// at the end.

#include "infeasibility.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "discretization_internal.h"
#include "reachability.h"

namespace timeopt::internal {
namespace {

using Infeasibility = TemporalResult::Infeasibility;

// "s = 12.35 m along the curve (piece 2 at 0.46)" for free value v of d.
std::string Where(const TemporalProblem& problem, const TemporalDiscretization& d, int v) {
  int g = 0;
  while (g < static_cast<int>(d.grid.size()) && d.grid[static_cast<size_t>(g)].var != v) ++g;
  const int K = d.cells_per_piece;
  const int piece = g / (K + 1);
  const double s = static_cast<double>(g % (K + 1)) / K;
  // Arc length by Simpson's rule, 32 intervals per whole piece (|f'| is smooth).
  const auto length = [&](int i, double to) {
    constexpr int kIntervals = 32;
    const double h = to / kIntervals;
    double sum = 0.0;
    for (int j = 0; j <= kIntervals; ++j) {
      const double w = (j == 0 || j == kIntervals) ? 1.0 : (j % 2 == 1 ? 4.0 : 2.0);
      sum += w * problem.curve.Evaluate(i, j * h, 1).norm();
    }
    return sum * h / 3.0;
  };
  double along = 0.0;
  for (int i = 0; i < piece; ++i) along += length(i, 1.0);
  along += length(piece, s);
  std::ostringstream ss;
  ss << "s = " << along << " m along the curve (piece " << piece << " at " << s << ")";
  return ss.str();
}

// The cause from a presolve's or solver's message alone.
Infeasibility FromMessage(const std::string& message) {
  Infeasibility out;
  out.detail = message;
  const bool boundary = message.find("boundary.") != std::string::npos;
  const bool start = message.find("start") != std::string::npos;
  out.where = boundary ? (start ? "start" : "end") : "";
  if (boundary && message.find("acceleration") != std::string::npos) {
    out.cause = "boundary_acceleration";
  } else if (boundary || message.find("fixed speeds") != std::string::npos) {
    out.cause = "boundary_speed";
  } else {
    out.cause = "limits";
  }
  return out;
}

}  // namespace

Infeasibility DiagnoseInfeasible(const TemporalProblem& problem, const std::string& message,
                                 std::optional<RelaxedSpeeds>* relaxed) {
  relaxed->reset();
  if (problem.limits.max_acceleration_change) return FromMessage(message);
  if (problem.limits.max_jerk) {
    // The presolve's own certificates first (a boundary acceleration above a limit, one the jerk
    // limit cannot unwind, one across the path that the curvature does not give).
    if (message.find("boundary.") != std::string::npos) return FromMessage(message);
    // Without the jerk limit (and the boundary accelerations it needs) the problem only gets
    // easier: a cause found there (a start too fast for the limits or to brake in time, an end
    // speed out of reach) holds here too. Its speeds are not this problem's nearest ones, so no
    // relaxation is proposed from it (RelaxStartState finds those).
    TemporalProblem relaxation = problem;
    relaxation.limits.max_jerk.reset();
    relaxation.boundary.start_acceleration.setZero();
    relaxation.boundary.end_acceleration.setZero();
    relaxation.constraint_mode = ConstraintMode::kPaper;
    std::optional<RelaxedSpeeds> ignored;
    Infeasibility without = DiagnoseInfeasible(relaxation, message, &ignored);
    if (ignored && (without.cause == "boundary_speed" || without.cause == "braking" || without.cause == "end_speed")) {
      without.detail += " (already without the jerk limit, which only lowers these speeds)";
      return without;
    }
    return FromMessage(message);
  }
  FreeBoundaries free;
  TemporalDiscretization d;
  try {
    d = DiscretizeWithFreeBoundaries(problem, &free);
  } catch (const std::exception&) {
    return FromMessage(message);
  }
  if (d.infeasible_reason) return FromMessage(*d.infeasible_reason);  // whatever the boundary speeds
  ChainRows chain(0);
  if (d.num_vars == 0 || !ChainFromDiscretization(d, &chain)) return FromMessage(message);
  std::vector<double> lo, hi;
  const int empty = ControllableSets(chain, &lo, &hi);
  if (empty >= 0) {
    Infeasibility out{"limits", Where(problem, d, empty),
                      "no profile gets past this point whatever the boundary speeds (" + message + ")"};
    return out;
  }
  RelaxedSpeeds speeds;
  std::optional<Infeasibility> found;
  std::ostringstream detail;
  double start_x = hi[0];
  if (free.var[0] >= 0) {
    const int v = free.var[0];
    const double given = free.given_b[0] / free.scale[0];
    const double speed = problem.boundary.start_velocity.norm();
    if (given > hi[static_cast<size_t>(v)] * (1.0 + 1e-9)) {
      speeds.start_factor = std::sqrt(hi[static_cast<size_t>(v)] / given);
      start_x = hi[static_cast<size_t>(v)];
      if (given > chain.u[static_cast<size_t>(v)] * (1.0 + 1e-9)) {
        detail << "the start speed " << speed << " m/s is above the limit there ("
               << speed * std::sqrt(chain.u[static_cast<size_t>(v)] / given) << " m/s)";
        found = Infeasibility{"boundary_speed", "start", detail.str()};
      } else {
        const int fail = BrakingFailure(chain, given);
        detail << "from " << speed << " m/s the vehicle cannot brake in time for what lies ahead"
               << (fail >= 0 ? " (" + Where(problem, d, fail) + ")" : std::string())
               << "; the fastest start that can is " << speed * speeds.start_factor << " m/s";
        found = Infeasibility{"braking", fail >= 0 ? Where(problem, d, fail) : "start", detail.str()};
      }
    } else {
      start_x = given;
    }
  }
  if (free.var[1] >= 0) {
    const int v = free.var[1];
    const double given = free.given_b[1] / free.scale[1];
    const std::vector<double> fastest = GreedyForward(chain, lo, hi, start_x);
    const double reach = fastest[static_cast<size_t>(v)];
    if (given > reach * (1.0 + 1e-9)) {
      speeds.end_factor = std::sqrt(std::max(0.0, reach) / given);
      const double speed = problem.boundary.end_velocity.norm();
      if (!found) {
        std::ostringstream end_detail;
        end_detail << "the end speed " << speed << " m/s cannot be reached; the fastest end is "
                   << speed * speeds.end_factor << " m/s";
        found = Infeasibility{given > chain.u[static_cast<size_t>(v)] * (1.0 + 1e-9) ? "boundary_speed" : "end_speed",
                              "end", end_detail.str()};
      }
    }
  }
  if (!found) return FromMessage(message);  // on the grid the chain holds: a solver's borderline verdict
  *relaxed = speeds;
  return *found;
}

}  // namespace timeopt::internal
