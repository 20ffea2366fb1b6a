// Reachability along the path (reachability.h).

#include "reachability.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace timeopt::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A line a x + b y <= h of a cell's polygon.
struct Line {
  double a, b, h;
};

// The smallest and largest x over the polygon of `lines` (bounded by its box), by its vertices:
// false if it is empty.
bool ExtremesOfX(const std::vector<Line>& lines, double* lo, double* hi) {
  double best_hi = -kInf, best_lo = kInf;
  for (size_t i = 0; i < lines.size(); ++i) {
    for (size_t j = i + 1; j < lines.size(); ++j) {
      const double det = lines[i].a * lines[j].b - lines[j].a * lines[i].b;
      if (!(std::abs(det) > 1e-12 * (std::abs(lines[i].a * lines[j].b) + std::abs(lines[j].a * lines[i].b)))) continue;
      const double x = (lines[i].h * lines[j].b - lines[j].h * lines[i].b) / det;
      const double y = (lines[i].a * lines[j].h - lines[j].a * lines[i].h) / det;
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      bool feasible = true;
      for (const Line& q : lines) {
        if (q.a * x + q.b * y > q.h + 1e-12 * (1.0 + std::abs(q.h))) {
          feasible = false;
          break;
        }
      }
      if (!feasible) continue;
      best_hi = std::max(best_hi, x);
      best_lo = std::min(best_lo, x);
    }
  }
  *lo = best_lo;
  *hi = best_hi;
  return best_hi >= best_lo;
}

}  // namespace

bool ChainRows::Add(int v0, double c0, int v1, double c1, double h) {
  if (c1 == 0.0 || v1 == v0) {
    const double c = c0 + (v1 == v0 ? c1 : 0.0);
    if (c > 0.0)
      u[static_cast<size_t>(v0)] = std::min(u[static_cast<size_t>(v0)], h / c);
    else if (c < 0.0)
      l[static_cast<size_t>(v0)] = std::max(l[static_cast<size_t>(v0)], h / c);
    return true;
  }
  if (c0 == 0.0) return Add(v1, c1, v1, 0.0, h);
  if (std::abs(v1 - v0) != 1) return false;
  if (v0 < v1)
    pairs[static_cast<size_t>(v0)].push_back({c0, c1, h});
  else
    pairs[static_cast<size_t>(v1)].push_back({c1, c0, h});
  return true;
}

bool ChainRows::CapUnbounded() {
  double largest = 0.0;
  for (double b : u) {
    if (b < kUnbounded) largest = std::max(largest, b);
  }
  const double cap = largest > 0.0 ? 1e3 * largest : 1.0;
  for (size_t v = 0; v < u.size(); ++v) {
    if (!(u[v] < kUnbounded)) u[v] = std::max(cap, l[v]);
    if (l[v] > u[v]) return false;
  }
  return true;
}

bool ChainFromDiscretization(const TemporalDiscretization& d, ChainRows* chain) {
  if (!d.cubic_rows.empty() || !d.cone_rows.empty()) return false;
  ChainRows& c = *chain;
  c = ChainRows(d.num_vars);
  for (int v = 0; v < d.num_vars; ++v) {
    if (std::isfinite(d.var_upper[static_cast<size_t>(v)])) c.Add(v, 1.0, v, 0.0, d.var_upper[static_cast<size_t>(v)]);
  }
  for (const LinearRow& r : d.rows) {
    if (r.lower == r.upper || r.terms.empty() || r.terms.size() > 2) return false;
    const int v0 = r.terms[0].first, v1 = r.terms.size() == 2 ? r.terms[1].first : v0;
    const double c0 = r.terms[0].second, c1 = r.terms.size() == 2 ? r.terms[1].second : 0.0;
    if (std::isfinite(r.upper) && !c.Add(v0, c0, v1, c1, r.upper)) return false;
    if (std::isfinite(r.lower) && !c.Add(v0, -c0, v1, -c1, -r.lower)) return false;
  }
  return c.CapUnbounded();
}

int ControllableSets(const ChainRows& c, std::vector<double>* lo_out, std::vector<double>* hi_out) {
  const int n = c.size();
  std::vector<double>& lo = *lo_out;
  std::vector<double>& hi = *hi_out;
  lo = c.l;
  hi = c.u;
  if (n == 0) return -1;
  if (lo.back() > hi.back()) return n - 1;
  std::vector<Line> lines;
  for (int v = n - 2; v >= 0; --v) {
    // The polygon of (x_v, x_{v+1}): its rows and the box; the extremes of x_v over it.
    lines.clear();
    for (const ChainRows::Pair& p : c.pairs[static_cast<size_t>(v)]) lines.push_back({p.a, p.b, p.h});
    lines.push_back({1.0, 0.0, c.u[static_cast<size_t>(v)]});
    lines.push_back({-1.0, 0.0, -c.l[static_cast<size_t>(v)]});
    lines.push_back({0.0, 1.0, hi[static_cast<size_t>(v) + 1]});
    lines.push_back({0.0, -1.0, -lo[static_cast<size_t>(v) + 1]});
    double x_lo = 0.0, x_hi = 0.0;
    if (!ExtremesOfX(lines, &x_lo, &x_hi)) return v;
    lo[static_cast<size_t>(v)] = std::max(c.l[static_cast<size_t>(v)], x_lo);
    hi[static_cast<size_t>(v)] = std::min(c.u[static_cast<size_t>(v)], x_hi);
    if (lo[static_cast<size_t>(v)] > hi[static_cast<size_t>(v)]) return v;
  }
  return -1;
}

std::vector<double> GreedyForward(const ChainRows& c, const std::vector<double>& lo, const std::vector<double>& hi,
                                  double start) {
  const int n = c.size();
  std::vector<double> x(static_cast<size_t>(n), 0.0);
  if (n == 0) return x;
  x[0] = start;
  for (int v = 1; v < n; ++v) {
    double top = hi[static_cast<size_t>(v)];
    const double prev = x[static_cast<size_t>(v) - 1];
    for (const ChainRows::Pair& p : c.pairs[static_cast<size_t>(v) - 1]) {
      if (p.b > 0.0) top = std::min(top, (p.h - p.a * prev) / p.b);
    }
    x[static_cast<size_t>(v)] = std::max(top, lo[static_cast<size_t>(v)]);
  }
  return x;
}

int BrakingFailure(const ChainRows& c, double start) {
  const int n = c.size();
  double prev = start;
  for (int v = 1; v < n; ++v) {
    double bottom = c.l[static_cast<size_t>(v)], top = c.u[static_cast<size_t>(v)];
    for (const ChainRows::Pair& p : c.pairs[static_cast<size_t>(v) - 1]) {
      if (p.b < 0.0) bottom = std::max(bottom, (p.h - p.a * prev) / p.b);
      if (p.b > 0.0) top = std::min(top, (p.h - p.a * prev) / p.b);
    }
    if (bottom > top + 1e-12 * (1.0 + std::abs(top))) return v;
    prev = bottom;
  }
  return -1;
}

}  // namespace timeopt::internal
