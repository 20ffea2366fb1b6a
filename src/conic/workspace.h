#pragma once
// The reusable working memory of Solver (private to the conic module): the analyzed pattern, the
// internal problem, the cones with their scaling, the KKT system, the iterates and every work
// vector of the iteration, allocated once per sparsity pattern. The phases of one interior-point
// iteration (measure, Newton step: predictor, corrector, step to the boundary) are its methods, in
// workspace.cpp and newton_step.cpp; Solver::Solve (solver.cpp) runs the loop and asks Termination
// what to do.

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "cones.h"
#include "internal_problem.h"
#include "kkt_system.h"
#include "termination.h"
#include "timeopt/conic/solver.h"

namespace timeopt::conic {

struct Solver::Workspace {
  // ---------------- analysis (what must match for reuse) ----------------
  bool analyzed = false;
  int sparse_min_dim = 0;
  KktMethod method_option = KktMethod::kAutomatic;
  int reduced_max_expanded_cones = 0;
  int reduced_max_profile_per_row = 0;
  std::int64_t max_factor_bytes = 0;

  internal::InternalProblem data;
  internal::Cones cones;
  std::unique_ptr<internal::KktSystem> kkt;

  // ---------------- iterates and work vectors ----------------
  Eigen::VectorXd x, y, z, s;
  double tau = 1.0, kappa = 1.0;
  Eigen::VectorXd rx, ry, rz;              // residuals of the homogeneous embedding
  double rtau = 0.0;                       // its tau row: kappa + c'x + b'y + h'z
  Eigen::VectorXd Ax, Gx, Aty, Gtz;        // products
  Eigen::VectorXd rhs1, sol1, rhs2, sol2;  // unpermuted KKT vectors of size num_kkt
  // A direction (dx, dy, dz, ds), W^{-1} ds and W dz (ds_aff, dz_aff: after the predictor, its
  // direction, which the corrector's right-hand side uses), lambda \ d_s (ldiv) and W ldiv (dtmp2);
  // dtmp1 and dtmp3 hold the trial point s + a ds, z + a dz.
  Eigen::VectorXd dx, dy, dz, ds, ds_aff, dz_aff, dtmp1, dtmp2, dtmp3, ldiv;
  Eigen::VectorXd best_x, best_y, best_z, best_s;
  double best_tau = 1.0, best_kappa = 1.0;

  int refinement_counter = 0;     // refinement steps of this solve
  double refinement_floor = 0.0;  // refinement_mu_factor * mu of the current iteration
  int dynamic_regularizations = 0;
  int regularization_boosts = 0;

  // ---------------- analysis and data (workspace.cpp) ----------------
  bool PatternMatches(const Problem& problem, const Options& options) const;
  void Analyze(const Problem& problem, const Options& options);
  void LoadValues(const Problem& problem, const Options& options);
  // Leaves the reduced method for the augmented one in the middle of a solve (the data and the
  // regularization in use are reloaded); the next Solve() analyzes the pattern afresh.
  void SwitchToAugmented();
  bool reduced() const { return kkt->method() == KktMethod::kReducedBanded; }

  // ---------------- iterates (workspace.cpp) ----------------
  // The centered point of the embedding: x = 0, y = 0, s = z = e, tau = kappa = 1.
  void Initialize();
  // Residuals and products of the iterate, and its convergence measures.
  internal::IterateMeasures Measure(double norm_c, double norm_b, double norm_h);
  internal::CertificateData certificate_data() { return {Aty, Gtz, Ax, Gx, s, dx, dz}; }
  void SaveBest();
  // The iterate moves halfway back to the best one saved (the lookback: from a step taken at the
  // best iterate, the midpoint of that step).
  void MoveHalfwayToBest();
  void RestoreBest();
  // result's x, y, z, s in the user's coordinates: the iterate scaled by 1 / tau, or for a
  // certificate the normalized ray (see Status).
  void ExportSolution(Status status, Result* result) const;

  // ---------------- Newton step (newton_step.cpp) ----------------
  struct StepOutcome {
    double step = 0.0;    // step length taken
    double sigma = 0.0;   // centering parameter
    int refinements = 0;  // refinement steps of this iteration
    std::string failure;  // non-empty: no step was taken, and why
  };
  // One predictor-corrector step from the iterate measured by `it`.
  StepOutcome NewtonStep(const Options& options, const internal::IterateMeasures& it, int iteration);
  // Factorizes and solves K sol1 = [-c; b; h] and the predictor's system (raising the static
  // regularization if the factorization breaks down); returns the tau denominator.
  double FactorAndSolve(const Options& options);
  // Right-hand side rhs2 of a Newton direction for the residual weight eta_r and the complementarity
  // right-hand side d_s (see Cones::ComplementarityRhs).
  void DirectionRhs(bool corrector, double sigma_mu, double eta_r);
  // Completes the direction whose rhs2 is set and (if `solved`) solved into sol2: dx, dy, dz, ds,
  // W^{-1} ds and W dz (ds_aff, dz_aff); sets *dtau, *dkappa and returns the cones' step limit.
  double Direction(const Options& options, double denom, double eta_r, double d_kappa, int refinement_steps,
                   bool solved, double* dtau, double* dkappa);
  // The largest step keeping cones, tau and kappa non-negative, given the cones' limit.
  double MaxStep(double cone_step, double dtau, double dkappa) const;
  // Shortens *step until the trial point is strictly inside; false if none above min_step is.
  bool FindInteriorStep(const Options& options, double dtau, double dkappa, double* step);
};

}  // namespace timeopt::conic
