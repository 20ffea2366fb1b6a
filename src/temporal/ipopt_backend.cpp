// The Ipopt backend of the temporal stage: the discretized problem of discretization.h as an NLP
// in b (the free grid values x), with exact first and second derivatives (see ipopt_nlp.h).
// Debian 12 ships Ipopt 3.11 with MUMPS as its only linear solver.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <IpIpoptApplication.hpp>
#include <IpSolveStatistics.hpp>
#include <IpTNLP.hpp>

#include "ipopt_nlp.h"
#include "reachability.h"
#include "solver_internal.h"
#include "timeopt/temporal/temporal_solver.h"

namespace timeopt {

// ---------------------------------------------------------------------------------------------
// IpoptTemporalNlp
// ---------------------------------------------------------------------------------------------

namespace {

std::int64_t EntryKey(int row, int col) {
  return (static_cast<std::int64_t>(row) << 32) | static_cast<std::uint32_t>(col);
}

double IpoptBound(double v) {
  if (v >= IpoptTemporalNlp::kIpoptInfinity) return IpoptTemporalNlp::kIpoptInfinity;
  if (v <= -IpoptTemporalNlp::kIpoptInfinity) return -IpoptTemporalNlp::kIpoptInfinity;
  return v;
}

}  // namespace

IpoptTemporalNlp::IpoptTemporalNlp(const TemporalDiscretization& d) : d_(d) {
  cells_.reserve(d.cells.size());
  std::vector<std::int64_t> keys;
  keys.reserve(3 * d.cells.size());
  for (const Cell& cell : d.cells) {
    if (cell.time_weight == 0.0 && d.rho == 0.0) continue;  // no time, no regularization (a rest cell's half)
    CellTerms c;
    c.ds = cell.ds;
    c.tw = cell.ds * cell.time_weight;
    for (int j = 0; j < 2; ++j) {
      const GridValue& g = d.grid[static_cast<size_t>(cell.first_grid + j)];
      c.var[j] = g.var;
      c.scale[j] = g.scale;
      c.fixed[j] = g.fixed;
    }
    for (int j = 0; j < 2; ++j) {
      if (c.var[j] >= 0) keys.push_back(EntryKey(c.var[j], c.var[j]));
    }
    if (c.var[0] >= 0 && c.var[1] >= 0) {
      keys.push_back(EntryKey(std::max(c.var[0], c.var[1]), std::min(c.var[0], c.var[1])));
    }
    cells_.push_back(c);
  }
  cubic_.reserve(d.cubic_rows.size());
  for (const CubicRow& row : d.cubic_rows) {
    CubicTerms c;
    c.row = &row;
    for (int j = 0; j < 3; ++j) {
      const GridValue& g = d.grid[static_cast<size_t>(row.grid[static_cast<size_t>(j)])];
      c.var[j] = g.var;
      c.scale[j] = g.scale;
      c.fixed[j] = g.fixed;
    }
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        if (c.var[j] >= 0 && c.var[k] >= 0 && c.var[j] >= c.var[k]) keys.push_back(EntryKey(c.var[j], c.var[k]));
      }
    }
    cubic_.push_back(c);
  }
  cone_.reserve(d.cone_rows.size());
  for (const ConeRow& row : d.cone_rows) {
    ConeTerms c;
    c.t0 = row.bound_constant;
    c.v0 = row.norm_constant;
    for (size_t j = 0; j < row.grid.size(); ++j) {
      const GridValue& g = d.grid[static_cast<size_t>(row.grid[j])];
      if (g.var < 0) {
        c.t0 += row.bound[j] * g.fixed;
        c.v0 += row.norm[j] * g.fixed;
        continue;
      }
      int a = 0;
      while (a < c.k && c.var[a] != g.var) ++a;
      if (a == c.k) {
        if (c.k == 3) throw std::invalid_argument("IpoptTemporalNlp: a cone row over more than three values");
        c.var[c.k] = g.var;
        c.beta[c.k].setZero();
        ++c.k;
      }
      c.alpha[a] += row.bound[j] * g.scale;
      c.beta[a] += row.norm[j] * g.scale;
    }
    for (int a = 0; a < c.k; ++a) {
      for (int b = 0; b < c.k; ++b) {
        if (c.var[a] >= c.var[b]) keys.push_back(EntryKey(c.var[a], c.var[b]));
      }
    }
    cone_.push_back(c);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  hess_rows_.reserve(keys.size());
  hess_cols_.reserve(keys.size());
  for (std::int64_t k : keys) {
    hess_rows_.push_back(static_cast<int>(k >> 32));
    hess_cols_.push_back(static_cast<int>(k & 0xffffffff));
  }
  const auto index_of = [&keys](int row, int col) {
    const auto it = std::lower_bound(keys.begin(), keys.end(), EntryKey(row, col));
    return static_cast<int>(it - keys.begin());
  };
  for (CellTerms& c : cells_) {
    for (int j = 0; j < 2; ++j) {
      if (c.var[j] >= 0) c.hess[j] = index_of(c.var[j], c.var[j]);
    }
    if (c.var[0] >= 0 && c.var[1] >= 0) {
      c.hess[2] = index_of(std::max(c.var[0], c.var[1]), std::min(c.var[0], c.var[1]));
    }
  }
  for (const LinearRow& r : d.rows) num_jacobian_entries_ += static_cast<int>(r.terms.size());
  num_linear_jacobian_entries_ = num_jacobian_entries_;
  for (CubicTerms& c : cubic_) {
    for (int j = 0; j < 3; ++j) {
      if (c.var[j] < 0) continue;
      for (int k = 0; k < j; ++k) {
        if (c.var[k] == c.var[j]) c.jac[j] = c.jac[k];
      }
      if (c.jac[j] < 0) c.jac[j] = num_jacobian_entries_++;
      for (int k = 0; k < 3; ++k) {
        if (c.var[k] >= 0 && c.var[j] >= c.var[k]) c.hess[j][k] = index_of(c.var[j], c.var[k]);
      }
    }
  }
  for (ConeTerms& c : cone_) {
    c.jac = num_jacobian_entries_;
    num_jacobian_entries_ += c.k;
    for (int a = 0; a < c.k; ++a) {
      for (int b = 0; b < c.k; ++b) {
        if (c.var[a] >= c.var[b]) c.hess[a][b] = index_of(c.var[a], c.var[b]);
      }
    }
  }
  // Ipopt's complementarity test is absolute (compl_inf_tol, in row value times multiplier), and
  // the multipliers carry the objective's unit: on a path flown in 0.05 s its answer stopped 1.3e-6
  // above the optimum, at 5e-4 s 1.3e-4 above, at 5 s 1e-8. The objective Ipopt sees is J divided
  // by an estimate of the optimum, so of order 1 at any time scale: J of the reachability profile
  // where the rows form a chain (the paper's and the certified rows: the pointwise fastest profile
  // the rows allow between neighbouring values, within a few percent of the optimum; its time
  // alone, since rho's term is large where it is far faster than the optimum, at vanishing
  // tangents), else J of the starting point (1.4-90 times the optimum on the tests' problems).
  double estimate = std::numeric_limits<double>::infinity();
  internal::ChainRows chain(d.num_vars);
  std::vector<double> lo, hi;
  if (d.num_vars > 0 && internal::ChainFromDiscretization(d, &chain) && chain.CapUnbounded() &&
      internal::ControllableSets(chain, &lo, &hi) < 0) {
    estimate = Objective(internal::GreedyForward(chain, lo, hi, hi[0]).data(), true);
  }
  if (!(std::isfinite(estimate) && estimate > 0.0)) estimate = Objective(StartingPoint().data());
  if (std::isfinite(estimate) && estimate > 0.0) objective_scale_ = 1.0 / estimate;
}

std::array<double, 3> IpoptTemporalNlp::CubicGradient(const CubicRow& r, const std::array<double, 3>& b) {
  std::array<double, 3> g{};
  for (int j = 0; j < 3; ++j) {
    double sum = 0.0;
    for (int k = 0; k < 3; ++k) {
      for (int l = 0; l < 3; ++l) sum += r.coef[static_cast<size_t>(9 * j + 3 * k + l)] * b[k] * b[l];
    }
    g[j] = 3.0 * sum;
  }
  return g;
}

std::vector<double> IpoptTemporalNlp::StartingPoint() const {
  const size_t n = static_cast<size_t>(d_.num_vars);
  double cap = 0.0;
  for (double u : d_.var_upper) {
    if (std::isfinite(u)) cap = std::max(cap, u);
  }
  if (!(cap > 0.0)) cap = 1.0;
  std::vector<double> x0(n);
  for (size_t v = 0; v < n; ++v) x0[v] = std::min(d_.var_upper[v], cap);
  double t_max = 1.0;
  for (const LinearRow& r : d_.rows) {
    if (!(r.lower < 0.0 && r.upper > 0.0)) continue;  // 0 not strictly inside: ignored
    double value = 0.0;
    for (const auto& t : r.terms) value += t.second * x0[static_cast<size_t>(t.first)];
    if (value > r.upper) t_max = std::min(t_max, r.upper / value);
    if (value < r.lower) t_max = std::min(t_max, r.lower / value);
  }
  for (const CubicTerms& c : cubic_) {
    if (c.var[0] < 0 || c.var[1] < 0 || c.var[2] < 0) continue;
    const double value = c.row->Value(CubicB(c, x0.data()));
    if (value > 1.0) t_max = std::min(t_max, std::cbrt(1.0 / value));
  }
  for (double& v : x0) v *= 0.5 * t_max;
  return x0;
}

bool IpoptTemporalNlp::get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac_g, Ipopt::Index& nnz_h_lag,
                                    IndexStyleEnum& index_style) {
  n = d_.num_vars;
  m = static_cast<Ipopt::Index>(d_.rows.size() + cubic_.size() + cone_.size());
  nnz_jac_g = num_jacobian_entries_;
  nnz_h_lag = static_cast<Ipopt::Index>(hess_rows_.size());
  index_style = C_STYLE;
  return true;
}

bool IpoptTemporalNlp::get_bounds_info(Ipopt::Index n, Ipopt::Number* x_l, Ipopt::Number* x_u, Ipopt::Index m,
                                       Ipopt::Number* g_l, Ipopt::Number* g_u) {
  const Ipopt::Index linear = static_cast<Ipopt::Index>(d_.rows.size());
  const Ipopt::Index cubic_end = linear + static_cast<Ipopt::Index>(cubic_.size());
  if (n != d_.num_vars || m != cubic_end + static_cast<Ipopt::Index>(cone_.size())) return false;
  for (Ipopt::Index v = 0; v < n; ++v) {
    x_l[v] = 0.0;
    x_u[v] = IpoptBound(d_.var_upper[static_cast<size_t>(v)]);
  }
  for (Ipopt::Index i = 0; i < linear; ++i) {
    const LinearRow& r = d_.rows[static_cast<size_t>(i)];
    g_l[i] = IpoptBound(r.lower);
    g_u[i] = IpoptBound(r.upper);
  }
  for (Ipopt::Index i = linear; i < cubic_end; ++i) {
    g_l[i] = -kIpoptInfinity;
    g_u[i] = 1.0;
  }
  for (Ipopt::Index i = cubic_end; i < m; ++i) {  // t^2 - ||v||^2 >= 0
    g_l[i] = 0.0;
    g_u[i] = kIpoptInfinity;
  }
  return true;
}

bool IpoptTemporalNlp::get_constraints_linearity(Ipopt::Index m, LinearityType* const_types) {
  const Ipopt::Index linear = static_cast<Ipopt::Index>(d_.rows.size());
  for (Ipopt::Index i = 0; i < m; ++i) const_types[i] = i < linear ? LINEAR : NON_LINEAR;
  return true;
}

bool IpoptTemporalNlp::get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z,
                                          Ipopt::Number* /*z_L*/, Ipopt::Number* /*z_U*/, Ipopt::Index /*m*/,
                                          bool init_lambda, Ipopt::Number* /*lambda*/) {
  // Only a primal start is provided (no warm_start_init_point).
  if (init_z || init_lambda || n != d_.num_vars) return false;
  if (init_x) {
    const std::vector<double> x0 = StartingPoint();
    std::copy(x0.begin(), x0.end(), x);
  }
  return true;
}

bool IpoptTemporalNlp::eval_f(Ipopt::Index /*n*/, const Ipopt::Number* x, bool /*new_x*/, Ipopt::Number& obj_value) {
  obj_value = objective_scale_ * Objective(x);
  // b = 0 at both ends of a cell: infinite time. Ipopt then shortens its step.
  return std::isfinite(obj_value);
}

double IpoptTemporalNlp::Objective(const Ipopt::Number* x, bool time_only) const {
  const double rho = d_.rho;
  double time = 0.0, reg = 0.0;
  for (const CellTerms& c : cells_) {
    const double b0 = std::max(0.0, B(c, 0, x));
    const double b1 = std::max(0.0, B(c, 1, x));
    time += 2.0 * c.tw / (std::sqrt(b0) + std::sqrt(b1));
    const double diff = b1 - b0;
    reg += diff * diff / (4.0 * c.ds);
  }
  return time_only ? time : time + rho * reg;
}

bool IpoptTemporalNlp::eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool /*new_x*/, Ipopt::Number* grad_f) {
  std::fill(grad_f, grad_f + n, 0.0);
  const double rho = d_.rho;
  for (const CellTerms& c : cells_) {
    const double b0 = B(c, 0, x), b1 = B(c, 1, x);
    const double r0 = std::sqrt(std::max(b0, kMinDerivativeB));
    const double r1 = std::sqrt(std::max(b1, kMinDerivativeB));
    const double s = r0 + r1;
    const double reg = rho * (b1 - b0) / (2.0 * c.ds);  // dR/db1 = -dR/db0
    const double db[2] = {-c.tw / (s * s * r0) - reg, -c.tw / (s * s * r1) + reg};
    for (int j = 0; j < 2; ++j) {
      if (c.var[j] >= 0) grad_f[c.var[j]] += objective_scale_ * c.scale[j] * db[j];
    }
  }
  return true;
}

bool IpoptTemporalNlp::eval_g(Ipopt::Index /*n*/, const Ipopt::Number* x, bool /*new_x*/, Ipopt::Index m,
                              Ipopt::Number* g) {
  const Ipopt::Index linear = static_cast<Ipopt::Index>(d_.rows.size());
  const Ipopt::Index cubic_end = linear + static_cast<Ipopt::Index>(cubic_.size());
  if (m != cubic_end + static_cast<Ipopt::Index>(cone_.size())) return false;
  for (size_t r = 0; r < cone_.size(); ++r) {
    const double t = ConeT(cone_[r], x);
    g[cubic_end + static_cast<Ipopt::Index>(r)] = t * t - ConeV(cone_[r], x).squaredNorm();
  }
  for (Ipopt::Index i = 0; i < linear; ++i) {
    double value = 0.0;
    for (const auto& t : d_.rows[static_cast<size_t>(i)].terms) value += t.second * x[t.first];
    g[i] = value;
  }
  for (size_t r = 0; r < cubic_.size(); ++r)
    g[linear + static_cast<Ipopt::Index>(r)] = cubic_[r].row->Value(CubicB(cubic_[r], x));
  return true;
}

bool IpoptTemporalNlp::eval_jac_g(Ipopt::Index /*n*/, const Ipopt::Number* x, bool /*new_x*/, Ipopt::Index m,
                                  Ipopt::Index nele_jac, Ipopt::Index* iRow, Ipopt::Index* jCol,
                                  Ipopt::Number* values) {
  const Ipopt::Index linear = static_cast<Ipopt::Index>(d_.rows.size());
  const Ipopt::Index cubic_end = linear + static_cast<Ipopt::Index>(cubic_.size());
  if (nele_jac != num_jacobian_entries_ || m != cubic_end + static_cast<Ipopt::Index>(cone_.size())) return false;
  for (size_t r = 0; r < cone_.size(); ++r) {
    const ConeTerms& c = cone_[r];
    if (values == nullptr) {
      for (int a = 0; a < c.k; ++a) {
        iRow[c.jac + a] = cubic_end + static_cast<Ipopt::Index>(r);
        jCol[c.jac + a] = c.var[a];
      }
      continue;
    }
    const double t = ConeT(c, x);
    const Eigen::Vector3d v = ConeV(c, x);
    for (int a = 0; a < c.k; ++a) values[c.jac + a] = 2.0 * t * c.alpha[a] - 2.0 * c.beta[a].dot(v);
  }
  for (size_t r = 0; r < cubic_.size(); ++r) {
    const CubicTerms& c = cubic_[r];
    if (values == nullptr) {
      for (int j = 0; j < 3; ++j) {
        if (c.jac[j] < 0) continue;
        iRow[c.jac[j]] = linear + static_cast<Ipopt::Index>(r);
        jCol[c.jac[j]] = c.var[j];
      }
      continue;
    }
    for (int j = 0; j < 3; ++j) {
      if (c.jac[j] >= 0) values[c.jac[j]] = 0.0;
    }
    const std::array<double, 3> grad = CubicGradient(*c.row, CubicB(c, x));
    for (int j = 0; j < 3; ++j) {
      if (c.jac[j] >= 0) values[c.jac[j]] += c.scale[j] * grad[static_cast<size_t>(j)];
    }
  }
  Ipopt::Index e = 0;
  for (Ipopt::Index i = 0; i < linear; ++i) {
    for (const auto& t : d_.rows[static_cast<size_t>(i)].terms) {
      if (values == nullptr) {
        iRow[e] = i;
        jCol[e] = t.first;
      } else {
        values[e] = t.second;
      }
      ++e;
    }
  }
  return true;
}

bool IpoptTemporalNlp::eval_h(Ipopt::Index /*n*/, const Ipopt::Number* x, bool /*new_x*/,
                              Ipopt::Number ipopt_obj_factor, Ipopt::Index /*m*/, const Ipopt::Number* lambda,
                              bool /*new_lambda*/, Ipopt::Index nele_hess, Ipopt::Index* iRow, Ipopt::Index* jCol,
                              Ipopt::Number* values) {
  const double obj_factor = objective_scale_ * ipopt_obj_factor;
  if (nele_hess != static_cast<Ipopt::Index>(hess_rows_.size())) return false;
  if (values == nullptr) {
    std::copy(hess_rows_.begin(), hess_rows_.end(), iRow);
    std::copy(hess_cols_.begin(), hess_cols_.end(), jCol);
    return true;
  }
  // The linear rows' multipliers do not enter; the cubic and cone rows' do.
  std::fill(values, values + nele_hess, 0.0);
  const size_t linear = d_.rows.size();
  for (size_t r = 0; r < cone_.size(); ++r) {
    const double weight = lambda[linear + cubic_.size() + r];
    if (weight == 0.0) continue;
    const ConeTerms& c = cone_[r];
    for (int a = 0; a < c.k; ++a) {
      for (int b = 0; b < c.k; ++b) {
        if (c.hess[a][b] < 0) continue;
        values[c.hess[a][b]] += weight * 2.0 * (c.alpha[a] * c.alpha[b] - c.beta[a].dot(c.beta[b]));
      }
    }
  }
  for (size_t r = 0; r < cubic_.size(); ++r) {
    const double weight = lambda[linear + r];
    if (weight == 0.0) continue;
    const CubicTerms& c = cubic_[r];
    const std::array<double, 3> b = CubicB(c, x);
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) {
        if (c.hess[j][k] < 0) continue;
        double h = 0.0;
        for (int l = 0; l < 3; ++l)
          h += c.row->coef[static_cast<size_t>(9 * j + 3 * k + l)] * b[static_cast<size_t>(l)];
        values[c.hess[j][k]] += weight * 6.0 * h * c.scale[j] * c.scale[k];
      }
    }
  }
  const double rho = d_.rho;
  for (const CellTerms& c : cells_) {
    const double b0 = std::max(B(c, 0, x), kMinDerivativeB);
    const double b1 = std::max(B(c, 1, x), kMinDerivativeB);
    const double r0 = std::sqrt(b0), r1 = std::sqrt(b1);
    const double s = r0 + r1;
    const double s2 = s * s;
    const double reg = rho / (2.0 * c.ds);
    const double h00 = c.tw / (s2 * b0) * (1.0 / s + 0.5 / r0) + reg;
    const double h11 = c.tw / (s2 * b1) * (1.0 / s + 0.5 / r1) + reg;
    const double h01 = c.tw / (s2 * s * r0 * r1) - reg;
    if (c.hess[0] >= 0) values[c.hess[0]] += obj_factor * c.scale[0] * c.scale[0] * h00;
    if (c.hess[1] >= 0) values[c.hess[1]] += obj_factor * c.scale[1] * c.scale[1] * h11;
    if (c.hess[2] >= 0) {
      // A diagonal entry (both ends on one variable) receives the cross term twice.
      const double twice = c.var[0] == c.var[1] ? 2.0 : 1.0;
      values[c.hess[2]] += twice * obj_factor * c.scale[0] * c.scale[1] * h01;
    }
  }
  return true;
}

void IpoptTemporalNlp::finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x,
                                         const Ipopt::Number* /*z_L*/, const Ipopt::Number* /*z_U*/, Ipopt::Index /*m*/,
                                         const Ipopt::Number* /*g*/, const Ipopt::Number* /*lambda*/,
                                         Ipopt::Number /*obj_value*/, const Ipopt::IpoptData* /*ip_data*/,
                                         Ipopt::IpoptCalculatedQuantities* /*ip_cq*/) {
  solver_return_ = status;
  solution_.assign(x, x + n);
}

// ---------------------------------------------------------------------------------------------
// The backend
// ---------------------------------------------------------------------------------------------

namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

const char* ToString(Ipopt::ApplicationReturnStatus s) {
  switch (s) {
    case Ipopt::Solve_Succeeded:
      return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
      return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
      return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
      return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
      return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
      return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
      return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
      return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
      return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
      return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
      return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
      return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
      return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
      return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
      return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
      return "Insufficient_Memory";
    case Ipopt::Internal_Error:
      return "Internal_Error";
  }
  return "unknown Ipopt status";
}

// Absolute bound on the unscaled violation of a row or a bound at Ipopt's solution (rows are in
// m/s^2 or (m/s)^2, bounds in b). Ipopt's default (1e-4) would let T move by ~1e-4 relative;
// 1e-9 is well above the rounding of rows with coefficients ~K |f'| and keeps T's error far
// below the 1e-7 the tests ask.
constexpr double kConstraintViolationTolerance = 1e-9;
// Complementarity at the solution, in the units of row value times multiplier, the multipliers in
// those of the objective Ipopt sees (J divided by an estimate of its optimum, see
// IpoptTemporalNlp). Ipopt's default (1e-4) is far too loose for T to 1e-7. With the objective so
// scaled, 1e-9 left T 1.3e-9 to 1.8e-8 relative above the conic solver's on the benchmark's curves
// (m = 5-20, K = 30-100), 1e-11 1.3e-10 to 1.8e-9, in as many iterations or fewer (Ipopt's
// smallest barrier parameter, mu_min, is 1e-11).
constexpr double kComplementarityTolerance = 1e-11;
// Ipopt stops at an "acceptable" point after kAcceptableIterations consecutive iterates whose
// scaled error is below kAcceptableTolerance (and when it cannot make progress at such a point).
// We count that as optimal only with these tightened criteria (Ipopt's defaults are 1e-6 and a
// 1e-2 constraint violation): 1e-8 in the scaled error moves T by ~1e-8 relative.
constexpr double kAcceptableTolerance = 1e-8;
constexpr double kAcceptableConstraintViolation = 1e-8;
constexpr double kAcceptableComplementarity = 1e-8;
constexpr double kAcceptableDualInfeasibility = 1e-6;
constexpr int kAcceptableIterations = 15;

class IpoptTemporalSolver final : public TemporalSolver {
 public:
  explicit IpoptTemporalSolver(const IpoptTemporalOptions& options) : options_(options) {}

  TemporalBackend backend() const override { return TemporalBackend::kIpopt; }

 protected:
  JerkRows jerk_rows() const override { return JerkRows::kExact; }

 private:
  // Creates the application once per kind of rows (linear only, or with the exact jerk rows, whose
  // Jacobian changes); options never change for this solver.
  bool EnsureApplication(bool nonlinear_rows, std::string* error) {
    Ipopt::SmartPtr<Ipopt::IpoptApplication>& slot = app_[nonlinear_rows ? 1 : 0];
    if (Ipopt::IsValid(slot)) return true;
    // No console journal: the library never prints.
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication(false);
    Ipopt::OptionsList& o = *app->Options();
    bool ok = true;
    ok &= o.SetIntegerValue("print_level", 0);
    ok &= o.SetStringValue("sb", "yes");  // no banner
    ok &= o.SetNumericValue("tol", options_.tolerance);
    ok &= o.SetIntegerValue("max_iter", options_.max_iterations);
    if (std::isfinite(options_.max_solve_time_seconds)) {
      ok &= o.SetNumericValue("max_cpu_time", options_.max_solve_time_seconds);
    }
    ok &= o.SetNumericValue("constr_viol_tol", kConstraintViolationTolerance);
    ok &= o.SetNumericValue("compl_inf_tol", kComplementarityTolerance);
    ok &= o.SetNumericValue("acceptable_tol", kAcceptableTolerance);
    ok &= o.SetNumericValue("acceptable_constr_viol_tol", kAcceptableConstraintViolation);
    ok &= o.SetNumericValue("acceptable_compl_inf_tol", kAcceptableComplementarity);
    ok &= o.SetNumericValue("acceptable_dual_inf_tol", kAcceptableDualInfeasibility);
    ok &= o.SetIntegerValue("acceptable_iter", kAcceptableIterations);
    ok &= o.SetStringValue("linear_solver", "mumps");
    // No MC64/MUMPS scaling: faster on this well-scaled banded KKT system.
    ok &= o.SetIntegerValue("mumps_permuting_scaling", 0);
    ok &= o.SetIntegerValue("mumps_scaling", 0);
    ok &= o.SetStringValue("hessian_approximation", "exact");
    // Keep x >= 0 exactly (Ipopt relaxes bounds by 1e-8 by default): sqrt(b) stays defined at
    // every point Ipopt evaluates.
    ok &= o.SetNumericValue("bound_relax_factor", 0.0);
    // Linear rows: their Jacobian is evaluated once. The equalities are linear in every mode.
    ok &= o.SetStringValue("jac_c_constant", "yes");
    ok &= o.SetStringValue("jac_d_constant", nonlinear_rows ? "no" : "yes");
    ok &= o.SetNumericValue("nlp_lower_bound_inf", -1e19);
    ok &= o.SetNumericValue("nlp_upper_bound_inf", 1e19);
    if (!ok) {
      *error = "Ipopt rejected an option";
      return false;
    }
    // Options come only from the calls above, never from an ipopt.opt file in the working
    // directory: initialize from an empty stream.
    std::istringstream no_options_file;
    const Ipopt::ApplicationReturnStatus init = app->Initialize(no_options_file);
    if (init != Ipopt::Solve_Succeeded) {
      *error = std::string("Ipopt initialization failed: ") + ToString(init);
      return false;
    }
    slot = app;
    return true;
  }

  // The backend's part of TemporalSolver::Solve (overrides are private: the skeleton calls it).
  void SolveDiscretized(const TemporalDiscretization& d, TemporalResult* result, std::vector<double>* x) override {
    const Clock::time_point build_start = Clock::now();
    Ipopt::SmartPtr<IpoptTemporalNlp> nlp = new IpoptTemporalNlp(d);
    std::string error;
    const bool nonlinear = !d.cubic_rows.empty() || !d.cone_rows.empty();
    const bool ready = EnsureApplication(nonlinear, &error);
    result->build_time_seconds += Seconds(build_start, Clock::now());
    if (!ready) {
      result->status = TemporalStatus::kNumericalError;
      result->message = error;
      return;
    }

    const Clock::time_point solve_start = Clock::now();
    Ipopt::IpoptApplication& app = *app_[nonlinear ? 1 : 0];
    const Ipopt::ApplicationReturnStatus status = app.OptimizeTNLP(Ipopt::SmartPtr<Ipopt::TNLP>(Ipopt::GetRawPtr(nlp)));
    result->solve_time_seconds = Seconds(solve_start, Clock::now());
    Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app.Statistics();
    if (Ipopt::IsValid(stats)) result->iterations = stats->IterationCount();
    result->method = "ipopt";
    result->rows = static_cast<int>(d.rows.size() + d.cubic_rows.size() + d.cone_rows.size());

    switch (status) {
      case Ipopt::Solve_Succeeded:
      case Ipopt::Solved_To_Acceptable_Level:
        *x = nlp->solution();
        result->status = TemporalStatus::kOptimal;
        if (status == Ipopt::Solved_To_Acceptable_Level) {
          result->message = "Ipopt: solved to the acceptable level";
          result->reduced_accuracy = true;
        }
        return;
      case Ipopt::Infeasible_Problem_Detected:
        // With linear rows and bounds a point of local infeasibility is a global one. The exact
        // jerk rows are not convex, so there Ipopt's verdict is only local.
        result->status = TemporalStatus::kInfeasible;
        // The quadrotor's cones are convex, so with them (and no jerk rows) the verdict is global too.
        result->message = !d.cubic_rows.empty() ? std::string(
                                                      "Ipopt: the limits cannot be met (converged to a point of local "
                                                      "infeasibility; the exact jerk rows are not convex, so ") +
                                                      internal::kLocalVerdict + ")"
                          : !d.cone_rows.empty() ? "Ipopt: the limits cannot be met (converged to a point of local "
                                                   "infeasibility of the linear rows and the quadrotor's convex cones)"
                                                 : "Ipopt: the limits cannot be met (converged to a point of local "
                                                   "infeasibility of the linear rows)";
        return;
      case Ipopt::Maximum_Iterations_Exceeded:
        result->status = TemporalStatus::kIterationLimit;
        result->message =
            "Ipopt: maximum number of iterations (" + std::to_string(options_.max_iterations) + ") exceeded";
        return;
      case Ipopt::Maximum_CpuTime_Exceeded:
        result->status = TemporalStatus::kIterationLimit;
        result->message = "Ipopt: CPU time limit (" + std::to_string(options_.max_solve_time_seconds) + " s) exceeded";
        return;
      default:
        result->status = TemporalStatus::kNumericalError;
        result->message = std::string("Ipopt failed: ") + ToString(status);
        return;
    }
  }

  IpoptTemporalOptions options_;
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app_[2];  // linear rows only; with cubic rows
};

}  // namespace

std::unique_ptr<TemporalSolver> MakeIpoptTemporalSolver(const IpoptTemporalOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("IpoptTemporalOptions." + error);
  return std::make_unique<IpoptTemporalSolver>(options);
}

}  // namespace timeopt
