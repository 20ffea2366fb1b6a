// The temporal stage's names and options: the statuses' and backends' names, the backends'
// option checks, the memory estimate and budget, and the factories by backend.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "timeopt/core/enum_strings.h"
#include "timeopt/core/option_check.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {

const char* ToString(TemporalStatus status) {
  switch (status) {
    case TemporalStatus::kOptimal:
      return "optimal";
    case TemporalStatus::kInfeasible:
      return "infeasible";
    case TemporalStatus::kIterationLimit:
      return "iteration_limit";
    case TemporalStatus::kNumericalError:
      return "numerical_error";
    case TemporalStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

bool FromString(const std::string& text, TemporalStatus* status) {
  return EnumFromString(text, kTemporalStatuses, status);
}

const char* ToString(TemporalBackend backend) {
  switch (backend) {
    case TemporalBackend::kSocp:
      return "socp";
    case TemporalBackend::kIpopt:
      return "ipopt";
  }
  return "unknown";
}

bool FromString(const std::string& text, TemporalBackend* backend) {
  return EnumFromString(text, kTemporalBackends, backend);
}

namespace {

// The checks both backends' options share: a positive finite tolerance and an iteration limit of
// at least `min_iterations`.
bool ValidSolverOptions(double tolerance, int max_iterations, int min_iterations, std::string* error) {
  if (!std::isfinite(tolerance) || !(tolerance > 0.0)) {
    return internal::FailOption(error, "tolerance", "a positive finite number", tolerance);
  }
  if (max_iterations < min_iterations) {
    return internal::FailOption(error, "max_iterations", "an integer >= " + std::to_string(min_iterations),
                                max_iterations);
  }
  return true;
}

}  // namespace

bool SocpTemporalOptions::operator==(const SocpTemporalOptions& o) const {
  // A field added to the struct mostly changes its size (32 bytes on 64-bit machines): compare it
  // here too.
  static_assert(sizeof(void*) != 8 || sizeof(SocpTemporalOptions) == 32,
                "SocpTemporalOptions has a new field: compare it in operator==");
  return tolerance == o.tolerance && max_iterations == o.max_iterations && structured == o.structured &&
         jerk_ipopt_fallback_seconds == o.jerk_ipopt_fallback_seconds && max_memory_bytes == o.max_memory_bytes;
}

bool SocpTemporalOptions::IsValid(std::string* error) const {
  if (!ValidSolverOptions(tolerance, max_iterations, 1, error)) return false;
  if (!(max_memory_bytes >= 0)) {
    if (error) *error = "max_memory_bytes: expected a number >= 0, got " + std::to_string(max_memory_bytes);
    return false;
  }
  if (!(jerk_ipopt_fallback_seconds >= 0.0)) {
    if (error) {
      *error =
          "jerk_ipopt_fallback_seconds: expected a number >= 0, got " + std::to_string(jerk_ipopt_fallback_seconds);
    }
    return false;
  }
  return true;
}

bool IpoptTemporalOptions::IsValid(std::string* error) const {
  if (!ValidSolverOptions(tolerance, max_iterations, 0, error)) return false;
  if (!(max_solve_time_seconds > 0.0)) {
    if (error)
      *error = "max_solve_time_seconds: expected a positive number, got " + std::to_string(max_solve_time_seconds);
    return false;
  }
  return true;
}

std::int64_t TemporalPeakBytes(const TemporalProblem& problem, TemporalBackend backend) {
  // Bytes, from the measured peaks per cell rounded up (see the declaration): the process, then per
  // cell with the SOCP backend (paper and certified rows / jerk-limited) and with Ipopt (likewise).
  constexpr double kProcessBytes = 64.0 * (1 << 20);
  constexpr double kSocpCellBytes = 10e3, kSocpJerkCellBytes = 16e3;
  constexpr double kIpoptCellBytes = 5e3, kIpoptJerkCellBytes = 1e6;
  const bool jerk = problem.limits.max_jerk.has_value();
  const double per_cell = backend == TemporalBackend::kSocp ? (jerk ? kSocpJerkCellBytes : kSocpCellBytes)
                                                            : (jerk ? kIpoptJerkCellBytes : kIpoptCellBytes);
  const double cells = static_cast<double>(problem.curve.num_pieces()) * std::max(problem.cells_per_piece, 0);
  const double bytes = kProcessBytes + cells * per_cell;
  return bytes < 9e18 ? static_cast<std::int64_t>(bytes) : std::numeric_limits<std::int64_t>::max();
}

std::unique_ptr<TemporalSolver> MakeTemporalSolver(TemporalBackend backend) {
  switch (backend) {
    case TemporalBackend::kSocp:
      return MakeSocpTemporalSolver();
    case TemporalBackend::kIpopt:
      return MakeIpoptTemporalSolver();
  }
  throw std::invalid_argument("MakeTemporalSolver: unknown backend");
}

void CheckTemporalMemory(const TemporalProblem& problem, TemporalBackend backend, std::int64_t max_memory_bytes) {
  const std::int64_t peak = TemporalPeakBytes(problem, backend);
  if (max_memory_bytes > 0 && peak > max_memory_bytes) {
    throw std::invalid_argument("the problem's " + std::to_string(problem.curve.num_pieces()) + " x " +
                                std::to_string(problem.cells_per_piece) + " cells need about " +
                                std::to_string(peak >> 20) + " MiB with " + ToString(backend) +
                                (problem.limits.max_jerk ? " and a jerk limit" : "") + ", above the memory budget of " +
                                std::to_string(max_memory_bytes >> 20) + " MiB");
  }
}

std::unique_ptr<TemporalSolver> MakeBudgetedTemporalSolver(TemporalBackend backend, std::int64_t max_memory_bytes,
                                                           std::optional<double> ipopt_seconds) {
  if (backend == TemporalBackend::kSocp) {
    SocpTemporalOptions options;
    if (max_memory_bytes > 0) options.max_memory_bytes = max_memory_bytes;
    if (ipopt_seconds) options.jerk_ipopt_fallback_seconds = *ipopt_seconds;
    return MakeSocpTemporalSolver(options);
  }
  IpoptTemporalOptions options;
  if (ipopt_seconds) options.max_solve_time_seconds = *ipopt_seconds;
  return MakeIpoptTemporalSolver(options);
}

}  // namespace timeopt
