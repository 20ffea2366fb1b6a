#pragma once
// Termination of the interior-point iteration (private to the conic module): the status decision
// (optimal, infeasibility certificates, stall, divergence, iteration and time limits, non-finite
// values), with the bookkeeping it needs across iterations (the best iterate by merit, the progress
// marks of the stall test, the lookback). The iteration itself moves the iterates; this class only
// says what to do.

#include <functional>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "timeopt/conic/solver.h"

namespace timeopt::conic::internal {

// Convergence measures of the iterate (x, y, z, s) / tau of the homogeneous embedding.
struct IterateMeasures {
  double pcost = 0.0;  // c'x / tau
  double dcost = 0.0;  // -(b'y + h'z) / tau
  double gap = 0.0;    // s'z / tau^2
  double pres = 0.0;   // relative primal residual
  double dres = 0.0;   // relative dual residual
  double mu = 0.0;     // (s'z + tau kappa) / (degree + 1)
  double tau = 1.0, kappa = 1.0;
  double cx = 0.0, by = 0.0, hz = 0.0;  // c'x, b'y, h'z (unscaled)
};

// The products of the iterate that the infeasibility certificates are measured with; the scratch
// vectors (sizes n and m) avoid allocation.
struct CertificateData {
  const Eigen::VectorXd& Aty;
  const Eigen::VectorXd& Gtz;
  const Eigen::VectorXd& Ax;
  const Eigen::VectorXd& Gx;
  const Eigen::VectorXd& s;
  Eigen::VectorXd& scratch_n;
  Eigen::VectorXd& scratch_m;
};

class Termination {
 public:
  enum class Action {
    kContinue,           // take a Newton step from the iterate
    kStop,               // stop with Decision::status and message (then see FallBackToBest)
    kLookback,           // measure the midpoint between the best iterate and this one (no step)
    kSwitchToAugmented,  // restore the best iterate and go on with the augmented KKT method
  };
  struct Decision {
    Action action = Action::kContinue;
    Status status = Status::kNotSolved;
    std::string message;
    bool save_best = false;  // the iterate is the best so far: save it (before acting)
  };

  explicit Termination(const SolverOptions& options) : options_(options) {}

  // The decision at `iteration` on the iterate measured by `it`, reached by a step of length `step`.
  // `reduced_method`: the reduced KKT method is in use (it may hand over to the augmented one).
  Decision Check(const IterateMeasures& it, int iteration, double step, bool reduced_method,
                 const CertificateData& data, const std::function<double()>& elapsed_seconds);

  // After a stop: a stall or limit (kNumericalError, kIterationLimit) falls back to the best iterate,
  // as kOptimal with *reduced_accuracy when it meets the reduced tolerances. Returns true if the
  // caller must restore the best iterate.
  bool FallBackToBest(Status* status, std::string* message, bool* reduced_accuracy) const;

 private:
  // Lookback, best iterate, progress, divergence and stall; false (with `decision` set) to stop there.
  // pd_gap = |pcost - dcost|, gap_scale = min(|pcost|, |dcost|).
  bool CheckMerit(const IterateMeasures& it, double pd_gap, double gap_scale, int iteration, double step,
                  bool reduced_method, Decision* decision);
  // Certificates of primal or dual infeasibility, once kappa > tau.
  static bool CheckInfeasibility(const IterateMeasures& it, const CertificateData& data, const SolverOptions& options,
                                 Decision* decision);

  const SolverOptions& options_;
  int best_iteration_ = -1;   // iteration of the best iterate
  bool looked_back_ = false;  // the current iterate is a lookback midpoint
  // Best iterate so far by the merit max(pres / tol, dres / tol, gap / gap tol): returned if the
  // iteration stalls, and accepted as kOptimal with reduced accuracy if it meets the reduced tolerances.
  double best_merit_ = std::numeric_limits<double>::infinity();
  double progress_merit_ = std::numeric_limits<double>::infinity();
  double progress_mu_ = std::numeric_limits<double>::infinity();
  int progress_iteration_ = 0;
  bool have_best_ = false;
  bool best_reduced_ok_ = false;
};

}  // namespace timeopt::conic::internal
