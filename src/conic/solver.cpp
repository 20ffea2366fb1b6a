#include "timeopt/conic/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <utility>

#include "termination.h"
#include "workspace.h"

namespace timeopt::conic {

namespace {

// Objectives and residuals of result.x, y, z, s in the user's data (for certificates: of the
// normalized ray).
void MeasureResult(const Problem& problem, Result& result) {
  result.primal_objective = problem.c.dot(result.x);
  result.dual_objective = -problem.b.dot(result.y) - problem.h.dot(result.z);
  result.gap = result.s.dot(result.z);
  const Eigen::VectorXd Ax = problem.A * result.x;
  const Eigen::VectorXd Gx = problem.G * result.x;
  const Eigen::VectorXd Aty = problem.A.transpose() * result.y;
  const Eigen::VectorXd Gtz = problem.G.transpose() * result.z;
  auto ninf = [](const Eigen::VectorXd& v) { return v.size() ? v.lpNorm<Eigen::Infinity>() : 0.0; };
  if (result.status == Status::kPrimalInfeasible) {
    result.primal_residual = 0.0;
    result.dual_residual = ninf(Aty + Gtz);
  } else if (result.status == Status::kDualInfeasible) {
    result.primal_residual = std::max(ninf(Ax), ninf(Gx + result.s));
    result.dual_residual = 0.0;
  } else {
    result.primal_residual = std::max(ninf(Ax - problem.b), ninf(Gx + result.s - problem.h)) /
                             std::max({1.0, ninf(problem.b), ninf(problem.h), ninf(Ax), ninf(Gx), ninf(result.s)});
    result.dual_residual = ninf(problem.c + Aty + Gtz) / std::max({1.0, ninf(problem.c), ninf(Aty), ninf(Gtz)});
  }
}

}  // namespace

Solver::Solver(Options options) : options_(std::move(options)), workspace_(std::make_unique<Workspace>()) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
}

Solver::~Solver() = default;
Solver::Solver(Solver&&) noexcept = default;
Solver& Solver::operator=(Solver&&) noexcept = default;

void Solver::set_options(const Options& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
  options_ = options;
}

Result Solver::Solve(const Problem& problem) {
  using Clock = std::chrono::steady_clock;
  const auto start_time = Clock::now();
  const std::function<double()> elapsed = [&start_time] {
    return std::chrono::duration<double>(Clock::now() - start_time).count();
  };

  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("Solver::Options: " + error);
  problem.Validate();

  // ---- initialization ----
  if (!workspace_) workspace_ = std::make_unique<Workspace>();
  Workspace& W = *workspace_;
  Result result;
  result.reused_symbolic = W.PatternMatches(problem, options_);
  if (!result.reused_symbolic) W.Analyze(problem, options_);
  W.LoadValues(problem, options_);
  W.refinement_counter = 0;
  W.dynamic_regularizations = 0;
  W.regularization_boosts = 0;
  const double norm_c = internal::NormInf(W.data.c.data(), W.data.n);
  const double norm_b = internal::NormInf(W.data.b.data(), W.data.p);
  const double norm_h = internal::NormInf(W.data.h.data(), W.data.m);
  W.Initialize();

  // ---- iteration ----
  internal::Termination termination(options_);
  Status status = Status::kIterationLimit;
  std::string message;
  int iteration = 0;
  double step = 0.0, sigma = 0.0;
  int iteration_refinements = 0;
  for (;; ++iteration) {
    const internal::IterateMeasures it = W.Measure(norm_c, norm_b, norm_h);
    if (options_.callback) {
      IterationInfo info;
      info.iteration = iteration;
      info.primal_objective = it.pcost;
      info.dual_objective = it.dcost;
      info.gap = it.gap;
      info.primal_residual = it.pres;
      info.dual_residual = it.dres;
      info.tau = it.tau;
      info.kappa = it.kappa;
      info.mu = it.mu;
      info.step = step;
      info.sigma = sigma;
      info.refinement_steps = iteration_refinements;
      options_.callback(info);
    }
    const internal::Termination::Decision decision =
        termination.Check(it, iteration, step, W.reduced(), W.certificate_data(), elapsed);
    if (decision.save_best) W.SaveBest();
    using Action = internal::Termination::Action;
    if (decision.action == Action::kStop) {
      status = decision.status;
      message = decision.message;
      break;
    }
    if (decision.action == Action::kLookback) {
      step *= 0.5;
      W.MoveHalfwayToBest();
      --iteration;  // the midpoint is measured under the same iteration number
      continue;
    }
    if (decision.action == Action::kSwitchToAugmented) {
      try {
        W.SwitchToAugmented();
      } catch (const std::invalid_argument& e) {
        // The augmented factor is above max_factor_bytes: the banded one stalled and there is no
        // other to switch to.
        status = Status::kNumericalError;
        message = std::string("the banded KKT factor stalled, and the sparse one cannot replace it: ") + e.what();
        break;
      }
      W.RestoreBest();
      continue;
    }
    const Workspace::StepOutcome outcome = W.NewtonStep(options_, it, iteration);
    step = outcome.step;
    sigma = outcome.sigma;
    iteration_refinements = outcome.refinements;
    if (!outcome.failure.empty()) {
      status = Status::kNumericalError;
      message = outcome.failure;
      break;
    }
  }

  // ---- stalled or stopped: fall back to the best iterate ----
  bool reduced_accuracy = false;
  if (termination.FallBackToBest(&status, &message, &reduced_accuracy)) W.RestoreBest();

  // ---- output in the user's coordinates ----
  result.status = status;
  result.reduced_accuracy = reduced_accuracy;
  result.message = message;
  result.iterations = iteration;
  result.num_refinement_steps = W.refinement_counter;
  result.num_dynamic_regularizations = W.dynamic_regularizations;
  result.num_regularization_boosts = W.regularization_boosts;
  result.kkt_method = W.kkt->method();
  result.kkt_size = W.kkt->size();
  result.kkt_nonzeros = W.kkt->num_nonzeros();
  result.factor_nonzeros = W.kkt->num_factor_nonzeros();
  W.ExportSolution(status, &result);
  MeasureResult(problem, result);
  result.solve_time_seconds = elapsed();
  return result;
}

}  // namespace timeopt::conic
