#pragma once
// Primal-dual interior-point solver for linear, second-order and rotated second-order cone programs
// (problem form in problem.h).
//
// Method (after the designs documented for ECOS, Domahidi, Chu and Boyd, ECC 2013, and Clarabel,
// Goulart and Chen, 2024): the homogeneous self-dual embedding in (x, y, z, s, tau, kappa), so that
// infeasible and unbounded problems end with certificates; Nesterov-Todd scaling for the orthant and
// second-order cones; Mehrotra predictor-corrector with the second-order correction; one sparse
// quasi-definite KKT system per iteration
//     [ delta I   A'        G'            ] [dx]
//     [ A        -delta I   0             ] [dy]
//     [ G         0        -W'W - delta I ] [dz]
// factorized by a signed LDL' with a fill-reducing (AMD) ordering and a symbolic analysis computed
// once per sparsity pattern, static and dynamic regularization and iterative refinement on the
// unregularized system. Large second-order cones enter the KKT system by the sparse expansion of
// their scaling W'W = eta^2 (D + u u' - v v') (two extra rows per cone), so no dense block appears.
// Rotated cones are mapped to standard ones by the orthogonal transform of their first two rows.
// Step lengths are the exact distance to the cone boundary, computed in the scaled space of
// lambda = W z (for a cone, the hyperbolic rotation that maps lambda to e turns the limit into
// 1 / (||rho1|| - rho0)), times step_fraction. The iteration starts from the centered point
// x = 0, y = 0, s = z = e, tau = kappa = 1. Stopping: relative primal and dual residuals and the gap
// (absolute or relative) below their tolerances; infeasibility from the
// normalized rays once kappa > tau. If the iteration stalls (see SolverOptions::stall_iterations),
// the best iterate is returned, as kOptimal with Result::reduced_accuracy when it meets the reduced
// tolerances.
//
// A Solver is a reusable workspace: a second Solve() on a problem with the same sparsity pattern
// (same A and G patterns, same cones) reuses the ordering, the symbolic factorization and all memory
// (only the returned Result is allocated).
//
// Cost per iteration: one numeric LDL' factorization, one two-right-hand-side sweep over the factor
// (the constant system K sol1 = [-c; b; h] and the predictor, both unrefined), one solve for the
// corrector, and iterative refinement of the combined corrector direction only (to max(1e-12,
// refinement_mu_factor mu): 0-2 steps, each a solve and a KKT product); the factor is about as large
// as the KKT matrix on path-like (banded) problems; about 0.3 ms per iteration for the temporal
// problem with 1,003 variables and 4,002 cone rows on the development machine (see
// benchmarks/conic_benchmark.cpp for measured tables).
//
// Known limitation: the explicit scaling W'W of small cones and the expansion of large ones lose
// accuracy as the iterates approach the optimum (condition number ~ w0^4); on large or degenerate
// problems the last step to the 1e-8 tolerances can fail and the result is kOptimal with
// reduced_accuracy (typically gap ~1e-7 relative).

#include <array>
#include <functional>
#include <limits>
#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "timeopt/conic/problem.h"

namespace timeopt::conic {

/// Termination status of Solver::Solve.
enum class Status {
  /// The tolerances of Options were met: x, y, z, s are an approximately optimal primal-dual pair.
  /// x is usable. If the iteration stalled just short of them (rounding limits on badly conditioned
  /// problems), the best iterate met the reduced tolerances instead and Result::reduced_accuracy is set.
  kOptimal,
  /// The problem has no feasible x. y and z hold a certificate normalized so that b'y + h'z = -1,
  /// with A'y + G'z = 0 (to infeasibility_tolerance) and z in K. x and s are zero and not usable.
  kPrimalInfeasible,
  /// The problem is unbounded below (its dual is infeasible). x and s hold a certificate normalized so
  /// that c'x = -1, with A x = 0 and G x + s = 0 (to infeasibility_tolerance) and s in K: an improving
  /// ray. y and z are zero. x is a direction, not a solution.
  kDualInfeasible,
  /// max_iterations (or the time limit) was reached first. x, y, z, s are the best iterate scaled by
  /// 1/tau; they satisfy the cone constraints but not necessarily the tolerances (see the residuals).
  kIterationLimit,
  /// The iteration could not make progress (stalled, tiny steps, failed factorization or non-finite
  /// values) and the best iterate does not meet the reduced tolerances. x, y, z, s are the best iterate
  /// scaled by 1/tau; use them only after checking the residuals.
  kNumericalError,
  /// Solve() has not run. Nothing is usable.
  kNotSolved,
};

/// Short lowercase name of a status, e.g. "optimal", "primal_infeasible".
// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<Status, 6> kStatuses = {Status::kOptimal,        Status::kPrimalInfeasible,
                                                    Status::kDualInfeasible, Status::kIterationLimit,
                                                    Status::kNumericalError, Status::kNotSolved};
const char* ToString(Status status);
// The enumerator named `text` (as ToString writes it) into *status; false when none is.
bool FromString(const std::string& text, Status* status);

/// How the Newton (KKT) system of every iteration is solved.
enum class KktMethod {
  /// kReducedBanded when it is safe and pays off: G has at least as many rows as columns and no empty
  /// column (else G' W^{-2} G is singular), at most SolverOptions::reduced_max_expanded_cones (8)
  /// cones are expanded, and the reduced system is narrow (its variable-band profile, after a reverse
  /// Cuthill-McKee ordering, stores at most SolverOptions::reduced_max_profile_per_row (16) entries
  /// per row on average, border rows excluded). Otherwise kAugmentedSparse.
  kAutomatic,
  /// The full quasi-definite system in (x, y, z), AMD-ordered, sparse LDL'. Works for every sparsity.
  kAugmentedSparse,
  /// z eliminated through the cone scaling: the system in (x, y) with G' W^{-2} G, ordered to a small
  /// bandwidth (reverse Cuthill-McKee) and factorized by a skyline LDL' on contiguous memory; large
  /// cones enter as two border rows each. Faster on path-like problems (trajectory time allocation);
  /// iterative refinement still runs on the full unreduced system. Defined only when G has at least
  /// as many rows as columns and no empty column; otherwise kAugmentedSparse is used (see
  /// Result::kkt_method).
  kReducedBanded,
};

inline constexpr std::array<KktMethod, 3> kKktMethods = {KktMethod::kAutomatic, KktMethod::kAugmentedSparse,
                                                         KktMethod::kReducedBanded};
const char* ToString(KktMethod method);
// The enumerator named `text` (as ToString writes it) into *method; false when none is.
bool FromString(const std::string& text, KktMethod* method);

/// Progress of one interior-point iteration, given to Options::callback.
struct IterationInfo {
  /// 0 for the initial point, then 1, 2, ... Near the optimum the midpoint of a step that missed the
  /// tolerances is measured once (no KKT solve) and reported with the same number again.
  int iteration = 0;
  double primal_objective = 0.0;  ///< c'x / tau.
  double dual_objective = 0.0;    ///< -(b'y + h'z) / tau.
  double gap = 0.0;               ///< s'z / tau^2 (absolute complementarity gap).
  double primal_residual = 0.0;   ///< Relative primal residual (see Result).
  double dual_residual = 0.0;     ///< Relative dual residual (see Result).
  double tau = 0.0;               ///< Homogeneous variable tau (tends to 0 for infeasible problems).
  double kappa = 0.0;             ///< Homogeneous variable kappa (tends to 0 for solvable problems).
  double mu = 0.0;                ///< Complementarity measure (s'z + tau kappa) / (degree + 1).
  double step = 0.0;              ///< Step length taken in this iteration (0 for the initial point).
  double sigma = 0.0;             ///< Centering parameter of this iteration.
  int refinement_steps = 0;       ///< Iterative refinement steps used in this iteration.
};

/// Outcome of Solver::Solve. For the meaning of x, y, z, s under each status see Status.
struct Result {
  Status status = Status::kNotSolved;
  std::string message;            ///< Human readable reason for the status.
  Eigen::VectorXd x;              ///< Primal variables, size n.
  Eigen::VectorXd y;              ///< Duals of A x = b, size p (sign: c + A'y + G'z = 0).
  Eigen::VectorXd z;              ///< Duals of G x + s = h, size m, in K.
  Eigen::VectorXd s;              ///< Slacks h - G x, size m, in K.
  double primal_objective = 0.0;  ///< c'x.
  double dual_objective = 0.0;    ///< -b'y - h'z.
  double gap = 0.0;               ///< Absolute complementarity gap s'z.
  /// max(||Ax-b||_inf, ||Gx+s-h||_inf) / max(1, ||b||_inf, ||h||_inf, ||Ax||_inf, ||Gx||_inf, ||s||_inf).
  /// The stopping test measures it in the solver's internal coordinates, where the first two rows of
  /// each rotated cone are turned by 45 degrees, so here it can exceed the tolerance by up to sqrt(2).
  double primal_residual = 0.0;
  /// ||c + A'y + G'z||_inf / max(1, ||c||_inf, ||A'y||_inf, ||G'z||_inf).
  double dual_residual = 0.0;
  int iterations = 0;                   ///< Interior-point iterations performed.
  double solve_time_seconds = 0.0;      ///< Wall time of Solve(), including analysis.
  int num_refinement_steps = 0;         ///< Iterative refinement steps over all iterations.
  int num_dynamic_regularizations = 0;  ///< Pivots replaced by dynamic regularization.
  /// Times the static regularization was raised (by SolverOptions::regularization_boost_factor) after
  /// a factorization broke down (the direction came out non-finite); at most
  /// SolverOptions::max_regularization_boosts per solve.
  int num_regularization_boosts = 0;
  bool reused_symbolic = false;  ///< True if the ordering and symbolic analysis were reused.
  /// True if kOptimal was reached only with the reduced tolerances of SolverOptions (the iteration
  /// stalled near the optimum); residuals and gap tell the accuracy actually reached.
  bool reduced_accuracy = false;
  /// Dimension of the factorized system: n + p + m + 2 per expanded cone (kAugmentedSparse) or
  /// n + p + 2 per expanded cone (kReducedBanded).
  int kkt_size = 0;
  long long kkt_nonzeros = 0;  ///< Stored non-zeros of the factorized matrix's upper triangle.
  /// Non-zeros of the LDL' factor L (strictly lower part; for kReducedBanded its stored profile).
  long long factor_nonzeros = 0;
  /// The method used at the end (never kAutomatic after Solve()). The reduced method hands over to
  /// the augmented one, from the best iterate, if a direction near the optimum comes out spoiled by
  /// the rounding of G'W^{-2}G (the merit jumps by SolverOptions::divergence_merit_factor).
  KktMethod kkt_method = KktMethod::kAutomatic;

  /// True iff status == kOptimal.
  bool is_success() const { return status == Status::kOptimal; }
  /// One line: status, objective, residuals, iterations, time.
  std::string BriefReport() const;
};

/// Settings of Solver (also reachable as Solver::Options).
struct SolverOptions {
  /// Relative primal and dual residual tolerance for kOptimal (dimensionless, see Result). 1e-8.
  double feasibility_tolerance = 1e-8;
  /// Absolute tolerance on the gap s'z for kOptimal (objective units). 1e-8.
  double absolute_gap_tolerance = 1e-8;
  /// Relative tolerance on the gap, s'z / min(|primal objective|, |dual objective|), for kOptimal.
  /// Either gap tolerance suffices. 1e-8.
  double relative_gap_tolerance = 1e-8;
  /// Tolerance of the infeasibility certificates: residual of the normalized ray. 1e-8.
  double infeasibility_tolerance = 1e-8;
  /// Reduced tolerances: if the iteration stalls (no halving of the merit, see stall_iterations, a
  /// step below min_step or the iteration limit), the best iterate is returned as kOptimal with
  /// Result::reduced_accuracy = true when its relative residuals are <= reduced_feasibility_tolerance
  /// and its gap <= reduced_gap_tolerance (absolute, or relative to the objective). 1e-6 and 1e-5:
  /// the last digits of a badly conditioned problem are lost to rounding, not to the method. Values
  /// below the strict tolerances act as the strict ones; set both to 0 to disable the fallback.
  double reduced_feasibility_tolerance = 1e-6;
  double reduced_gap_tolerance = 1e-5;
  /// Iterations without halving either the merit max(pres / tol, dres / tol, gap / gap tol) or the
  /// complementarity mu after which the iteration is declared stalled, when the best iterate already
  /// meets the reduced tolerances; otherwise slow_phase_stall_factor times as many. 5: near the
  /// optimum a healthy iteration halves both at every step.
  int stall_iterations = 5;
  /// Factor (>= 1) on stall_iterations while the best iterate does not yet meet the reduced
  /// tolerances: far from the optimum slow phases of a few iterations are normal (infeasible problems
  /// until a certificate appears, long path problems in their first iterations). 4 (20 iterations).
  int slow_phase_stall_factor = 4;
  /// Lookback: a full step from the best iterate that neither ends the solve nor improves the merit
  /// may have traded one criterion for another (the gap met, the primal residual spoiled by rounding
  /// in the last solves); the midpoint of that step often meets all of them and is measured once (no
  /// KKT solve; the callback sees the iteration number again). Only when the best merit (see
  /// stall_iterations; 1 = the tolerances met) is at most lookback_merit (>= 0, dimensionless): 10,
  /// i.e. within 10x of the tolerances, where rounding rather than the method limits the step...
  double lookback_merit = 10.0;
  /// ... and the step was longer than lookback_min_step (in [0, 1]): a shorter step moved the iterate
  /// too little to have traded criteria, and its midpoint is nearly the best iterate again. 0.2.
  double lookback_min_step = 0.2;
  /// Once the best iterate meets the reduced tolerances, a merit above divergence_merit_factor (> 1)
  /// times the best one is rounding taking over, not a phase that recovers: the solve stops with the
  /// best iterate (the reduced method first hands over to the augmented one, see Result::kkt_method).
  /// 1e3: the breakdowns seen rose ~1e4-fold at once.
  double divergence_merit_factor = 1e3;
  /// Maximum interior-point iterations. 100 (a healthy problem needs 10-40).
  int max_iterations = 100;
  /// Wall-time limit of one Solve(), seconds. Infinite by default.
  double max_solve_time_seconds = std::numeric_limits<double>::infinity();
  /// Fraction of the step to the cone boundary that is taken, in (0, 1). 0.99 keeps iterates
  /// strictly interior without slowing convergence.
  double step_fraction = 0.99;
  /// Smallest step length (in (0, 1)) below which the iteration is declared stuck. 1e-10.
  double min_step = 1e-10;
  /// The exact step keeps the iterate inside the cones, but rounding can put a nearly active cone on
  /// its boundary; the step is then halved until the trial point is strictly interior, trying at most
  /// max_step_trials (>= 1) points (and none below min_step). 40: 2^-40 ~ 1e-12 is below the default
  /// min_step anyway.
  int max_step_trials = 40;
  /// Static regularization delta added with the sign of each KKT diagonal block (dimensionless).
  /// 1e-8 makes the KKT matrix quasi-definite even with redundant equalities; iterative refinement
  /// removes its effect on the solution.
  double static_regularization = 1e-8;
  /// When a factorization breaks down (the direction comes out non-finite; near the optimum the
  /// scaling spans ~20 orders of magnitude and the LDL' of a large system can meet pivots of the
  /// wrong sign, then overflow), the static regularization is multiplied by
  /// regularization_boost_factor (> 1) for the rest of the solve and the factorization redone, at
  /// most max_regularization_boosts (>= 0) times per solve; refinement on the unregularized system
  /// recovers the accuracy. 100 and 3: each attempt changes the pivots decisively, and a breakdown
  /// that regularization does not cure costs at most three extra factorizations (the default delta
  /// then ends at 1e-2).
  double regularization_boost_factor = 100.0;
  int max_regularization_boosts = 3;
  /// A pivot whose signed value falls below this threshold is replaced (dynamic regularization).
  double dynamic_regularization_threshold = 1e-13;
  /// The value (with the pivot's expected sign) that replaces such a pivot. 1e-7.
  double dynamic_regularization = 1e-7;
  /// Maximum iterative refinement steps per KKT solve, on the unregularized system. 6.
  int max_refinement_steps = 6;
  /// The same for the affine (predictor) direction, which only sets the centering and the second-order
  /// correction, so a rough solve suffices. 0.
  int max_affine_refinement_steps = 0;
  /// Refinement stops once ||residual||_inf <= this * (1 + ||rhs||_inf). 1e-12.
  double refinement_tolerance = 1e-12;
  /// ... or once ||residual||_inf <= refinement_mu_factor * mu * (1 + ||rhs||_inf), mu the iteration's
  /// complementarity: far from the optimum a direction needs no more accuracy than a small fraction
  /// of mu, and near it refinement_tolerance rules. 0 always refines to refinement_tolerance. 1e-4
  /// (measured: the same iterations with 60% fewer refinement steps, 10-20% less time on the
  /// temporal problems).
  double refinement_mu_factor = 1e-4;
  /// Refinement also stops when one step reduces the residual by less than this factor, in (0, 1]:
  /// further steps would cost a solve each for little gain. 0.5.
  double refinement_stagnation = 0.5;
  /// Second-order cones of at least this dimension use the sparse expansion of their scaling
  /// (two extra KKT rows per cone) instead of a dense block. >= 1. 6: below that a dense block
  /// has fewer non-zeros than the expansion.
  int sparse_cone_min_dimension = 6;
  /// kAutomatic chooses kReducedBanded only with at most this many expanded cones (>= 0): each adds
  /// two full-width border rows to the banded factor, beyond a few of them the augmented system is
  /// the better choice. 8.
  int reduced_max_expanded_cones = 8;
  /// kAutomatic chooses kReducedBanded only if the reduced system's profile, after the reverse
  /// Cuthill-McKee ordering, stores at most this many entries per row on average (>= 1; border rows
  /// excluded). 16: a skyline factor stores (and computes on) every zero inside the profile, so on
  /// wider problems the AMD-ordered sparse factor with its little fill is cheaper.
  int reduced_max_profile_per_row = 16;
  /// How the KKT system is solved; see KktMethod. kAutomatic.
  KktMethod kkt_method = KktMethod::kAutomatic;
  /// The most memory the sparse KKT factor (kAugmentedSparse) may take, bytes, counted with its
  /// fill-in before anything of it is allocated: its non-zeros after the elimination, at
  /// kFactorBytesPerNonzero each. 0 (the default): no limit. Solve throws std::invalid_argument
  /// naming the factor's size when it is above. (The reduced system's banded factor is bounded by
  /// reduced_max_profile_per_row.)
  std::int64_t max_factor_bytes = 0;
  static constexpr std::int64_t kFactorBytesPerNonzero = 28;
  /// Called after every iteration (and once for the initial point) if set. The library never prints.
  std::function<void(const IterationInfo&)> callback;

  /// True if every field is in its range; otherwise false with a message in *error (may be null).
  bool IsValid(std::string* error) const;
};

class Solver {
 public:
  using Options = SolverOptions;

  explicit Solver(Options options = {});
  ~Solver();
  Solver(Solver&&) noexcept;
  Solver& operator=(Solver&&) noexcept;
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  const Options& options() const { return options_; }
  /// Replaces the options (throws std::invalid_argument if !options.IsValid()). A change of
  /// sparse_cone_min_dimension, kkt_method, reduced_max_expanded_cones or reduced_max_profile_per_row
  /// forces a new symbolic analysis at the next Solve().
  void set_options(const Options& options);

  /// Solves the problem. Throws std::invalid_argument (before any iteration) if the problem is malformed
  /// (see Problem::Validate) or the options are invalid. All other outcomes are reported in the Result.
  Result Solve(const Problem& problem);

 private:
  struct Workspace;
  Options options_;
  std::unique_ptr<Workspace> workspace_;
};

}  // namespace timeopt::conic
