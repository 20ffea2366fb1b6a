#pragma once

// Solvers of the temporal problem: the paper's SOCP with our own conic solver, and the same
// problem as an Ipopt NLP for comparison. Both solve the TemporalDiscretization built from the
// problem, so they agree up to their tolerances.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "timeopt/conic/problem.h"
#include "timeopt/temporal/discretization.h"
#include "timeopt/temporal/temporal_problem.h"
#include "timeopt/trajectory/temporal_profile.h"

namespace timeopt {

enum class TemporalStatus {
  kOptimal,         // profile, total_time and piece_durations are usable
  kInfeasible,      // no time allocation satisfies the limits; message says why when known
  kIterationLimit,  // the solver stopped first; nothing is usable
  kNumericalError,  // the solver failed numerically; nothing is usable
  kInvalidInput,    // the problem is malformed; message names the field
};

// "optimal", "infeasible", "iteration_limit", "numerical_error", "invalid_input".
// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<TemporalStatus, 5> kTemporalStatuses = {
    TemporalStatus::kOptimal,
    TemporalStatus::kInfeasible,
    TemporalStatus::kIterationLimit,
    TemporalStatus::kNumericalError,
    TemporalStatus::kInvalidInput,
};
const char* ToString(TemporalStatus status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, TemporalStatus* status);

enum class TemporalBackend { kSocp, kIpopt };

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<TemporalBackend, 2> kTemporalBackends = {
    TemporalBackend::kSocp,
    TemporalBackend::kIpopt,
};
const char* ToString(TemporalBackend backend);  // "socp", "ipopt"
// The enumerator named `text` (as ToString writes it) into *backend; false when none is.
bool FromString(const std::string& text, TemporalBackend* backend);

struct TemporalResult {
  TemporalStatus status = TemporalStatus::kNumericalError;
  std::string message;
  std::string solver;            // "socp" or "ipopt"
  double total_time = 0.0;       // T, seconds
  double objective = 0.0;        // J = T + rho sum a^2 ds
  std::vector<double> piece_durations;  // seconds
  int iterations = 0;
  double solve_time_seconds = 0.0;  // solver only (building excluded)
  double build_time_seconds = 0.0;  // discretization and problem assembly
  TemporalProfile profile;          // set when optimal
  std::vector<JointInfo> joints;    // joint types found (C1, G1 with ratio, stop)
  // Dense check of the exact trajectory (not only the grid): the largest |v_axis| / vmax_axis and
  // |acc_axis| / amax_axis over all axes and a fine sampling of every cell. Set when optimal.
  double max_velocity_ratio = 0.0;
  double max_acceleration_ratio = 0.0;

  // Optimal, but only to the backend's reduced tolerances (the conic solver's
  // reduced_feasibility_tolerance and reduced_gap_tolerance; Ipopt's acceptable level): rounding
  // stopped the solver short of its tolerances. `message` says why.
  bool reduced_accuracy = false;

  bool is_success() const { return status == TemporalStatus::kOptimal; }
};

// The one skeleton of both backends. Solve() (not virtual) validates and discretizes the problem,
// answers what presolve already decides (infeasible, or every grid value fixed), times the stages,
// hands the rest to the backend's SolveDiscretized and finishes an optimal answer the same way for
// both. So both backends answer every bad input alike: the same status and message.
class TemporalSolver {
 public:
  virtual ~TemporalSolver() = default;
  // Never throws for bad problems: they come back as kInvalidInput with a message naming the
  // field. An unexpected error inside a backend comes back as kNumericalError.
  TemporalResult Solve(const TemporalProblem& problem);
  virtual TemporalBackend backend() const = 0;

 protected:
  // Solves `d`, which has free values (d.num_vars > 0) and no presolve verdict. Sets status,
  // message, iterations, solve_time_seconds and reduced_accuracy, adds the backend's own assembly
  // time to build_time_seconds, and on kOptimal sets *x to the d.num_vars free values. May throw
  // std::invalid_argument for a problem the backend cannot represent (reported as kInvalidInput).
  virtual void SolveDiscretized(const TemporalDiscretization& d, TemporalResult* result,
                                std::vector<double>* x) = 0;
};

// Options of the SOCP backend.
struct SocpTemporalOptions {
  // Relative feasibility and gap tolerance of the interior-point solver. 1e-8 (the conic solver's
  // default) gives T to ~1e-10 relative on the reference curves; tighter values can end in a
  // numerical error when the last iterates cannot improve further.
  double tolerance = 1e-8;
  // Interior-point iteration limit. 100 (the temporal problem needs 15-30).
  int max_iterations = 100;

  // False, with "<field>: expected <what>, got <value>" in *error, unless tolerance is positive
  // and finite and max_iterations >= 1.
  bool IsValid(std::string* error) const;
};

// Options of the Ipopt backend.
struct IpoptTemporalOptions {
  // Ipopt's `tol` (scaled NLP error). 1e-10 so that T agrees with the SOCP to ~1e-9 relative.
  double tolerance = 1e-10;
  // Ipopt's `max_iter`. 3000.
  int max_iterations = 3000;

  // False, with "<field>: expected <what>, got <value>" in *error, unless tolerance is positive
  // and finite and max_iterations >= 0.
  bool IsValid(std::string* error) const;
};

// The factories throw std::invalid_argument with IsValid's message for invalid options.
std::unique_ptr<TemporalSolver> MakeSocpTemporalSolver(const SocpTemporalOptions& options = {});
std::unique_ptr<TemporalSolver> MakeIpoptTemporalSolver(const IpoptTemporalOptions& options = {});
std::unique_ptr<TemporalSolver> MakeTemporalSolver(TemporalBackend backend);

// The conic program the SOCP backend solves (see socp_backend.cpp for its variables and cones):
// variables x (the discretization's free values), then c, d and, when rho > 0, t; its optimal value
// is the objective J of the discretization. Exposed so that the same problem can be handed to another
// conic solver, e.g. written with conic::WriteCbf. Throws std::invalid_argument when there is no
// program to build: presolve already proved d infeasible, or every grid value is fixed.
conic::Problem BuildTemporalSocp(const TemporalDiscretization& d);

}  // namespace timeopt
