// The structured path's problem (banded_ipm.h): rows over the unknowns (the free values, or the
// control values of a jerk-limited grid), scaled to a bound of +-1, and the cells' time terms as
// forms in the unknowns; BuildBandedProblem writes it from a discretization. The interior point
// that solves it is in banded_ipm.cpp.

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "banded_ipm.h"
#include "discretization_internal.h"

namespace timeopt::internal {

bool BandedProblem::AddRow(const std::vector<std::pair<int, double>>& terms, double sign, double bound,
                           bool is_essential) {
  BandedRow row;
  row.kind = static_cast<short>(kind);
  double constant = 0.0;
  int lo = n, hi = -1;
  for (const auto& [var, coef] : terms) {
    const ControlForm& f = x_form[static_cast<size_t>(var)];
    constant += coef * f.constant;
    if (f.count > 0) {
      lo = std::min(lo, f.first);
      hi = std::max(hi, f.first + f.count - 1);
    }
  }
  if (hi < lo) return sign * constant <= sign * bound + 1e-9 * std::max(1.0, std::abs(bound));
  if (hi - lo + 1 > kMaxRowSpan) return false;
  row.first = lo;
  row.count = static_cast<short>(hi - lo + 1);
  for (const auto& [var, coef] : terms) {
    const ControlForm& f = x_form[static_cast<size_t>(var)];
    for (int t = 0; t < f.count; ++t) row.v[f.first + t - lo] += coef * f.coef[static_cast<size_t>(t)];
  }
  bound -= constant;
  // A row sign v.y <= sign bound with sign v <= 0 and sign bound >= 0 holds wherever y >= 0 (the
  // bound rows, which come first and stay in every solve): left out, unless it must stay (on the
  // jerk-limited grid, the rows b >= 0 of each cell are these: a quarter of d's rows).
  if (!is_essential && sign * bound >= 0.0) {
    bool implied = true;
    for (int t = 0; t < row.count && implied; ++t) implied = sign * row.v[t] <= 0.0;
    if (implied) return true;
  }
  double scale = std::abs(bound);
  if (!(scale > 0.0)) {
    for (int t = 0; t < row.count; ++t) scale = std::max(scale, std::abs(row.v[t]));
  }
  if (!(scale > 0.0)) scale = 1.0;
  for (int t = 0; t < row.count; ++t) row.v[t] *= sign / scale;
  rows.push_back(row);
  h.push_back(sign * bound / scale);
  essential.push_back(is_essential || !(h.back() > 0.0) ? 1 : 0);
  id.push_back(next_id >= 0 ? next_id : static_cast<int>(rows.size()) - 1);
  return true;
}

void BandedProblem::Reserve(size_t count) {
  rows.reserve(count);
  h.reserve(count);
  essential.reserve(count);
  id.reserve(count);
}

void BandedProblem::Clear() {
  n = 0;
  bandwidth = 1;
  controls = false;
  rows.clear();
  h.clear();
  cap.clear();
  cells.clear();
  grid_form.clear();
  x_form.clear();
  essential.clear();
  id.clear();
  next_id = -1;
  kind = -1;
}

bool BandedProblem::AppendRow(int first, int count, const double (&v)[kMaxRowSpan], double bound) {
  if (count == 0) return bound >= -1e-9;
  double scale = std::abs(bound);
  if (!(scale > 0.0)) {
    for (int t = 0; t < count; ++t) scale = std::max(scale, std::abs(v[t]));
  }
  if (!(scale > 0.0)) scale = 1.0;
  const double inverse = 1.0 / scale;
  // Written in place (a row passed by value through the stack and read back whole stalled on
  // store forwarding: 7% of a jerk-limited solve).
  BandedRow& row = rows.emplace_back();
  row.first = first;
  row.count = static_cast<short>(count);
  row.kind = static_cast<short>(kind);
  for (int t = 0; t < kMaxRowSpan; ++t) row.v[t] = v[t] * inverse;
  const double scaled = bound * inverse;
  h.push_back(scaled);
  essential.push_back(!(scaled > 0.0) ? 1 : 0);
  id.push_back(next_id >= 0 ? next_id : static_cast<int>(rows.size()) - 1);
  return true;
}

bool BandedProblem::MapCell(int g0, CellMap* map) const {
  *map = CellMap();
  int lo = n, hi = -1;
  for (int j = 0; j < 3; ++j) {
    const ControlForm& f = grid_form[static_cast<size_t>(g0 + j)];
    map->constant[j] = f.constant;
    if (f.count > 0) {
      lo = std::min(lo, f.first);
      hi = std::max(hi, f.first + f.count - 1);
    }
  }
  if (hi < lo) return true;
  if (hi - lo + 1 > kMaxRowSpan) return false;
  map->first = lo;
  map->count = hi - lo + 1;
  for (int j = 0; j < 3; ++j) {
    const ControlForm& f = grid_form[static_cast<size_t>(g0 + j)];
    for (int t = 0; t < f.count; ++t) map->m[j][f.first - lo + t] = f.coef[static_cast<size_t>(t)];
  }
  return true;
}

bool BandedProblem::AddCellRow(const CellMap& map, const double* coef, double bound) {
  const double c0 = coef[0], c1 = coef[1], c2 = coef[2];
  bound -= c0 * map.constant[0];
  bound -= c1 * map.constant[1];
  bound -= c2 * map.constant[2];
  // Each term in one expression (summed through v in memory, the loop did not vectorize).
  double v[kMaxRowSpan];
  for (int t = 0; t < kMaxRowSpan; ++t) v[t] = c0 * map.m[0][t] + c1 * map.m[1][t] + c2 * map.m[2][t];
  // Terms that cancel leave the window as it is: a zero coefficient costs nothing.
  return AppendRow(map.first, map.count, v, bound);
}

bool BuildBandedProblem(const TemporalDiscretization& d, BandedProblem* out, std::string* why) {
  BandedProblem& p = *out;
  p.Clear();
  p.controls = d.controls.has_value();
  p.n = p.controls ? d.controls->num_controls : d.num_vars;
  if (p.n <= 0 || d.num_vars <= 0) {
    *why = "no free values";
    return false;
  }
  if (!d.cone_rows.empty() || !d.cubic_rows.empty()) {
    *why = "cone or cubic rows";
    return false;
  }
  // b at every grid value and x at every free value, as forms in the unknowns.
  p.grid_form.resize(d.grid.size());
  p.x_form.assign(static_cast<size_t>(d.num_vars), ControlForm());
  std::vector<char> x_set(static_cast<size_t>(d.num_vars), 0);
  for (size_t g = 0; g < d.grid.size(); ++g) {
    const GridValue& v = d.grid[g];
    ControlForm f;
    if (p.controls) {
      f = d.controls->grid[g];
    } else if (v.var >= 0) {
      f.first = v.var;
      f.count = 1;
      f.coef[0] = v.scale;
    } else {
      f.constant = v.fixed;
    }
    p.grid_form[g] = f;
    if (v.var >= 0 && !x_set[static_cast<size_t>(v.var)]) {
      x_set[static_cast<size_t>(v.var)] = 1;
      ControlForm& x = p.x_form[static_cast<size_t>(v.var)];
      x = f;
      x.constant /= v.scale;
      for (int t = 0; t < x.count; ++t) x.coef[static_cast<size_t>(t)] /= v.scale;
    }
  }
  // Each unknown's cap for the start: the upper bound of its free value (of its cell's middle for a
  // control value), or the largest finite one (but the cap near a vanishing tangent, which is no
  // measure of the speeds elsewhere).
  double cap = 0.0;
  for (double u : d.var_upper) {
    if (std::isfinite(u) && u < kSlowTangentCap) cap = std::max(cap, u);
  }
  if (!(cap > 0.0)) cap = 1.0;
  p.cap.assign(static_cast<size_t>(p.n), cap);
  for (int v = 0; v < p.n; ++v) {
    const int var = p.controls ? d.grid[static_cast<size_t>(d.controls->middle[static_cast<size_t>(v)])].var : v;
    if (var >= 0) p.cap[static_cast<size_t>(v)] = std::min(d.var_upper[static_cast<size_t>(var)], cap);
  }
  // Bound rows first: row v is -y_v <= 0 (the start keeps their residual at 0).
  for (int v = 0; v < p.n; ++v) {
    BandedRow row;
    row.first = v;
    row.count = 1;
    row.v[0] = -1.0;
    p.rows.push_back(row);
    p.h.push_back(0.0);
    p.essential.push_back(1);
    p.id.push_back(v);
  }
  bool fits = true;
  std::vector<std::pair<int, double>> single(1);
  if (p.controls) {
    // x >= 0 where the forms' signs do not already imply it.
    for (int v = 0; v < d.num_vars; ++v) {
      const ControlForm& f = p.x_form[static_cast<size_t>(v)];
      bool implied = f.constant >= 0.0;
      for (int t = 0; t < f.count; ++t) implied = implied && f.coef[static_cast<size_t>(t)] >= 0.0;
      single[0] = {v, 1.0};
      if (!implied) fits = p.AddRow(single, -1.0, 0.0) && fits;
    }
  }
  for (const LinearRow& r : d.rows) {
    if (r.lower == r.upper) {
      // The control values satisfy every equality row by construction (checked when d.controls
      // was built); the free values do not.
      if (p.controls) continue;
      *why = "equality rows";
      return false;
    }
    p.kind = static_cast<int>(r.kind);
    if (std::isfinite(r.upper)) fits = p.AddRow(r.terms, 1.0, r.upper) && fits;
    if (std::isfinite(r.lower)) fits = p.AddRow(r.terms, -1.0, r.lower) && fits;
    p.kind = -1;
  }
  p.kind = kCapKind;
  for (int v = 0; v < d.num_vars; ++v) {
    single[0] = {v, 1.0};
    if (std::isfinite(d.var_upper[static_cast<size_t>(v)]))
      fits = p.AddRow(single, 1.0, d.var_upper[static_cast<size_t>(v)], !p.controls) && fits;
  }
  p.kind = -1;
  if (!fits) {
    *why = "a row over more than four unknowns, or a constant row violated";
    return false;
  }
  if (!p.controls) {
    // Without the reachability start (which needs these rows) the method took 37-75 iterations
    // where the conic solver takes 15-26 (lambda_a's rows over three values), so it stops here.
    for (const BandedRow& row : p.rows) {
      if (row.count > 2) {
        *why = "a row over more than two neighbouring values";
        return false;
      }
    }
  }
  int bandwidth = 1;
  for (const BandedRow& row : p.rows) bandwidth = std::max(bandwidth, row.count - 1);
  for (const Cell& cell : d.cells) {
    if (cell.time_weight == 0.0 && d.rho == 0.0) continue;  // no time, no regularization (a rest cell's half)
    BandedCell c;
    for (int j = 0; j < 2; ++j) c.b[j] = p.grid_form[static_cast<size_t>(cell.first_grid + j)];
    if (c.b[0].count == 0 && c.b[1].count == 0 && !(c.b[0].constant + c.b[1].constant > 0.0)) {
      *why = "a cell whose speed is fixed at 0 at both ends";
      return false;
    }
    c.c = 2.0 * cell.ds * cell.time_weight;
    c.reg = d.rho / (4.0 * cell.ds);
    int lo = p.n, hi = -1;
    for (const ControlForm& f : c.b) {
      if (f.count == 0) continue;
      lo = std::min(lo, f.first);
      hi = std::max(hi, f.first + f.count - 1);
    }
    if (hi >= lo) bandwidth = std::max(bandwidth, hi - lo);
    p.cells.push_back(c);
  }
  p.bandwidth = bandwidth;
  return true;
}

}  // namespace timeopt::internal
