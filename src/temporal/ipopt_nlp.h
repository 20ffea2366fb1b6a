#pragma once

// Private: the temporal problem as an Ipopt NLP over the free unknowns x of a
// TemporalDiscretization (b_g = scale_g * x[var_g], see discretization.h).
//
//   minimize    J(x) = sum over cells [ 2 ds / (sqrt(b0) + sqrt(b1)) + rho ds ((b1 - b0) / (2 ds))^2 ]
//               (Ipopt sees J divided by an estimate of its optimum: of order 1 at every time scale)
//   subject to  0 <= x <= var_upper,   row.lower <= sum row.coef * x <= row.upper  (linear rows)
//
// Derivatives of one cell's time g(b0, b1) = 2 ds / S, S = r0 + r1, r = sqrt(b):
//   dg/db0      = -ds / (S^2 r0)
//   d2g/db0^2   =  ds / (S^2 b0) (1/S + 1/(2 r0))
//   d2g/db0 db1 =  ds / (S^3 r0 r1)
// (and the same with 0 <-> 1); of its regularization R = rho (b1 - b0)^2 / (4 ds):
//   dR/db1 = -dR/db0 = rho (b1 - b0) / (2 ds),  d2R/db0^2 = d2R/db1^2 = -d2R/db0 db1 = rho / (2 ds).
// Chain rule through b = scale * x. The linear rows do not enter the Hessian of the Lagrangian;
// each cell couples the variables of its two grid points (lower triangle, duplicate (row, col)
// pairs merged into one entry).
//
// Jerk-limited mode with exact rows (JerkRows::kExact) adds the cubic rows c(b) = sum S_jkl b_j b_k
// b_l <= 1 (S fully symmetric) over a cell's three half-grid values, after the linear rows:
//   dc/db_j = 3 sum_kl S_jkl b_k b_l,   d2c/db_j db_k = 6 sum_l S_jkl b_l,
// and lambda times the latter in the Hessian, which then couples all three values of the cell.
//
// Only used by ipopt_backend.cpp and its test.

#include <array>
#include <vector>

#include <Eigen/Core>
#include <IpTNLP.hpp>

#include "discretization.h"

namespace timeopt {

class IpoptTemporalNlp : public Ipopt::TNLP {
 public:
  // Smallest b used inside derivative evaluation, where 1/sqrt(b) appears up to the third power
  // (a fixed b = 0 next to a free b, or a free b that Ipopt drives to its bound). 1e-60 keeps
  // every power in the formulas above finite in double precision (r^-3 S^-2 <= 1e150), and is
  // far below any b the optimizer can settle on (b = 1e-60 means a speed of 1e-30 unit-s/s).
  // Function values are evaluated without it.
  static constexpr double kMinDerivativeB = 1e-60;
  // Ipopt's "infinite" bound: any bound beyond +-1e19 (nlp_upper_bound_inf) counts as absent.
  static constexpr double kIpoptInfinity = 2e19;

  // Keeps a reference: `d` must outlive the NLP.
  explicit IpoptTemporalNlp(const TemporalDiscretization& d);

  int num_hessian_entries() const { return static_cast<int>(hess_rows_.size()); }
  int num_jacobian_entries() const { return num_jacobian_entries_; }

  // The factor on J in what Ipopt sees (eval_f, eval_grad_f, eval_h): 1 / an estimate of the
  // optimal J (see the constructor), or 1 when there is none.
  double objective_scale() const { return objective_scale_; }
  // The point Ipopt last reported through finalize_solution (empty before).
  const std::vector<double>& solution() const { return solution_; }
  Ipopt::SolverReturn solver_return() const { return solver_return_; }

  // Starting point: x0_v = min(var_upper_v, cap) with cap the largest finite upper bound (1
  // without any), scaled by half of the largest t in (0, 1] such that every row with 0 inside
  // its bounds holds at t x0. Linear rows hold at x = 0, so t x0 satisfies them for all
  // t in [0, t_max]: the start is feasible for those rows and strictly inside the bounds. Cubic
  // rows whose values are all free scale as t^3 and are taken in the same way; the others are
  // left to Ipopt, which does not need a feasible start.
  std::vector<double> StartingPoint() const;

  // ---- Ipopt::TNLP ----
  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override;
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m, Ipopt::Number* g_l,
                       Ipopt::Number* g_u) override;
  bool get_constraints_linearity(Ipopt::Index m, LinearityType* const_types) override;
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z, Ipopt::Number* z_L,
                          Ipopt::Number* z_U, Ipopt::Index m, bool init_lambda, Ipopt::Number* lambda) override;
  bool eval_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number& obj_value) override;
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number* grad_f) override;
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Number* g) override;
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m, Ipopt::Index nele_jac,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override;
  bool eval_h(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Number obj_factor, Ipopt::Index m,
              const Ipopt::Number* lambda, bool new_lambda, Ipopt::Index nele_hess, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override;
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x, const Ipopt::Number* z_L,
                         const Ipopt::Number* z_U, Ipopt::Index m, const Ipopt::Number* g, const Ipopt::Number* lambda,
                         Ipopt::Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  // One cell with its two grid values resolved: b_j = fixed[j] when var[j] < 0, else
  // scale[j] * x[var[j]]. hess[0], hess[1], hess[2]: Hessian entries of (var0, var0),
  // (var1, var1) and (var0, var1) (-1 when a variable is fixed; all the same entry when
  // var0 == var1).
  struct CellTerms {
    int var[2] = {-1, -1};
    double scale[2] = {1.0, 1.0};
    double fixed[2] = {0.0, 0.0};
    int hess[3] = {-1, -1, -1};
    double ds = 0.0;
    double tw = 0.0;  // the time term's ds times the cell's time_weight
  };

  double B(const CellTerms& c, int j, const Ipopt::Number* x) const {
    return c.var[j] < 0 ? c.fixed[j] : c.scale[j] * x[c.var[j]];
  }

  // One cubic row with its grid values resolved as in CellTerms. jac[j]: the Jacobian entry that
  // value j's variable adds to (-1 when fixed; values on one variable share it). hess[j][k]: the
  // Hessian entry the ordered pair adds to (-1 when a value is fixed or var[j] < var[k], so that
  // each lower-triangle entry collects its pairs once).
  struct CubicTerms {
    const CubicRow* row = nullptr;
    int var[3] = {-1, -1, -1};
    double scale[3] = {1.0, 1.0, 1.0};
    double fixed[3] = {0.0, 0.0, 0.0};
    int jac[3] = {-1, -1, -1};
    int hess[3][3] = {{-1, -1, -1}, {-1, -1, -1}, {-1, -1, -1}};
  };
  std::array<double, 3> CubicB(const CubicTerms& c, const Ipopt::Number* x) const {
    std::array<double, 3> b{};
    for (int j = 0; j < 3; ++j) b[j] = c.var[j] < 0 ? c.fixed[j] : c.scale[j] * x[c.var[j]];
    return b;
  }
  // dc/db_j for the three values.
  static std::array<double, 3> CubicGradient(const CubicRow& r, const std::array<double, 3>& b);

  // One cone row (ConeRow) in x: t = t0 + alpha . x_vars, v = v0 + beta x_vars (3 x k), written as
  // the smooth q = t^2 - ||v||^2 >= 0 (with t >= 0 from the cone's own linear row or a constant
  // t): grad q = 2 t alpha - 2 beta' v, Hessian 2 (alpha alpha' - beta' beta), constant.
  struct ConeTerms {
    int k = 0;  // distinct free variables
    int var[3] = {-1, -1, -1};
    double alpha[3] = {0.0, 0.0, 0.0};
    Eigen::Vector3d beta[3];
    double t0 = 0.0;
    Eigen::Vector3d v0 = Eigen::Vector3d::Zero();
    int jac = -1;                                                 // its first Jacobian entry (k consecutive ones)
    int hess[3][3] = {{-1, -1, -1}, {-1, -1, -1}, {-1, -1, -1}};  // (a, b) with var[a] >= var[b]
  };
  double ConeT(const ConeTerms& c, const Ipopt::Number* x) const {
    double t = c.t0;
    for (int a = 0; a < c.k; ++a) t += c.alpha[a] * x[c.var[a]];
    return t;
  }
  Eigen::Vector3d ConeV(const ConeTerms& c, const Ipopt::Number* x) const {
    Eigen::Vector3d v = c.v0;
    for (int a = 0; a < c.k; ++a) v += c.beta[a] * x[c.var[a]];
    return v;
  }

  // J(x) unscaled (eval_f reports objective_scale_ J), or its time term alone.
  double Objective(const Ipopt::Number* x, bool time_only = false) const;
  const TemporalDiscretization& d_;
  // The factor on J in everything Ipopt sees (see objective_scale()).
  double objective_scale_ = 1.0;
  std::vector<CellTerms> cells_;
  std::vector<CubicTerms> cubic_;
  std::vector<ConeTerms> cone_;
  int num_linear_jacobian_entries_ = 0;
  std::vector<int> hess_rows_, hess_cols_;
  int num_jacobian_entries_ = 0;
  std::vector<double> solution_;
  Ipopt::SolverReturn solver_return_ = Ipopt::INTERNAL_ERROR;
};

}  // namespace timeopt
