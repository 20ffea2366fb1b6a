// The structured path of the SOCP backend (banded_ipm.h): a primal-dual interior-point method
// with Mehrotra's predictor-corrector on J(x) subject to G x <= h, solving each Newton system
//   (grad^2 J + G' (Z / S) G) dx = rhs
// by a banded Cholesky factorization along the path.
//
// Iterate: x, slacks s = h - G x + r_p (r_p -> 0) and multipliers z > 0. With r_d = grad J + G'z,
// r_p = G x + s - h and a complementarity target r_c (s o z for the predictor; s o z + ds_a o dz_a
// - sigma mu e for the corrector):
//   M dx = -r_d + G' ((r_c - z o r_p) / s),   dz = (z o (r_p + G dx) - r_c) / s,   ds = -r_p - G dx,
// and one step length for all three (J is not linear, so the primal and dual steps are not
// separable as in a linear programme), 0.99 of the way to the boundary of s, z >= 0. The bound
// rows x >= 0 start with r_p = 0 and keep it (their rows are linear), so x = s > 0 and J stays
// finite at every iterate.

#include "banded_ipm.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "reachability.h"

namespace timeopt::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The fraction of the step to the boundary of s, z >= 0 that is taken.
constexpr double kStepFraction = 0.99;
// The start: x0 = kGreedyWeight times the reachability profile (GreedyProfile, feasible and close
// to the optimum) plus the rest times a uniformly scaled-down one (strictly inside every row that
// holds at 0), and multipliers with s'z = kStartGap J(x0). Measured on the benchmark's curves
// (m = 10, K = 50): 12 iterations with 0.9 and 0.1; weights 0.5-0.95 and gaps 0.01-1 took 11-17;
// the scaled-down start alone took 37, and z from the gradient's size instead of J 75 (no answer).
constexpr double kGreedyWeight = 0.9;
constexpr double kStartGap = 0.1;
// How much looser (relative) every bound must still leave the problem without a profile for
// this path to call it infeasible itself (see banded_ipm.h).
constexpr double kInfeasibleMargin = 1e-6;
// The smallest pivot of the Cholesky factorization relative to its diagonal entry: below it the
// system is too badly conditioned for this path, and the conic solver takes over.
constexpr double kPivotFloor = 1e-15;

// One cell's time term with its grid values resolved (as IpoptTemporalNlp's CellTerms).
struct CellTerm {
  int var[2] = {-1, -1};
  double scale[2] = {1.0, 1.0};
  double fixed[2] = {0.0, 0.0};
  double c = 0.0;    // time = c / (sqrt(b0) + sqrt(b1)): 2 ds time_weight
  double reg = 0.0;  // rho / (4 ds): the regularization rho (b1 - b0)^2 / (4 ds)
};

// Lower band of a symmetric n x n matrix: entry (i, i - k) at band[i * (p + 1) + k], k = 0..p.
struct Band {
  int n = 0, p = 0;
  std::vector<double> v;
  void Reset(int size, int bandwidth) {
    n = size;
    p = bandwidth;
    v.assign(static_cast<size_t>(n) * static_cast<size_t>(p + 1), 0.0);
  }
  double& At(int i, int j) { return v[static_cast<size_t>(i) * static_cast<size_t>(p + 1) + static_cast<size_t>(i - j)]; }
  // Adds a to (i, j) and, for i != j, its mirror (stored once).
  void Add(int i, int j, double a) { At(std::max(i, j), std::min(i, j)) += a; }

  // In-place Cholesky L L'; false when a pivot falls below kPivotFloor times its diagonal.
  bool Factor() {
    if (p == 1) {
      // Tridiagonal (the paper's and the certified rows): v[2 i] diagonal, v[2 i + 1] sub-diagonal.
      double* a = v.data();
      for (int j = 0; j < n; ++j) {
        const double original = a[2 * j];
        const double diag = original - (j > 0 ? a[2 * j + 1] * a[2 * j + 1] : 0.0);
        if (!(diag > kPivotFloor * std::abs(original)) || !std::isfinite(diag)) return false;
        const double l = std::sqrt(diag);
        a[2 * j] = l;
        if (j + 1 < n) a[2 * (j + 1) + 1] /= l;
      }
      return true;
    }
    for (int j = 0; j < n; ++j) {
      const int lo = std::max(0, j - p);
      double diag = At(j, j);
      const double original = diag;
      for (int k = lo; k < j; ++k) diag -= At(j, k) * At(j, k);
      if (!(diag > kPivotFloor * std::abs(original)) || !std::isfinite(diag)) return false;
      const double l = std::sqrt(diag);
      At(j, j) = l;
      const int hi = std::min(n - 1, j + p);
      for (int i = j + 1; i <= hi; ++i) {
        double a = At(i, j);
        for (int k = std::max(lo, i - p); k < j; ++k) a -= At(i, k) * At(j, k);
        At(i, j) = a / l;
      }
    }
    return true;
  }
  // Solves L L' x = b in place.
  void Solve(std::vector<double>& b) {
    if (p == 1) {
      const double* a = v.data();
      double* x = b.data();
      x[0] /= a[0];
      for (int i = 1; i < n; ++i) x[i] = (x[i] - a[2 * i + 1] * x[i - 1]) / a[2 * i];
      x[n - 1] /= a[2 * (n - 1)];
      for (int i = n - 2; i >= 0; --i) x[i] = (x[i] - a[2 * (i + 1) + 1] * x[i + 1]) / a[2 * i];
      return;
    }
    for (int i = 0; i < n; ++i) {
      double a = b[static_cast<size_t>(i)];
      for (int k = std::max(0, i - p); k < i; ++k) a -= At(i, k) * b[static_cast<size_t>(k)];
      b[static_cast<size_t>(i)] = a / At(i, i);
    }
    for (int i = n - 1; i >= 0; --i) {
      double a = b[static_cast<size_t>(i)];
      const int hi = std::min(n - 1, i + p);
      for (int k = i + 1; k <= hi; ++k) a -= At(k, i) * b[static_cast<size_t>(k)];
      b[static_cast<size_t>(i)] = a / At(i, i);
    }
  }
};

class BandedIpm {
 public:
  BandedIpm(const TemporalDiscretization& d, const BandedIpmSettings& settings) : d_(d), settings_(settings) {}

  BandedIpmOutcome Run() {
    BandedIpmOutcome out;
    if (!Setup(&out.message)) {
      if (infeasible_) out.kind = BandedIpmOutcome::Kind::kInfeasible;
      return out;
    }
    out.kind = BandedIpmOutcome::Kind::kGaveUp;
    Start();
    for (int it = 0;; ++it) {
      out.iterations = it;
      Evaluate();
      if (Converged()) {
        out.kind = BandedIpmOutcome::Kind::kOptimal;
        out.x = x_;
        return out;
      }
      if (it >= settings_.max_iterations) {
        out.message = "structured path: iteration limit";
        return out;
      }
      if (!Step()) {
        out.message = "structured path: the Newton system broke down";
        return out;
      }
    }
  }

 private:
  // A row v0 x_c0 + v1 x_c1 <= h over one value (v1 = 0, c1 = c0) or two neighbouring ones
  // (c1 = c0 + 1), scaled so that h is +-1 or 0.
  struct Row {
    int c0 = 0, c1 = 0;
    double v0 = 0.0, v1 = 0.0;
  };

  // The rows, the cells and the bandwidth; false (not applicable) with a reason.
  bool Setup(std::string* why) {
    n_ = d_.num_vars;
    if (n_ <= 0) {
      *why = "no free values";
      return false;
    }
    if (!d_.cone_rows.empty() || !d_.cubic_rows.empty()) {
      *why = "cone or cubic rows";
      return false;
    }
    rows_.clear();
    h_.clear();
    bool two_neighbours = true;
    const auto add_row = [&](const std::vector<std::pair<int, double>>& terms, double sign, double bound) {
      double scale = std::abs(bound);
      if (!(scale > 0.0)) {
        for (const auto& t : terms) scale = std::max(scale, std::abs(t.second));
      }
      if (!(scale > 0.0)) scale = 1.0;
      Row row;
      if (terms.size() == 1) {
        row.c0 = row.c1 = terms[0].first;
        row.v0 = sign * terms[0].second / scale;
      } else if (terms.size() == 2 && std::abs(terms[0].first - terms[1].first) == 1) {
        const bool ordered = terms[0].first < terms[1].first;
        const auto& first = ordered ? terms[0] : terms[1];
        const auto& second = ordered ? terms[1] : terms[0];
        row.c0 = first.first;
        row.c1 = second.first;
        row.v0 = sign * first.second / scale;
        row.v1 = sign * second.second / scale;
      } else {
        two_neighbours = false;
        return;
      }
      rows_.push_back(row);
      h_.push_back(sign * bound / scale);
    };
    // Bound rows first: row v is -x_v <= 0 (the start keeps their residual at 0).
    std::vector<std::pair<int, double>> single(1);
    for (int v = 0; v < n_; ++v) {
      single[0] = {v, 1.0};
      add_row(single, -1.0, 0.0);
    }
    for (const LinearRow& r : d_.rows) {
      if (r.lower == r.upper) {
        *why = "equality rows";
        return false;
      }
      if (std::isfinite(r.upper)) add_row(r.terms, 1.0, r.upper);
      if (std::isfinite(r.lower)) add_row(r.terms, -1.0, r.lower);
    }
    for (int v = 0; v < n_; ++v) {
      single[0] = {v, 1.0};
      if (std::isfinite(d_.var_upper[static_cast<size_t>(v)])) add_row(single, 1.0, d_.var_upper[static_cast<size_t>(v)]);
    }
    // Without the reachability start (which needs these rows) the method took 37-75 iterations
    // where the conic solver takes 15-26 (lambda_a's rows over three values), so it stops here.
    if (!two_neighbours) {
      *why = "a row over more than two neighbouring values";
      return false;
    }
    m_ = static_cast<int>(h_.size());
    cells_.clear();
    int p = 1;
    for (const Cell& cell : d_.cells) {
      CellTerm c;
      for (int j = 0; j < 2; ++j) {
        const GridValue& g = d_.grid[static_cast<size_t>(cell.first_grid + j)];
        c.var[j] = g.var;
        c.scale[j] = g.scale;
        c.fixed[j] = g.fixed;
      }
      if (c.var[0] < 0 && c.var[1] < 0 && !(c.fixed[0] + c.fixed[1] > 0.0)) {
        *why = "a cell whose speed is fixed at 0 at both ends";
        return false;
      }
      c.c = 2.0 * cell.ds * cell.time_weight;
      c.reg = d_.rho / (4.0 * cell.ds);
      if (c.var[0] >= 0 && c.var[1] >= 0) p = std::max(p, std::abs(c.var[0] - c.var[1]));
      cells_.push_back(c);
    }
    if (p > settings_.max_bandwidth) {
      *why = "half-bandwidth " + std::to_string(p);
      return false;
    }
    p_ = p;
    if (!GreedyProfile(&greedy_, 0.0)) {
      std::vector<double> unused;
      infeasible_ = !GreedyProfile(&unused, kInfeasibleMargin);
      *why = infeasible_ ? "no time allocation satisfies the limits: reachability along the path finds no "
                           "profile (structured path)"
                         : "the reachability pass found no profile";
      return false;
    }
    return true;
  }

  double RowValue(const Row& row, const std::vector<double>& x) const {
    return row.v0 * x[static_cast<size_t>(row.c0)] + row.v1 * x[static_cast<size_t>(row.c1)];
  }

  // x0: kGreedyWeight times the reachability profile plus the rest times min(var_upper, cap)
  // scaled by half of the largest t in (0, 1] that keeps every row holding at 0 satisfied at t x0
  // (as IpoptTemporalNlp::StartingPoint); s from the rows (at least kSlackFloor, which leaves a
  // residual on rows the start violates); z = mu0 / s.
  void Start() {
    double cap = 0.0;
    for (double u : d_.var_upper) {
      if (std::isfinite(u)) cap = std::max(cap, u);
    }
    if (!(cap > 0.0)) cap = 1.0;
    x_.assign(static_cast<size_t>(n_), 0.0);
    for (int v = 0; v < n_; ++v) x_[static_cast<size_t>(v)] = std::min(d_.var_upper[static_cast<size_t>(v)], cap);
    double t_max = 1.0;
    for (int r = n_; r < m_; ++r) {
      if (!(h_[static_cast<size_t>(r)] > 0.0)) continue;
      const double value = RowValue(rows_[static_cast<size_t>(r)], x_);
      if (value > h_[static_cast<size_t>(r)]) t_max = std::min(t_max, h_[static_cast<size_t>(r)] / value);
    }
    for (int v = 0; v < n_; ++v) {
      x_[static_cast<size_t>(v)] = kGreedyWeight * greedy_[static_cast<size_t>(v)] +
                                   (1.0 - kGreedyWeight) * 0.5 * t_max * x_[static_cast<size_t>(v)];
    }
    s_.assign(static_cast<size_t>(m_), 0.0);
    z_.assign(static_cast<size_t>(m_), 0.0);
    constexpr double kSlackFloor = 1e-2;
    for (int r = 0; r < m_; ++r) {
      const double slack = h_[static_cast<size_t>(r)] - RowValue(rows_[static_cast<size_t>(r)], x_);
      s_[static_cast<size_t>(r)] = r < n_ ? x_[static_cast<size_t>(r)] : std::max(slack, kSlackFloor);
    }
    // z = mu0 / s with s'z = kStartGap J(x0).
    Evaluate();
    const double mu0 = std::max(kStartGap * std::abs(objective_) / m_, std::numeric_limits<double>::min());
    for (int r = 0; r < m_; ++r) z_[static_cast<size_t>(r)] = mu0 / s_[static_cast<size_t>(r)];
  }

  // A feasible profile by reachability along the path (reachability.h): the controllable sets
  // backward, then the largest values forward. False when a set comes out empty.
  // `margin` loosens every bound: h + margin |h| (and margin for h = 0).
  bool GreedyProfile(std::vector<double>* out, double margin) const {
    ChainRows chain(n_);
    for (size_t r = 0; r < rows_.size(); ++r) {
      const Row& row = rows_[r];
      const double h = h_[r] + margin * std::max(1.0, std::abs(h_[r]));
      chain.Add(row.c0, row.v0, row.c1, row.v1, h);  // two-value rows are neighbours (Setup)
    }
    if (!chain.CapUnbounded()) return false;
    std::vector<double> lo, hi;
    if (ControllableSets(chain, &lo, &hi) >= 0) return false;
    *out = GreedyForward(chain, lo, hi, hi[0]);
    return true;
  }

  double B(const CellTerm& c, int j, const std::vector<double>& x) const {
    return c.var[j] < 0 ? c.fixed[j] : c.scale[j] * x[static_cast<size_t>(c.var[j])];
  }

  // J, its gradient and (into hess_) its Hessian at x_; the residuals r_d and r_p.
  void Evaluate() {
    grad_.assign(static_cast<size_t>(n_), 0.0);
    hess_.Reset(n_, p_);
    objective_ = 0.0;
    for (const CellTerm& c : cells_) {
      const double b0 = std::max(B(c, 0, x_), 0.0), b1 = std::max(B(c, 1, x_), 0.0);
      const double r0 = std::sqrt(b0), r1 = std::sqrt(b1);
      const double S = r0 + r1;
      objective_ += c.c / S + c.reg * (b1 - b0) * (b1 - b0);
      const double half = 0.5 * c.c;
      const double reg_grad = 2.0 * c.reg * (b1 - b0);
      double db[2] = {-reg_grad, reg_grad};
      double h00 = 2.0 * c.reg, h11 = 2.0 * c.reg, h01 = -2.0 * c.reg;
      const double S2 = S * S;
      if (c.var[0] >= 0) {
        db[0] += -half / (S2 * r0);
        h00 += half / (S2 * b0) * (1.0 / S + 0.5 / r0);
      }
      if (c.var[1] >= 0) {
        db[1] += -half / (S2 * r1);
        h11 += half / (S2 * b1) * (1.0 / S + 0.5 / r1);
      }
      if (c.var[0] >= 0 && c.var[1] >= 0) h01 += half / (S2 * S * r0 * r1);
      for (int j = 0; j < 2; ++j) {
        if (c.var[j] >= 0) grad_[static_cast<size_t>(c.var[j])] += c.scale[j] * db[j];
      }
      if (c.var[0] >= 0) hess_.Add(c.var[0], c.var[0], c.scale[0] * c.scale[0] * h00);
      if (c.var[1] >= 0) hess_.Add(c.var[1], c.var[1], c.scale[1] * c.scale[1] * h11);
      if (c.var[0] >= 0 && c.var[1] >= 0) {
        const double cross = c.scale[0] * c.scale[1] * h01;
        if (c.var[0] == c.var[1]) hess_.Add(c.var[0], c.var[0], 2.0 * cross);
        else hess_.Add(c.var[0], c.var[1], cross);
      }
    }
    rd_ = grad_;
    rp_.resize(static_cast<size_t>(m_));
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      const Row& row = rows_[r];
      rd_[static_cast<size_t>(row.c0)] += row.v0 * z_[r];
      rd_[static_cast<size_t>(row.c1)] += row.v1 * z_[r];
      rp_[r] = RowValue(row, x_) + s_[r] - h_[r];
    }
  }

  bool Converged() const {
    double rp = 0.0, rd = 0.0, hmax = 1.0, gmax = 1.0, gap = 0.0;
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      rp = std::max(rp, std::abs(rp_[r]));
      hmax = std::max(hmax, std::abs(h_[r]));
      gap += s_[r] * z_[r];
    }
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) {
      rd = std::max(rd, std::abs(rd_[v]));
      gmax = std::max(gmax, std::abs(grad_[v]));
    }
    return rp <= settings_.tolerance * hmax && rd <= settings_.tolerance * gmax &&
           gap <= settings_.gap_tolerance * std::abs(objective_);
  }

  // Solves the Newton system for the complementarity target rc into dx, ds, dz; returns the
  // largest step in (0, inf] that keeps s and z >= 0.
  double Direction(const std::vector<double>& rc) {
    dx_.resize(static_cast<size_t>(n_));
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) dx_[v] = -rd_[v];
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      const Row& row = rows_[r];
      const double t = (rc[r] - z_[r] * rp_[r]) * inv_s_[r];
      dx_[static_cast<size_t>(row.c0)] += row.v0 * t;
      dx_[static_cast<size_t>(row.c1)] += row.v1 * t;
    }
    factor_.Solve(dx_);
    ds_.resize(static_cast<size_t>(m_));
    dz_.resize(static_cast<size_t>(m_));
    double alpha = kInf;
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      const double gdx = RowValue(rows_[r], dx_);
      const double ds = -rp_[r] - gdx;
      const double dz = (z_[r] * (rp_[r] + gdx) - rc[r]) * inv_s_[r];
      ds_[r] = ds;
      dz_[r] = dz;
      if (ds < 0.0) alpha = std::min(alpha, -s_[r] / ds);
      if (dz < 0.0) alpha = std::min(alpha, -z_[r] / dz);
    }
    return alpha;
  }

  bool Step() {
    // M = grad^2 J + G' (Z / S) G, and mu.
    factor_ = hess_;
    double mu = 0.0;
    inv_s_.resize(static_cast<size_t>(m_));
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      const Row& row = rows_[r];
      inv_s_[r] = 1.0 / s_[r];
      const double w = z_[r] * inv_s_[r];
      mu += s_[r] * z_[r];
      factor_.At(row.c0, row.c0) += w * row.v0 * row.v0;
      if (row.v1 != 0.0) {
        factor_.At(row.c1, row.c1) += w * row.v1 * row.v1;
        factor_.At(row.c1, row.c0) += w * row.v0 * row.v1;
      }
    }
    mu /= m_;
    if (!factor_.Factor()) return false;
    // Predictor.
    rc_.resize(static_cast<size_t>(m_));
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) rc_[r] = s_[r] * z_[r];
    const double alpha_aff = std::min(1.0, Direction(rc_));
    double mu_aff = 0.0;
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      mu_aff += (s_[r] + alpha_aff * ds_[r]) * (z_[r] + alpha_aff * dz_[r]);
    }
    mu_aff /= m_;
    const double ratio = std::max(0.0, mu_aff / mu);
    const double sigma = std::min(1.0, ratio * ratio * ratio);
    // Corrector.
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) rc_[r] = s_[r] * z_[r] + ds_[r] * dz_[r] - sigma * mu;
    const double alpha = std::min(1.0, kStepFraction * Direction(rc_));
    for (double v : dx_) {
      if (!std::isfinite(v)) return false;
    }
    if (!(alpha > 0.0)) return false;
    for (size_t r = 0; r < static_cast<size_t>(m_); ++r) {
      s_[r] += alpha * ds_[r];
      z_[r] += alpha * dz_[r];
    }
    // The bound rows keep x = s exactly (their residual is 0 and stays 0 up to rounding).
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) x_[v] = s_[v];
    return true;
  }

  const TemporalDiscretization& d_;
  BandedIpmSettings settings_;
  int n_ = 0, m_ = 0, p_ = 0;
  std::vector<Row> rows_;
  std::vector<double> h_;
  std::vector<CellTerm> cells_;
  std::vector<double> greedy_;  // the reachability profile (GreedyProfile)
  bool infeasible_ = false;     // no profile even with the bounds loosened (kInfeasibleMargin)
  std::vector<double> x_, s_, z_;
  std::vector<double> grad_, rd_, rp_, rc_, dx_, ds_, dz_, inv_s_;
  double objective_ = 0.0;
  Band hess_, factor_;
};

}  // namespace

BandedIpmOutcome SolveBanded(const TemporalDiscretization& d, const BandedIpmSettings& settings) {
  return BandedIpm(d, settings).Run();
}

}  // namespace timeopt::internal
