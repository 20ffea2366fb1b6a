// The control values of the jerk-limited discretization (ControlBasis in discretization.h;
// BuildControlBasis in discretization_internal.h).
//
// On a regular cell of length L with control polygon P0, P1, P2, b(u) = P0 (1 - u)^2 + 2 P1 u (1 - u)
// + P2 u^2, so sddot = b' / 2 is (P1 - P0) / L at the start and (P2 - P1) / L at the end. Its three
// half-grid values are P0, (P0 + 2 P1 + P2) / 4 and P2. The knots follow from continuity of sddot:
//   between regular cells k - 1 and k:  P = (L_k P1_{k-1} + L_{k-1} P1_k) / (L_{k-1} + L_k);
//   after a rest cell of length L0 (b = w^4 q(w), q = alpha (1 - w) + b1 w in its time fraction w,
//   sddot = (5 b1 - alpha) / (6 L0) at its end; alpha, its middle value, is a control):
//                                       b1 = (alpha / (6 L0) + P1_1 / L1) / (5 / (6 L0) + 1 / L1),
//                                       and its mirror;
//   at a boundary whose sddot a is given: P1 = P0 + a L (start) or P2 - a L (end), a constant;
//   at a joint without a stop, with b after it = rho b before it (rho the ratio of the shared grid
//   value's scales) and the tangential acceleration equal on both sides, |f'+|^2 sddot+ =
//   f'+ . f'- sddot- + f'+ . (f''- - rho f''+) b-:  E (rho / L+ + alpha / L- + beta) =
//   P1+ / L+ + alpha P1- / L-, with alpha and beta the two coefficients over |f'+|^2.
//   at a boundary where the tangent vanishes, b is fixed by the acceleration (acc = f'' b), or is a
//   control of its own where the curvature vanishes too (nothing bounds it but its cell's rows),
//   and P1 is free.
// A ramp cell (b = w^4 q(w), q quadratic in w; temporal_profile.h) has q's middle Bernstein
// coefficient in w as its control, and a knot next to one follows from sddot continuity written
// for each side as lambda b + (a form of that cell's control), whatever the two shapes are.
// A run of tied pieces (TemporalDiscretization::tied): b = b0 + 2 sddot s on each, with b0 and
// sddot carried across each joint by its continuity row from the knot before the run, which is a
// control (read back as the grid value), and the P1 before it; the first P1 after the run follows.
// Every other case (a rest cell next to a rest cell, a boundary without a given sddot or b, a joint
// whose knot is not a positive mean) has no basis here, and the general solvers take the problem.

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "discretization_internal.h"

namespace timeopt::internal {
namespace {

// An affine form over the control values with a few terms (merged by index).
struct Form {
  static constexpr int kMax = 8;
  std::array<std::pair<int, double>, kMax> terms{};
  int n = 0;
  double constant = 0.0;

  static Form Control(int c, double coef) {
    Form f;
    f.terms[0] = {c, coef};
    f.n = 1;
    return f;
  }
  static Form Constant(double v) {
    Form f;
    f.constant = v;
    return f;
  }
  // *this += w * other; false when the terms do not fit.
  bool Add(const Form& other, double w) {
    constant += w * other.constant;
    for (int t = 0; t < other.n; ++t) {
      const auto& [c, v] = other.terms[static_cast<size_t>(t)];
      int i = 0;
      while (i < n && terms[static_cast<size_t>(i)].first != c) ++i;
      if (i == n) {
        if (n == kMax) return false;
        terms[static_cast<size_t>(n++)] = {c, 0.0};
      }
      terms[static_cast<size_t>(i)].second += w * v;
    }
    return true;
  }
  bool IsConstant() const {
    for (int t = 0; t < n; ++t) {
      if (terms[static_cast<size_t>(t)].second != 0.0) return false;
    }
    return true;
  }
};

Form Combine(const Form& a, double wa, const Form& b, double wb, bool* ok) {
  Form out;
  *ok = *ok && out.Add(a, wa) && out.Add(b, wb);
  return out;
}

// The form as a ControlForm (consecutive terms); false when they span more than kMaxTerms.
bool ToControlForm(const Form& f, ControlForm* out) {
  *out = ControlForm();
  out->constant = f.constant;
  int lo = 0, hi = -1;
  for (int t = 0; t < f.n; ++t) {
    const auto& [c, v] = f.terms[static_cast<size_t>(t)];
    if (v == 0.0) continue;
    if (hi < lo) lo = hi = c;
    lo = std::min(lo, c);
    hi = std::max(hi, c);
  }
  if (hi < lo) return true;
  if (hi - lo + 1 > ControlForm::kMaxTerms) return false;
  out->first = lo;
  out->count = hi - lo + 1;
  for (int t = 0; t < f.n; ++t) {
    const auto& [c, v] = f.terms[static_cast<size_t>(t)];
    if (v != 0.0) out->coef[static_cast<size_t>(c - lo)] += v;
  }
  return true;
}

// Whether the basis is the discretization's: its forms give the grid's fixed values, every grid
// value that shares a free value is the same form, every control reads back from the forms, every
// equality row holds identically, and there are as many controls as the equalities leave free.
bool BasisMatchesGrid(const TemporalDiscretization& d, const ControlBasis& basis) {
  // The forms must agree with the grid: a fixed value is a constant equal to it.
  for (size_t g = 0; g < d.grid.size(); ++g) {
    const GridValue& v = d.grid[g];
    const ControlForm& f = basis.grid[g];
    if (v.var < 0 && (f.count != 0 || std::abs(f.constant - v.fixed) > 1e-12 * std::max(1.0, std::abs(v.fixed)))) {
      return false;
    }
  }
  // And they must satisfy every equality row identically (the check that the cases above are
  // the discretization's): x_var = b_g / scale_g.
  std::vector<const ControlForm*> of_var(static_cast<size_t>(d.num_vars), nullptr);
  std::vector<double> var_scale(static_cast<size_t>(d.num_vars), 1.0);
  for (size_t g = 0; g < d.grid.size(); ++g) {
    const GridValue& v = d.grid[g];
    if (v.var >= 0 && of_var[static_cast<size_t>(v.var)] == nullptr) {
      of_var[static_cast<size_t>(v.var)] = &basis.grid[g];
      var_scale[static_cast<size_t>(v.var)] = v.scale;
    }
  }
  for (const ControlForm* f : of_var) {
    if (f == nullptr) return false;
  }
  // Every grid value that shares a free value (a joint) is the same form in x: b_g / scale_g.
  const auto same = [](const ControlForm& a, double sa, const ControlForm& b, double sb) {
    double size = std::abs(a.constant / sa);
    for (int t = 0; t < a.count; ++t) size = std::max(size, std::abs(a.coef[static_cast<size_t>(t)] / sa));
    const double tolerance = 1e-12 * std::max(size, 1e-300);
    if (std::abs(a.constant / sa - b.constant / sb) > tolerance) return false;
    const int lo = std::min(a.count > 0 ? a.first : b.first, b.count > 0 ? b.first : a.first);
    const int hi = std::max(a.first + a.count, b.first + b.count);
    for (int c = lo; c < hi; ++c) {
      const double ca = c >= a.first && c < a.first + a.count ? a.coef[static_cast<size_t>(c - a.first)] / sa : 0.0;
      const double cb = c >= b.first && c < b.first + b.count ? b.coef[static_cast<size_t>(c - b.first)] / sb : 0.0;
      if (std::abs(ca - cb) > tolerance) return false;
    }
    return true;
  };
  for (size_t g = 0; g < d.grid.size(); ++g) {
    const GridValue& v = d.grid[g];
    if (v.var < 0) continue;
    if (!same(basis.grid[g], v.scale, *of_var[static_cast<size_t>(v.var)], var_scale[static_cast<size_t>(v.var)])) {
      return false;
    }
  }
  // Every control is read back from the forms (ControlBasis::FromGrid): the map from y to b is
  // one to one, so no two controls describe the same profile.
  bool ok = true;
  for (int c = 0; c < basis.num_controls; ++c) {
    const size_t g = static_cast<size_t>(basis.middle[static_cast<size_t>(c)]);
    Form read;
    const auto add = [&](size_t grid, double w) {
      const ControlForm& f = basis.grid[grid];
      read.constant += w * f.constant;
      for (int t = 0; t < f.count; ++t)
        ok = ok && read.Add(Form::Control(f.first + t, f.coef[static_cast<size_t>(t)]), w);
    };
    if (basis.at_knot[static_cast<size_t>(c)]) {
      add(g, 1.0);
    } else {
      const std::array<double, 3>& w = basis.read[static_cast<size_t>(c)];
      add(g - 1, w[0]);
      add(g, w[1]);
      add(g + 1, w[2]);
    }
    if (!ok) return false;
    const double scale = basis.scale[static_cast<size_t>(c)];
    if (std::abs(read.constant) > 1e-9 * scale) return false;
    for (int t = 0; t < read.n; ++t) {
      const auto& [control, coef] = read.terms[static_cast<size_t>(t)];
      if (std::abs(coef - (control == c ? scale : 0.0)) > 1e-9 * scale) return false;
    }
  }
  int equalities = 0;
  for (const LinearRow& row : d.rows) {
    if (row.lower != row.upper) continue;
    ++equalities;
    Form sum;
    double size = std::abs(row.lower);
    for (const auto& [var, coef] : row.terms) {
      const ControlForm& f = *of_var[static_cast<size_t>(var)];
      const double w = coef / var_scale[static_cast<size_t>(var)];
      sum.constant += w * f.constant;
      size = std::max(size, std::abs(w * f.constant));
      for (int t = 0; t < f.count; ++t) {
        Form one = Form::Control(f.first + t, w * f.coef[static_cast<size_t>(t)]);
        size = std::max(size, std::abs(one.terms[0].second));
        if (!sum.Add(one, 1.0)) return false;
      }
    }
    const double tolerance = 1e-9 * std::max(size, 1e-300);
    if (std::abs(sum.constant - row.lower) > tolerance) return false;
    for (int t = 0; t < sum.n; ++t) {
      if (std::abs(sum.terms[static_cast<size_t>(t)].second) > tolerance) return false;
    }
  }
  // As many controls as the equalities leave free: with the controls independent (above) and the
  // equality rows too (each fixes a new value along the path), the basis spans every profile of
  // the grid. A count that differs either way leaves the problem to the general path.
  return basis.num_controls + equalities == d.num_vars;
}

}  // namespace

std::optional<ControlBasis> BuildControlBasis(const TemporalProblem& problem, const TemporalDiscretization& d,
                                              const std::optional<double> (&boundary_sddot)[2],
                                              const std::optional<double> (&boundary_b)[2]) {
  const int m = d.num_pieces;
  const int K = static_cast<int>(d.shapes.size()) / std::max(m, 1);
  if (m <= 0 || K <= 0 || static_cast<int>(d.shapes.size()) != m * K) return std::nullopt;
  const auto shape = [&](int i, int k) { return d.shapes[static_cast<size_t>(i * K + k)]; };
  const auto len = [&](int i, int k) {
    const std::vector<double>& e = d.cell_edges[static_cast<size_t>(i)];
    return e[static_cast<size_t>(k) + 1] - e[static_cast<size_t>(k)];
  };
  const auto grid = [&](int i, int j) -> const GridValue& { return d.grid[static_cast<size_t>(d.GridIndex(i, j))]; };

  ControlBasis basis;
  bool ok = true;
  // P1 of every regular cell (path order) and the knots of every piece.
  std::vector<Form> p1(static_cast<size_t>(m * K));
  std::vector<bool> has_p1(static_cast<size_t>(m * K), false);
  // The middle value of every rest cell (q at its rest point), a control of its own.
  std::vector<Form> alpha(static_cast<size_t>(m * K));
  // A boundary value bound by nothing (tangent and curvature vanish: no row fixes b) is a control
  // of its own, before the first P1 or after the last.
  Form free_boundary[2];
  const auto add_free_boundary = [&](int end) {
    const int g = end == 0 ? d.GridIndex(0, 0) : d.GridIndex(m - 1, 2 * K);
    const GridValue& v = d.grid[static_cast<size_t>(g)];
    if (v.var < 0 || boundary_b[end] || !(v.scale > 0.0)) return;
    free_boundary[end] = Form::Control(basis.num_controls++, v.scale);
    basis.middle.push_back(g);
    basis.at_knot.push_back(1);
    basis.scale.push_back(v.scale);
    basis.read.push_back({0.0, 1.0, 0.0});
  };
  add_free_boundary(0);
  const auto tied = [&](int i) { return i >= 0 && i < m && !d.tied.empty() && d.tied[static_cast<size_t>(i)] != 0; };
  std::vector<Form> run_entry(static_cast<size_t>(m));  // the knot before a run, at its first piece
  for (int i = 0; i < m; ++i) {
    if (tied(i)) {
      if (i == 0 || i == m - 1) return std::nullopt;
      if (!tied(i - 1)) {
        const int g = d.GridIndex(i - 1, 2 * K);
        const GridValue& v = d.grid[static_cast<size_t>(g)];
        if (v.var < 0 || !(v.scale > 0.0)) return std::nullopt;
        run_entry[static_cast<size_t>(i)] = Form::Control(basis.num_controls++, v.scale);
        basis.middle.push_back(g);
        basis.at_knot.push_back(1);
        basis.scale.push_back(v.scale);
        basis.read.push_back({0.0, 1.0, 0.0});
      }
      continue;
    }
    for (int k = 0; k < K; ++k) {
      if (k == 0 && tied(i - 1)) {
        // The first P1 after a run follows from it (below).
        if (shape(i, 0) != CellShape::kQuadratic || (i == m - 1 && K == 1)) return std::nullopt;
        continue;
      }
      if (IsRampShape(shape(i, k))) {
        // q's middle Bernstein coefficient, scaled as q at the middle (rho_m b_mid).
        const int g = d.GridIndex(i, 2 * k + 1);
        const GridValue& mid = d.grid[static_cast<size_t>(g)];
        if (mid.var < 0 || !(mid.scale > 0.0)) return std::nullopt;
        const RampFrame fr = RampFrameOf(d, i, k);
        const double scale = mid.scale * fr.rho[1];
        p1[static_cast<size_t>(i * K + k)] = Form::Control(basis.num_controls++, scale);
        has_p1[static_cast<size_t>(i * K + k)] = true;
        basis.middle.push_back(g);
        basis.at_knot.push_back(0);
        basis.scale.push_back(scale);
        basis.read.push_back({-0.5 * fr.rho[0], 2.0 * fr.rho[1], -0.5 * fr.rho[2]});
        continue;
      }
      if (shape(i, k) != CellShape::kQuadratic) {
        const int g = d.GridIndex(i, 2 * k + 1);
        const GridValue& mid = d.grid[static_cast<size_t>(g)];
        if (mid.var < 0 || !(mid.scale > 0.0)) return std::nullopt;
        alpha[static_cast<size_t>(i * K + k)] = Form::Control(basis.num_controls++, mid.scale);
        basis.middle.push_back(g);
        basis.at_knot.push_back(1);  // read back as the grid value itself
        basis.scale.push_back(mid.scale);
        basis.read.push_back({0.0, 1.0, 0.0});
        continue;
      }
      Form& f = p1[static_cast<size_t>(i * K + k)];
      has_p1[static_cast<size_t>(i * K + k)] = true;
      const bool first = i == 0 && k == 0, last = i == m - 1 && k == K - 1;
      if (first && grid(0, 0).var < 0) {
        if (!boundary_sddot[0]) return std::nullopt;
        f = Form::Constant(grid(0, 0).fixed + *boundary_sddot[0] * len(i, k));
        continue;
      }
      if (last && grid(m - 1, 2 * K).var < 0) {
        if (!boundary_sddot[1]) return std::nullopt;
        f = Form::Constant(grid(m - 1, 2 * K).fixed - *boundary_sddot[1] * len(i, k));
        continue;
      }
      // A boundary value that is free (a vanishing tangent) leaves this P1 free like any other.
      const GridValue& mid = grid(i, 2 * k + 1);
      if (mid.var < 0 || !(mid.scale > 0.0)) return std::nullopt;
      f = Form::Control(basis.num_controls++, mid.scale);
      basis.middle.push_back(d.GridIndex(i, 2 * k + 1));
      basis.at_knot.push_back(0);
      basis.scale.push_back(mid.scale);
      basis.read.push_back({-0.5, 2.0, -0.5});
    }
  }
  add_free_boundary(1);
  // Knot k of piece i (k = 0..K), in b.
  std::vector<Form> knot(static_cast<size_t>(m * (K + 1)));
  const auto knot_at = [&](int i, int k) -> Form& { return knot[static_cast<size_t>(i * (K + 1) + k)]; };
  const auto P1 = [&](int i, int k) -> const Form* {
    return has_p1[static_cast<size_t>(i * K + k)] ? &p1[static_cast<size_t>(i * K + k)] : nullptr;
  };
  // The continuity row of the joint after piece i, b+ = rho b- and sddot+ = alpha sddot- + beta b-
  // (the header comment); false where the joint has no shared free value.
  struct JointRow {
    double rho = 1.0, alpha = 0.0, beta = 0.0;
  };
  const auto joint_row = [&](int i, JointRow* out) {
    const GridValue& g = grid(i, 2 * K);
    const GridValue& next = grid(i + 1, 0);
    if (g.var < 0 || next.var != g.var || !(g.scale > 0.0)) return false;
    out->rho = next.scale / g.scale;
    const Eigen::Vector3d f1a = problem.curve.Evaluate(i, 1.0, 1), f1b = problem.curve.Evaluate(i + 1, 0.0, 1);
    const Eigen::Vector3d f2a = problem.curve.Evaluate(i, 1.0, 2), f2b = problem.curve.Evaluate(i + 1, 0.0, 2);
    const double n2 = f1b.squaredNorm();
    if (!(n2 > 0.0)) return false;
    out->alpha = f1b.dot(f1a) / n2;
    out->beta = f1b.dot(f2a - out->rho * f2b) / n2;
    return true;
  };
  // Across the joint after piece i, where b is `before_b` and sddot `before_sddot` before it.
  const auto across = [&](int i, const Form& before_b, const Form& before_sddot, Form* after_b, Form* after_sddot) {
    JointRow row;
    if (!joint_row(i, &row)) return false;
    *after_sddot = Combine(before_sddot, row.alpha, before_b, row.beta, &ok);
    *after_b = Form();
    ok = ok && after_b->Add(before_b, row.rho);
    return true;
  };
  for (int i = 0; i < m; ++i) {
    if (tied(i)) continue;  // set with the piece before its run
    for (int k = 0; k <= K; ++k) {
      const GridValue& g = grid(i, 2 * k);
      Form& f = knot_at(i, k);
      const bool piece_start = k == 0, piece_end = k == K;
      if ((piece_start || piece_end) && g.var < 0) {
        f = Form::Constant(g.fixed);
        continue;
      }
      if ((i == 0 && piece_start) || (i == m - 1 && piece_end)) {
        // A boundary whose tangent vanishes: b fixed by the acceleration, or free.
        const int end = piece_start ? 0 : 1;
        f = boundary_b[end] ? Form::Constant(*boundary_b[end]) : free_boundary[end];
        continue;
      }
      if (piece_start) continue;  // a shared value at a joint: set with the previous piece's end
      if (piece_end && tied(i + 1)) {
        const Form* before = P1(i, K - 1);
        if (before == nullptr) return std::nullopt;
        f = run_entry[static_cast<size_t>(i + 1)];
        Form b_end = f, sddot = Combine(f, 1.0 / len(i, K - 1), *before, -1.0 / len(i, K - 1), &ok);
        int j = i + 1;
        for (; tied(j); ++j) {
          Form start, slope;
          if (!across(j - 1, b_end, sddot, &start, &slope)) return std::nullopt;
          const std::vector<double>& edges = d.cell_edges[static_cast<size_t>(j)];
          for (int e = 0; e <= K; ++e) {
            knot_at(j, e) = Combine(start, 1.0, slope, 2.0 * edges[static_cast<size_t>(e)], &ok);
          }
          for (int e = 0; e < K; ++e) {
            p1[static_cast<size_t>(j * K + e)] = Combine(knot_at(j, e), 0.5, knot_at(j, e + 1), 0.5, &ok);
            has_p1[static_cast<size_t>(j * K + e)] = true;
          }
          b_end = knot_at(j, K);
          sddot = slope;
        }
        // The first cell after the run: its knot and P1 = knot + L sddot.
        Form start, slope;
        if (j >= m || !across(j - 1, b_end, sddot, &start, &slope)) return std::nullopt;
        knot_at(j, 0) = start;
        p1[static_cast<size_t>(j * K)] = Combine(start, 1.0, slope, len(j, 0), &ok);
        has_p1[static_cast<size_t>(j * K)] = true;
        continue;
      }
      if (piece_end) {
        // A joint without a stop (its value is a free variable shared with the next piece).
        if (i + 1 >= m) return std::nullopt;
        const Form* before = P1(i, K - 1);
        const Form* after = P1(i + 1, 0);
        JointRow row;
        if (before == nullptr || after == nullptr || !joint_row(i, &row)) return std::nullopt;
        const double la = len(i, K - 1), lb = len(i + 1, 0);
        const double denominator = row.rho / lb + row.alpha / la + row.beta;
        if (!(row.alpha > 0.0) || !(denominator > 0.0)) return std::nullopt;
        f = Combine(*before, row.alpha / la / denominator, *after, 1.0 / lb / denominator, &ok);
        Form& shared = knot_at(i + 1, 0);
        shared = Form();
        ok = ok && shared.Add(f, row.rho);
        continue;
      }
      // An interior knot.
      const CellShape left = shape(i, k - 1), right = shape(i, k);
      if (left == CellShape::kQuadratic && right == CellShape::kQuadratic) {
        const double l0 = len(i, k - 1), l1 = len(i, k);
        f = Combine(*P1(i, k - 1), l1 / (l0 + l1), *P1(i, k), l0 / (l0 + l1), &ok);
      } else if (left == CellShape::kRestStart && right == CellShape::kQuadratic) {
        // (5 b1 - alpha) / (6 L0) = (P1 - b1) / L1.
        const double l0 = len(i, k - 1), l1 = len(i, k), denominator = 5.0 / (6.0 * l0) + 1.0 / l1;
        f = Combine(alpha[static_cast<size_t>(i * K + k - 1)], 1.0 / (6.0 * l0) / denominator, *P1(i, k),
                    1.0 / l1 / denominator, &ok);
      } else if (left == CellShape::kQuadratic && right == CellShape::kRestEnd) {
        // The mirror: (b0 - P1) / L1 = -(5 b0 - alpha) / (6 L0).
        const double l1 = len(i, k - 1), l0 = len(i, k), denominator = 5.0 / (6.0 * l0) + 1.0 / l1;
        f = Combine(*P1(i, k - 1), 1.0 / l1 / denominator, alpha[static_cast<size_t>(i * K + k)],
                    1.0 / (6.0 * l0) / denominator, &ok);
      } else if (IsRampShape(left) || IsRampShape(right)) {
        // sddot on each side as lambda b + F (F a form of that cell's control): b = (F_right -
        // F_left) / (lambda_left - lambda_right).
        double lambda[2];
        Form F[2];
        const bool fits = [&] {
          for (int side = 0; side < 2; ++side) {
            const int cell = k - 1 + side;
            const CellShape sh = shape(i, cell);
            const bool at_end = side == 0;  // the knot is the left cell's end, the right cell's start
            const double L = len(i, cell);
            const Form* own = P1(i, cell);
            if (sh == CellShape::kQuadratic) {
              if (own == nullptr) return false;
              lambda[side] = at_end ? 1.0 / L : -1.0 / L;
              F[side] = Form();
              ok = ok && F[side].Add(*own, at_end ? -1.0 / L : 1.0 / L);
            } else if ((sh == CellShape::kRestStart && at_end) || (sh == CellShape::kRestEnd && !at_end)) {
              // (5 b - alpha) / (6 L), braking towards a rest end.
              const double sign = at_end ? 1.0 : -1.0;
              lambda[side] = sign * 5.0 / (6.0 * L);
              F[side] = Form();
              ok = ok && F[side].Add(alpha[static_cast<size_t>(i * K + cell)], -sign / (6.0 * L));
            } else if (IsRampShape(sh)) {
              // eps w (4 Q + w (dq/du) / dw) / 6 with Q = rho b, dq/du = 2 (P1 - Q) at the start and
              // 2 (Q - P1) at the end.
              if (own == nullptr) return false;
              const RampFrame fr = RampFrameOf(d, i, cell);
              const int e = at_end ? 2 : 0;
              const double w = fr.w[e], r = fr.rho[e], sign = at_end ? 1.0 : -1.0;
              lambda[side] = fr.eps * w * r * (4.0 + sign * 2.0 * w / fr.dw) / 6.0;
              F[side] = Form();
              ok = ok && F[side].Add(*own, -sign * fr.eps * w * w / (3.0 * fr.dw));
            } else {
              return false;
            }
          }
          return true;
        }();
        const double denominator = lambda[0] - lambda[1];
        if (!fits || !(denominator > 0.0)) return std::nullopt;
        f = Combine(F[1], 1.0 / denominator, F[0], -1.0 / denominator, &ok);
      } else {
        return std::nullopt;
      }
    }
  }
  if (!ok) return std::nullopt;
  // Every half-grid value.
  basis.grid.resize(d.grid.size());
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < K; ++k) {
      const Form& a = knot_at(i, k);
      const Form& b = knot_at(i, k + 1);
      Form middle;
      switch (shape(i, k)) {
        case CellShape::kQuadratic:
          ok = ok && middle.Add(a, 0.25) && middle.Add(*P1(i, k), 0.5) && middle.Add(b, 0.25);
          break;
        case CellShape::kRestStart:
        case CellShape::kRestEnd:
          ok = ok && middle.Add(alpha[static_cast<size_t>(i * K + k)], 1.0);
          break;
        case CellShape::kRampStart:
        case CellShape::kRampEnd: {
          // b_mid = q(1/2) / rho_m, q(1/2) = (rho_0 b_0 + 2 P1 + rho_2 b_2) / 4.
          const RampFrame fr = RampFrameOf(d, i, k);
          const double m = 1.0 / fr.rho[1];
          ok = ok && middle.Add(a, 0.25 * fr.rho[0] * m) && middle.Add(*P1(i, k), 0.5 * m) &&
               middle.Add(b, 0.25 * fr.rho[2] * m);
          break;
        }
        case CellShape::kLinear:  // not a shape of the jerk-limited grid
          return std::nullopt;
      }
      ok = ok && ToControlForm(a, &basis.grid[static_cast<size_t>(d.GridIndex(i, 2 * k))]) &&
           ToControlForm(middle, &basis.grid[static_cast<size_t>(d.GridIndex(i, 2 * k + 1))]) &&
           ToControlForm(b, &basis.grid[static_cast<size_t>(d.GridIndex(i, 2 * k + 2))]);
    }
  }
  if (!ok || basis.num_controls == 0) return std::nullopt;
  if (!BasisMatchesGrid(d, basis)) return std::nullopt;
  return basis;
}

}  // namespace timeopt::internal
