#pragma once
// The Newton (KKT) system of the interior-point iteration, behind one interface with one
// implementation per KktMethod (private to the conic module):
//     [ delta I   A'        G'            ] [dx]   [r1]
//     [ A        -delta I   0             ] [dy] = [r2]
//     [ G         0        -W'W - delta I ] [dz]   [r3]
// with W the Nesterov-Todd scaling of the current iterate (Cones). Vectors are unpermuted, of size
// InternalProblem::num_kkt (the entries after n + p + m belong to the expansion rows of large cones
// and are zero on the right-hand side). Every implementation refines on the unregularized system.
//
// - kkt_augmented.cpp: the full quasi-definite system, AMD-ordered, sparse LDL' (SparseLdl).
// - kkt_reduced.cpp: z eliminated, [G' W^{-2} G + delta I, A'; A, -delta I] plus a border per
//   expanded cone, ordered by reverse Cuthill-McKee, skyline LDL' (SkylineLdl).

#include <algorithm>
#include <cstdint>
#include <memory>

#include <Eigen/Core>

#include "cones.h"
#include "internal_problem.h"
#include "timeopt/conic/solver.h"

namespace timeopt::conic::internal {

// When iterative refinement stops (see the refinement fields of SolverOptions).
struct RefinementSettings {
  double tolerance = 0.0;   // SolverOptions::refinement_tolerance
  double floor = 0.0;       // refinement_mu_factor * mu of the current iteration
  double stagnation = 0.5;  // SolverOptions::refinement_stagnation
  int max_steps = 0;
};

class KktSystem {
 public:
  virtual ~KktSystem() = default;

  virtual KktMethod method() const = 0;
  // Copies the values of A and G (after InternalProblem::LoadValues) into the system.
  virtual void LoadData() = 0;
  // Sets the static regularization delta and the entries that depend on it (the scaled entries
  // follow at the next Factor).
  virtual void SetStaticRegularization(double delta) = 0;
  double static_regularization() const { return static_reg_; }
  // Loads the current scaling and factorizes; returns the number of dynamically regularized pivots.
  virtual int Factor(const SolverOptions& options) = 0;
  // sol = K^{-1} rhs with the factor, unrefined.
  virtual void Solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol) = 0;
  // Two unrefined solves in one sweep over the factor.
  virtual void Solve2(const Eigen::VectorXd& rhs_a, Eigen::VectorXd& sol_a, const Eigen::VectorXd& rhs_b,
                      Eigen::VectorXd& sol_b) = 0;
  // Iterative refinement of sol (an approximate solution of K sol = rhs) on the unregularized system;
  // returns the refinement steps taken.
  virtual int Refine(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, const RefinementSettings& settings) = 0;

  // For Result: dimension of the factorized matrix, its stored non-zeros (upper triangle) and those
  // of the factor L.
  virtual int size() const = 0;
  virtual long long num_nonzeros() const = 0;
  virtual long long num_factor_nonzeros() const = 0;

 protected:
  double static_reg_ = 0.0;
};

// The augmented system of `problem` (analyzed; values follow with LoadData).
// max_factor_bytes > 0: throws std::invalid_argument, before allocating the factor, when its
// non-zeros after fill-in need more (SolverOptions::max_factor_bytes).
std::unique_ptr<KktSystem> MakeAugmentedKkt(const InternalProblem& problem, const Cones& cones,
                                            std::int64_t max_factor_bytes);

// The reduced system of `problem`, or null where it is not defined (G has fewer rows than columns or
// an empty column) or, if `automatic`, does not pay off: more than options.reduced_max_expanded_cones
// expanded cones, or a profile of more than options.reduced_max_profile_per_row entries per row.
std::unique_ptr<KktSystem> MakeReducedKkt(const InternalProblem& problem, const Cones& cones, bool automatic,
                                          const SolverOptions& options);

// The refinement loop shared by both methods, on the first `len` entries: multiply(v, out) sets
// out = K v (unregularized), correct(r, out) sets out = K~^{-1} r (the factor). res and cand are
// work vectors. Adds the steps taken to *steps; returns true if sol changed.
template <typename Multiply, typename Correct>
bool RefineSolution(const Eigen::VectorXd& rhs, Eigen::VectorXd& sol, Eigen::VectorXd& res, Eigen::VectorXd& cand,
                    int len, const RefinementSettings& settings, Multiply multiply, Correct correct, int* steps) {
  const double bound = std::max(settings.tolerance, settings.floor) * (1.0 + NormInf(rhs.data(), len));
  multiply(sol, res);
  res.head(len) = rhs.head(len) - res.head(len);
  double norm = NormInf(res.data(), len);
  bool changed = false;
  for (int step = 0; step < settings.max_steps && norm > bound; ++step) {
    // Candidate sol + K~^{-1} r, accepted only if it reduces the residual of the exact system.
    correct(res, cand);
    cand.head(len) += sol.head(len);
    multiply(cand, res);
    res.head(len) = rhs.head(len) - res.head(len);
    const double new_norm = NormInf(res.data(), len);
    ++*steps;
    if (!(new_norm < norm)) break;  // no progress (or NaN): keep the previous solution
    sol.head(len) = cand.head(len);
    changed = true;
    if (new_norm > settings.stagnation * norm) break;  // slow: not worth another solve
    norm = new_norm;
  }
  return changed;
}

}  // namespace timeopt::conic::internal
