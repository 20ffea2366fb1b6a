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
// finite at every iterate. Over control values (jerk-limited mode) b is an affine form of y,
// positive wherever the forms' signs imply it; where one has a negative constant (a start braking
// hard), an iterate that reaches b <= 0 breaks the Newton system and the caller's general path
// decides.

#include "banded_ipm.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "reachability.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
// The row passes also in AVX2 and FMA, taken where the processor has them (GCC and Clang on
// x86-64; banded_ipm_rows.inc).
#if defined(__x86_64__) && defined(__GNUC__)
#define TIMEOPT_AVX2_ROWS 1
#include <immintrin.h>
#else
#define TIMEOPT_AVX2_ROWS 0
#endif

namespace timeopt::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The fraction of the step to the boundary of s, z >= 0 that is taken.
constexpr double kStepFraction = 0.99;
// A corrector step that would raise s'z above kGapGrowth times its value is taken again without
// Mehrotra's second-order term ds_a o dz_a (a centring step). After a blocked predictor that term
// can swamp the direction: on slow minimum-jerk curves (both end tangents vanish, b held by its
// cap next to the ends) a step of 0.008 raised the gap tenfold, and the iterates went round a
// cycle of 8 steps, the gap stuck at 3e-6 of J, until the iteration limit. With the test they end
// optimal in 12-13 iterations, T within 6e-11 of Ipopt's (sweep problems 2247, 5253, 7827, 8319).
// Leaving the term out whenever the predictor's step was below 0.02 instead did as well there, but
// slowed the hardest known cases (tests/temporal/data/time_allocated_*.json, whose predictor steps
// are often 1e-3 to 1e-2) from 55 and 47 iterations to the limit of 60. (The conic solver stalls on
// those four too, for another reason: the same rule there did not help.)
constexpr double kGapGrowth = 2.0;
// The start: x0 = kGreedyWeight times the reachability profile (GreedyProfile, feasible and close
// to the optimum) plus the rest times a uniformly scaled-down one (strictly inside every row that
// holds at 0), and multipliers with s'z = kStartGap J(x0). Measured on the benchmark's curves
// (m = 10, K = 50): 12 iterations with 0.9 and 0.1; weights 0.5-0.95 and gaps 0.01-1 took 11-17;
// the scaled-down start alone took 37, and z from the gradient's size instead of J 75 (no answer).
constexpr double kGreedyWeight = 0.9;
constexpr double kStartGap = 0.1;
// A warm start (BandedIpm::WarmStart): y at least kWarmFloor times its largest value, every slack
// at least kWarmSlack (rows are scaled to a bound of 1), and a complementarity of at least
// kWarmMinGap J per row on average. Measured on the same problems as kGuessSlack, the solves after
// the first: 14 / 10 / 11 iterations cold and 8-9 warm on the benchmark's curves (slack floors
// 1e-4 to 1e-1 gave 8-12), 22 / 19 / 21 / 19 cold and 20 / 11 / 15 / 12 warm on the plan.
constexpr double kWarmFloor = 1e-3;
constexpr double kWarmSlack = 3e-2;
constexpr double kWarmMinGap = 1e-4;
// A start from y0 itself without multipliers (the first solve of a sequential convex programme,
// from a guess that violates many rows): every slack at least kGuessSlack. Measured (jerk-limited
// rows, m = 10 / 20 / 10 pieces, K = 50 / 50 / 200; the default plan, 27 pieces, K = 20):
// 24 / 38 / 42 / 52 iterations from the blended start of Start, 18 / 21 / 20 / 28 with 1, 17 / 20
// / 21 / 32 with 0.5, 19 / - / - / 39 with 0.1.
constexpr double kGuessSlack = 1.0;
// How much looser (relative) every bound must still leave the problem without a profile for
// this path to call it infeasible itself (see banded_ipm.h).
constexpr double kInfeasibleMargin = 1e-6;
// The smallest pivot of the Cholesky factorization relative to its diagonal entry: below it the
// system is too badly conditioned for this path, and the conic solver takes over.
constexpr double kPivotFloor = 1e-15;
// A system that breaks down is factored again with its diagonal raised by this share (Step).
constexpr double kRegularization = 1e-10;

#include "banded_ipm_linear.inc"

// A feasible profile by reachability along the path (reachability.h), for problems whose rows are
// over one unknown or two neighbours: the controllable sets backward, then the largest values
// forward. False when a set comes out empty. `margin` loosens every bound: h + margin |h| (and
// margin for h = 0).
bool GreedyProfile(const BandedProblem& p, std::vector<double>* out, double margin) {
  ChainRows chain(p.n);
  for (size_t r = 0; r < p.rows.size(); ++r) {
    const BandedRow& row = p.rows[r];
    const double h = p.h[r] + margin * std::max(1.0, std::abs(p.h[r]));
    if (row.count == 1)
      chain.Add(row.first, row.v[0], row.first, 0.0, h);
    else
      chain.Add(row.first, row.v[0], row.first + 1, row.v[1], h);
  }
  if (!chain.CapUnbounded()) return false;
  std::vector<double> lo, hi;
  if (ControllableSets(chain, &lo, &hi) >= 0) return false;
  *out = GreedyForward(chain, lo, hi, hi[0]);
  return true;
}

// A run of consecutive rows that start at the same unknown (BandedIpm).
struct RowRun {
  int begin = 0, end = 0;  // rows [begin, end)
  int first = 0;           // their first unknown
  int span = 0;            // the most unknowns one of them touches
};
// A cell's two forms on one window of unknowns (BandedIpm::EvaluateCells).
struct CellWindow {
  int lo = 0, width = 0;               // the unknowns lo .. lo + width - 1
  double cv[2][2 * kMaxRowSpan] = {};  // the two forms' coefficients on them
};

// The views of BandedIpm's vectors over the rows that the passes read and write.
template <int W>
struct RowData {
  double* s = nullptr;
  double* z = nullptr;
  double* rp = nullptr;
  double* inv_sz = nullptr;  // 1 / (s z)
  double* ds = nullptr;
  double* dz = nullptr;
  const double* v[W] = {};  // the rows' coefficients as columns
};

// What the passes over the rows for a direction give (banded_ipm_rows.inc).
struct DirectionTotals {
  double inverse = 0.0;       // 1 / the largest step that keeps s, z >= 0
  double s1 = 0.0, s2 = 0.0;  // sum s dz + z ds and sum ds dz
};
// The row passes for every machine: two rows at a time (Pair).
namespace generic {
using Wide = Pair;
#define TIMEOPT_ROWS_TARGET
#include "banded_ipm_rows.inc"
#undef TIMEOPT_ROWS_TARGET
}  // namespace generic

#if TIMEOPT_AVX2_ROWS
// The same passes four rows at a time, compiled for AVX2 and FMA (whatever the build's flags);
// only called where the processor has both (RowPassesAvx2). Each function names its target
// itself (TIMEOPT_AVX2): GCC gives a template's instances the options in force where they are
// instantiated, and Clang has no target pragma.
namespace avx2 {
#define TIMEOPT_AVX2 __attribute__((target("avx2,fma")))
struct Quad {
  __m256d v;
  Quad() = default;  // uninitialized (the passes zero their sums)
  TIMEOPT_AVX2 explicit Quad(__m256d a) : v(a) {}
  TIMEOPT_AVX2 Quad(double a) : v(_mm256_set1_pd(a)) {}  // NOLINT: broadcast, as a double converts
  TIMEOPT_AVX2 Quad operator-() const { return Quad(_mm256_sub_pd(_mm256_setzero_pd(), v)); }
  TIMEOPT_AVX2 Quad& operator+=(Quad a) {
    v = _mm256_add_pd(v, a.v);
    return *this;
  }
};
TIMEOPT_AVX2 inline Quad operator+(Quad a, Quad b) { return Quad(_mm256_add_pd(a.v, b.v)); }
TIMEOPT_AVX2 inline Quad operator-(Quad a, Quad b) { return Quad(_mm256_sub_pd(a.v, b.v)); }
TIMEOPT_AVX2 inline Quad operator*(Quad a, Quad b) { return Quad(_mm256_mul_pd(a.v, b.v)); }
TIMEOPT_AVX2 inline Quad operator/(Quad a, Quad b) { return Quad(_mm256_div_pd(a.v, b.v)); }
}  // namespace avx2
template <>
struct Lanes<avx2::Quad> {
  using Quad = avx2::Quad;
  TIMEOPT_AVX2 static Quad Load(const double* p) { return Quad(_mm256_loadu_pd(p)); }
  TIMEOPT_AVX2 static void Store(double* p, Quad a) { _mm256_storeu_pd(p, a.v); }
  // The larger of a and b, and a when b is NaN (as std::max(a, b)).
  TIMEOPT_AVX2 static Quad Max(Quad a, Quad b) { return Quad(_mm256_max_pd(b.v, a.v)); }
  TIMEOPT_AVX2 static double Sum(Quad a) {
    const __m128d pair = _mm_add_pd(_mm256_castpd256_pd128(a.v), _mm256_extractf128_pd(a.v, 1));
    return _mm_cvtsd_f64(_mm_add_sd(pair, _mm_unpackhi_pd(pair, pair)));
  }
  TIMEOPT_AVX2 static double MaxOf(Quad a) {
    const __m128d pair = _mm_max_pd(_mm256_extractf128_pd(a.v, 1), _mm256_castpd256_pd128(a.v));
    return _mm_cvtsd_f64(_mm_max_sd(_mm_unpackhi_pd(pair, pair), pair));
  }
};
namespace avx2 {
using Wide = Quad;
#define TIMEOPT_ROWS_TARGET TIMEOPT_AVX2
#include "banded_ipm_rows.inc"
#undef TIMEOPT_ROWS_TARGET
}  // namespace avx2
#undef TIMEOPT_AVX2
#endif

// Whether the passes run four rows at a time: on a processor with AVX2 and FMA, unless
// SetWideRowPasses(false) said otherwise.
std::atomic<bool> wide_row_passes{true};
bool RowPassesAvx2() {
#if TIMEOPT_AVX2_ROWS
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported && wide_row_passes.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

}  // namespace

// Every vector of a BandedIpm. Each solve empties them first (clear() keeps the capacity), so
// it sees fresh, zero-filled vectors as before, on pages already touched.
struct BandedIpmWorkspace::Buffers {
  std::vector<RowRun> runs;
  std::vector<int> order, starts;
  std::vector<double> x, s, z, grad, rd, rp, dx, ds, dz, inv_sz, gz, g_inv_s, g_cross, g_dz, rhs;
  std::vector<double> v[kMaxRowSpan];
  std::vector<CellWindow> windows;
  std::vector<char> shares;  // per cell: its first value is the previous cell's last (EvaluateCells)
  Band hess, factor;         // factor: see Band::Factor
  Band matrix;               // the Newton matrix before factoring (for a regularized factorization)
  void Clear() {
    runs.clear();
    order.clear();
    starts.clear();
    for (std::vector<double>* u :
         {&x, &s, &z, &grad, &rd, &rp, &dx, &ds, &dz, &inv_sz, &gz, &g_inv_s, &g_cross, &g_dz, &rhs}) {
      u->clear();
    }
    for (std::vector<double>& u : v) u.clear();
    windows.clear();
    shares.clear();
    hess.v.clear();
    factor.v.clear();
  }
};

BandedIpmWorkspace::BandedIpmWorkspace() : buffers_(std::make_unique<Buffers>()) {}
BandedIpmWorkspace::~BandedIpmWorkspace() = default;

namespace {

// W: the width every row is treated as (its coefficients past `count` are 0, and the vectors over
// the unknowns carry W zeros past n), so that the loops over a row's terms have a fixed length.
template <int W>
class BandedIpm {
 public:
  BandedIpm(const BandedProblem& p, const std::vector<char>* subset, const BandedIpmSettings& settings,
            BandedIpmWorkspace::Buffers& buffers)
      : b_(buffers), p_(p), settings_(settings), n_(p.n) {
    b_.Clear();
    // The rows past the bounds (those of `subset`, or all) in order of their first unknown
    // (stable), so that runs are long: 2,488 runs of 15,474 rows in the order given, 500 sorted,
    // on the first jerk-limited solve at m = 10, K = 50. The bound rows stay first (row v is
    // -y_v <= 0). A counting sort by first unknown (a comparison sort was 4% of a plan's temporal
    // stage).
    const int all = static_cast<int>(p.rows.size());
    const int bounds = std::min(n_, all);
    const auto kept = [&](int r) { return subset == nullptr || (*subset)[static_cast<size_t>(r)] != 0; };
    std::vector<int>& starts = b_.starts;  // rows before those that start at unknown v, then the next free place
    starts.assign(static_cast<size_t>(n_) + 1, 0);
    for (int r = bounds; r < all; ++r) {
      if (kept(r)) ++starts[static_cast<size_t>(p.rows[static_cast<size_t>(r)].first) + 1];
    }
    starts[0] = bounds;
    for (int v = 0; v < n_; ++v) starts[static_cast<size_t>(v) + 1] += starts[static_cast<size_t>(v)];
    m_ = starts[static_cast<size_t>(n_)];
    order_.resize(static_cast<size_t>(m_));
    for (int r = 0; r < bounds; ++r) order_[static_cast<size_t>(r)] = r;
    for (int r = bounds; r < all; ++r) {
      if (kept(r)) order_[static_cast<size_t>(starts[static_cast<size_t>(p.rows[static_cast<size_t>(r)].first)]++)] = r;
    }
    // Runs of consecutive rows that start at the same unknown: their sums into the gradient, the
    // right-hand side and the Newton matrix are formed in registers and added once per run (adding
    // each row's terms in memory stalled on store-to-load forwarding).
    for (int r = 0; r < m_; ++r) {
      const BandedRow& row = Row(static_cast<size_t>(r));
      if (runs_.empty() || runs_.back().first != row.first) runs_.push_back(RowRun{r, r, row.first, 0});
      RowRun& run = runs_.back();
      run.end = r + 1;
      run.span = std::max<int>(run.span, row.count);
    }
    for (int r = 0; r < m_; ++r) h_max_ = std::max(h_max_, std::abs(Bound(static_cast<size_t>(r))));
    // Cells whose first value is the previous cell's last (consecutive cells of a piece): b, its
    // root and 1 / root carry over in EvaluateCells.
    const auto same = [](const ControlForm& a, const ControlForm& b) {
      if (a.first != b.first || a.count != b.count || a.constant != b.constant) return false;
      for (int t = 0; t < a.count; ++t) {
        if (a.coef[static_cast<size_t>(t)] != b.coef[static_cast<size_t>(t)]) return false;
      }
      return true;
    };
    shares_.assign(p.cells.size(), 0);
    for (size_t k = 1; k < p.cells.size(); ++k) shares_[k] = same(p.cells[k].b[0], p.cells[k - 1].b[1]) ? 1 : 0;
    // Each cell's two forms on one window of unknowns (over control values), for EvaluateCells.
    if (p.controls) {
      windows_.resize(p.cells.size());
      for (size_t k = 0; k < p.cells.size(); ++k) {
        const BandedCell& c = p.cells[k];
        CellWindow& window = windows_[k];
        int lo = n_, hi = -1;
        for (const ControlForm& f : c.b) {
          if (f.count == 0) continue;
          lo = std::min(lo, f.first);
          hi = std::max(hi, f.first + f.count - 1);
        }
        if (hi < lo) continue;  // width 0: no unknowns
        window.lo = lo;
        window.width = hi - lo + 1;
        for (int j = 0; j < 2; ++j) {
          const ControlForm& f = c.b[j];
          for (int t = 0; t < f.count; ++t) window.cv[j][f.first - lo + t] = f.coef[static_cast<size_t>(t)];
        }
      }
    }
    // The rows' coefficients as columns, for Step's passes two rows at a time.
    for (int t = 0; t < W; ++t) {
      v_[t].resize(static_cast<size_t>(m_));
      for (int r = 0; r < m_; ++r) v_[t][static_cast<size_t>(r)] = Row(static_cast<size_t>(r)).v[t];
    }
  }

  BandedIpmOutcome Run(const std::vector<double>& y0, const std::vector<double>* warm) {
    BandedIpmOutcome out;
    out.kind = BandedIpmOutcome::Kind::kGaveUp;
    out.rows = m_ - std::min(n_, m_);
    if (warm != nullptr ? !WarmStart(y0, *warm) : !Start(y0)) {
      out.message = "structured path: no start inside the rows that keep b positive";
      return out;
    }
    for (int it = 0;; ++it) {
      out.iterations = it;
      EvaluateCells();
      // Step keeps r_p and G'z up to date without a pass over the rows of their own; before
      // answering they are formed again from x, s and z, so rounding in those updates never
      // decides.
      if (Converged() && (RowResiduals(), EvaluateCells(), Converged())) {
        out.kind = BandedIpmOutcome::Kind::kOptimal;
        out.x.resize(p_.x_form.size());
        for (size_t v = 0; v < out.x.size(); ++v) out.x[v] = p_.x_form[v].Value(x_);
        out.y.assign(x_.begin(), x_.begin() + n_);
        out.z.assign(p_.rows.size(), 0.0);
        for (int r = 0; r < m_; ++r)
          out.z[static_cast<size_t>(order_[static_cast<size_t>(r)])] = z_[static_cast<size_t>(r)];
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
  // x0: kGreedyWeight times y0 plus the rest times a uniform profile (each unknown at its cap)
  // scaled by half of the largest t in (0, 1] that keeps every row holding at 0 satisfied at t x0
  // (as IpoptTemporalNlp::StartingPoint); s from the rows (at least kSlackFloor, which leaves a
  // residual on rows the start violates); z = mu0 / s. False when the bound rows are not strictly
  // inside at x0 or J is not finite there.
  bool Start(const std::vector<double>& y0) {
    x_ = p_.cap;
    x_.resize(static_cast<size_t>(n_ + W), 0.0);
    double t_max = 1.0;
    for (int r = n_; r < m_; ++r) {
      if (!(Bound(static_cast<size_t>(r)) > 0.0)) continue;
      const double value = Dot(Row(static_cast<size_t>(r)), x_);
      if (value > Bound(static_cast<size_t>(r))) t_max = std::min(t_max, Bound(static_cast<size_t>(r)) / value);
    }
    const bool guess = y0.size() == static_cast<size_t>(n_);
    const double weight = guess ? kGreedyWeight : 0.0;
    for (int v = 0; v < n_; ++v) {
      x_[static_cast<size_t>(v)] = (1.0 - weight) * 0.5 * t_max * x_[static_cast<size_t>(v)] +
                                   (guess ? weight * std::max(0.0, y0[static_cast<size_t>(v)]) : 0.0);
      if (!(x_[static_cast<size_t>(v)] > 0.0)) return false;
    }
    s_.assign(static_cast<size_t>(m_), 0.0);
    z_.assign(static_cast<size_t>(m_), 0.0);
    constexpr double kSlackFloor = 1e-2;
    for (int r = 0; r < m_; ++r) {
      const double slack = Bound(static_cast<size_t>(r)) - Dot(Row(static_cast<size_t>(r)), x_);
      s_[static_cast<size_t>(r)] = r < n_ ? x_[static_cast<size_t>(r)] : std::max(slack, kSlackFloor);
    }
    // z = mu0 / s with s'z = kStartGap J(x0).
    gz_.assign(static_cast<size_t>(n_ + W), 0.0);
    EvaluateCells();
    if (!std::isfinite(objective_)) return false;
    const double mu0 = std::max(kStartGap * std::abs(objective_) / m_, std::numeric_limits<double>::min());
    for (int r = 0; r < m_; ++r) z_[static_cast<size_t>(r)] = mu0 / s_[static_cast<size_t>(r)];
    RowResiduals();
    return true;
  }

  // From y0 itself (kept kWarmFloor inside y >= 0) and the multipliers of a previous solve of a
  // nearby problem: s from the rows (at least kWarmSlack; kGuessSlack when warm is empty), z from
  // warm (by row id) but at least mu / s, with mu the mean s z of the rows that have one (kStartGap
  // J per row when none has); z = mu / s for a row without.
  bool WarmStart(const std::vector<double>& y0, const std::vector<double>& warm) {
    if (y0.size() != static_cast<size_t>(n_)) return false;
    double ymax = 0.0;
    for (double v : y0) ymax = std::max(ymax, v);
    if (!(ymax > 0.0)) return false;
    x_.assign(static_cast<size_t>(n_ + W), 0.0);
    for (int v = 0; v < n_; ++v) x_[static_cast<size_t>(v)] = std::max(y0[static_cast<size_t>(v)], kWarmFloor * ymax);
    s_.assign(static_cast<size_t>(m_), 0.0);
    z_.assign(static_cast<size_t>(m_), 0.0);
    double sum = 0.0;
    int count = 0;
    for (int r = 0; r < m_; ++r) {
      const size_t i = static_cast<size_t>(r);
      const double slack = Bound(i) - Dot(Row(i), x_);
      s_[i] = r < n_ ? x_[i] : std::max(slack, warm.empty() ? kGuessSlack : kWarmSlack);
      const int id = p_.id[static_cast<size_t>(order_[i])];
      const double z = id >= 0 && static_cast<size_t>(id) < warm.size() ? warm[static_cast<size_t>(id)] : std::nan("");
      if (std::isfinite(z) && z > 0.0) {
        z_[i] = z;
        sum += s_[i] * z;
        ++count;
      }
    }
    gz_.assign(static_cast<size_t>(n_ + W), 0.0);
    EvaluateCells();
    if (!std::isfinite(objective_)) return false;
    const double mu = count > 0 ? std::max(sum / count, kWarmMinGap * std::abs(objective_) / m_)
                                : kStartGap * std::abs(objective_) / m_;
    for (int r = 0; r < m_; ++r) {
      const size_t i = static_cast<size_t>(r);
      z_[i] = std::max(z_[i], mu / s_[i]);
    }
    RowResiduals();
    return true;
  }

  // A row's value at v (W terms; v carries W zeros past n).
  static double Dot(const BandedRow& row, const std::vector<double>& v) {
    const double* x = v.data() + row.first;
    double value = 0.0;
    for (int t = 0; t < W; ++t) value += row.v[t] * x[t];
    return value;
  }

  // J, its gradient and Hessian at x_ (the cells), and r_d = grad J + G'z from the kept G'z.
  void EvaluateCells() {
    grad_.assign(static_cast<size_t>(n_ + W), 0.0);
    hess_.Reset(n_, p_.bandwidth);
    // (The objective in a local: summed in the member, each cell's stores into grad_ and hess_
    // forced it through memory.)
    double objective = 0.0;
    // The previous cell's last value, its root and 1 / root (see shares_).
    double last_b = 0.0, last_r = 0.0, last_inv_r = 0.0;
    for (size_t k = 0; k < p_.cells.size(); ++k) {
      const BandedCell& c = p_.cells[k];
      const bool free0 = c.b[0].count > 0, free1 = c.b[1].count > 0;
      double b0, r0, inv_r0;
      if (shares_[k]) {
        b0 = last_b;
        r0 = last_r;
        inv_r0 = last_inv_r;
      } else {
        b0 = std::max(c.b[0].Value(x_), 0.0);
        r0 = std::sqrt(b0);
        inv_r0 = free0 ? 1.0 / r0 : 0.0;
      }
      const double b1 = std::max(c.b[1].Value(x_), 0.0);
      const double r1 = std::sqrt(b1);
      const double inv_r1 = free1 ? 1.0 / r1 : 0.0;
      last_b = b1;
      last_r = r1;
      last_inv_r = inv_r1;
      const double S = r0 + r1;
      // Three divisions, every term from them (the divider bounds this loop).
      const double inv_S = 1.0 / S;
      objective += c.c * inv_S + c.reg * (b1 - b0) * (b1 - b0);
      // c / (2 S^2), the factor of every derivative of c / S.
      const double q = 0.5 * c.c * inv_S * inv_S;
      const double reg_grad = 2.0 * c.reg * (b1 - b0);
      // Derivatives in b0, b1; a constant b has none.
      double db[2] = {-reg_grad, reg_grad};
      double h00 = 2.0 * c.reg, h11 = 2.0 * c.reg, h01 = -2.0 * c.reg;
      if (free0) {
        db[0] += -q * inv_r0;
        h00 += q * inv_r0 * inv_r0 * (inv_S + 0.5 * inv_r0);
      }
      if (free1) {
        db[1] += -q * inv_r1;
        h11 += q * inv_r1 * inv_r1 * (inv_S + 0.5 * inv_r1);
      }
      if (free0 && free1) h01 += q * inv_S * inv_r0 * inv_r1;
      if (!p_.controls) {
        // One unknown per value (the paper's and certified rows): the terms directly.
        const double s0 = c.b[0].coef[0], s1 = c.b[1].coef[0];
        const int v0 = c.b[0].first, v1 = c.b[1].first;
        if (free0) {
          grad_[static_cast<size_t>(v0)] += s0 * db[0];
          hess_.Add(v0, v0, s0 * s0 * h00);
        }
        if (free1) {
          grad_[static_cast<size_t>(v1)] += s1 * db[1];
          hess_.Add(v1, v1, s1 * s1 * h11);
        }
        if (free0 && free1) {
          const double cross = s0 * s1 * h01;
          if (v0 == v1)
            hess_.Add(v0, v0, 2.0 * cross);
          else
            hess_.Add(v0, v1, cross);
        }
        continue;
      }
      // The two forms on one window of unknowns: grad += db_j c_j, hess += sum_jk h_jk c_j c_k'.
      const CellWindow& window = windows_[k];
      const int lo = window.lo, w = window.width;
      const auto& cv = window.cv;
      // As h_jk c_k, the entries are (h00 c0_a + h01 c1_a) c0_b + (h01 c0_a + h11 c1_a) c1_b; entry
      // (lo + a, lo + b) of the band is at row[-b] with row = band + (lo + a) (p + 1) + a.
      double* band = hess_.v.data() + static_cast<size_t>(lo) * static_cast<size_t>(hess_.p + 1);
      const size_t stride = static_cast<size_t>(hess_.p + 1);
      for (int a = 0; a < w; ++a) {
        grad_[static_cast<size_t>(lo + a)] += db[0] * cv[0][a] + db[1] * cv[1][a];
        const double u0 = h00 * cv[0][a] + h01 * cv[1][a], u1 = h01 * cv[0][a] + h11 * cv[1][a];
        double* row = band + static_cast<size_t>(a) * stride + static_cast<size_t>(a);
        for (int b = 0; b <= a; ++b) row[-b] += u0 * cv[0][b] + u1 * cv[1][b];
      }
    }
    objective_ = objective;
    rd_.resize(static_cast<size_t>(n_ + W));
    for (size_t v = 0; v < static_cast<size_t>(n_ + W); ++v) rd_[v] = grad_[v] + gz_[v];
  }

  // One pass over the rows: r_p, G'z and the figures Converged reads, from x, s and z.
  void RowResiduals() {
    gz_.assign(static_cast<size_t>(n_ + W), 0.0);
    rp_.resize(static_cast<size_t>(m_));
    double rp_max = 0.0, gap = 0.0;  // (locals: see EvaluateCells)
    for (const RowRun& run : runs_) {
      double acc[W] = {};
      for (int r = run.begin; r < run.end; ++r) {
        const BandedRow& row = Row(static_cast<size_t>(r));
        const size_t i = static_cast<size_t>(r);
        for (int t = 0; t < W; ++t) acc[t] += row.v[t] * z_[i];
        const double rp = Dot(row, x_) + s_[i] - Bound(i);
        rp_[i] = rp;
        rp_max = std::max(rp_max, std::abs(rp));
        gap += s_[i] * z_[i];
      }
      for (int t = 0; t < run.span; ++t) gz_[static_cast<size_t>(run.first + t)] += acc[t];
    }
    rp_max_ = rp_max;
    gap_ = gap;
  }

  bool Converged() const {
    double rd = 0.0, gmax = 1.0;
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) {
      rd = std::max(rd, std::abs(rd_[v]));
      gmax = std::max(gmax, std::abs(grad_[v]));
    }
    return rp_max_ <= settings_.tolerance * h_max_ && rd <= settings_.tolerance * gmax &&
           gap_ <= settings_.gap_tolerance * std::abs(objective_);
  }

  // One iteration in three passes over the rows (Mehrotra's predictor and corrector share the
  // factorization; the corrector's right-hand side and the next r_p and G'z come from sums kept in
  // the passes, so neither needs a pass of its own):
  //   1. M = grad^2 J + G' (Z / S) G, the predictor's right-hand side -r_d + G' (z - z o r_p / s)
  //      and G' (1 / s) (MatrixRows);
  //   2. the predictor's ds, dz (rc = s o z), its step and mu after it, and G' (ds_a o dz_a / s);
  //   3. the corrector's ds, dz with rc = s o z + ds_a o dz_a - sigma mu, whose right-hand side is
  //      that of the predictor + G' (ds_a o dz_a / s) - sigma mu G' (1 / s), and G' dz
  //      (Directions, DirectionRows).
  // Then s += alpha ds, z += alpha dz, and (rows being linear) r_p *= 1 - alpha, G'z += alpha G' dz.
  bool Step() {
    factor_ = hess_;
    dx_.assign(static_cast<size_t>(n_ + W), 0.0);
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) dx_[v] = -rd_[v];
    g_inv_s_.assign(static_cast<size_t>(n_ + W), 0.0);
    inv_sz_.resize(static_cast<size_t>(m_));
    double mu = MatrixPass();
    mu /= m_;
    matrix_ = factor_;  // (kept for a regularized factorization, below)
    if (!factor_.Factor()) {
      // A pivot below kPivotFloor: near the end, with s'z at 1e-14 of J, the rows at their bounds
      // weigh 1e16 and more, and two nearly parallel ones leave the system singular to rounding.
      // Once more with every diagonal entry raised by kRegularization of itself (the direction
      // then slightly damped where the system is nearly singular; the residuals are formed
      // exactly at the next iterate, so that cannot be mistaken for convergence). Sweep problem
      // 4194 (paper rows, K = 19) broke down with r_d at 1.09 times its tolerance and went to the
      // conic solver, which stalled; with it one more step ends optimal.
      factor_ = matrix_;
      for (int v = 0; v < n_; ++v) factor_.At(v, v) *= 1.0 + kRegularization;
      if (!factor_.Factor()) return false;
    }
    rhs_ = dx_;
    // Predictor.
    factor_.Solve(dx_);
    ds_.resize(static_cast<size_t>(m_));
    dz_.resize(static_cast<size_t>(m_));
    g_cross_.assign(static_cast<size_t>(n_ + W), 0.0);
    DirectionTotals totals = Directions(nullptr, &g_cross_);
    const double alpha_aff = std::min(1.0, totals.inverse > 0.0 ? 1.0 / totals.inverse : kInf);
    const double mu_aff = (mu * m_ + alpha_aff * totals.s1 + alpha_aff * alpha_aff * totals.s2) / m_;
    const double ratio = std::max(0.0, mu_aff / mu);
    const double sigma = std::min(1.0, ratio * ratio * ratio);
    const double shift = sigma * mu;
    // Corrector; again without the second-order term when its step would raise the gap (see
    // kGapGrowth).
    DirectionTotals totals_c;
    double alpha = 0.0;
    for (bool second_order = true;; second_order = false) {
      if (!second_order) {
        // (ds_ held ds_a o dz_a for the corrector's pass, g_cross_ its terms G' (ds_a o dz_a / s).)
        std::fill(ds_.begin(), ds_.end(), 0.0);
        std::fill(g_cross_.begin(), g_cross_.end(), 0.0);
      }
      for (size_t v = 0; v < static_cast<size_t>(n_); ++v) dx_[v] = rhs_[v] + g_cross_[v] - shift * g_inv_s_[v];
      for (size_t v = static_cast<size_t>(n_); v < dx_.size(); ++v) dx_[v] = 0.0;
      factor_.Solve(dx_);
      for (size_t v = 0; v < static_cast<size_t>(n_); ++v) {
        if (!std::isfinite(dx_[v])) return false;
      }
      g_dz_.assign(static_cast<size_t>(n_ + W), 0.0);
      totals_c = Directions(&shift, &g_dz_);
      alpha = std::min(1.0, kStepFraction * (totals_c.inverse > 0.0 ? 1.0 / totals_c.inverse : kInf));
      const double gap = mu * m_;
      if (!second_order || !(gap + alpha * totals_c.s1 + alpha * alpha * totals_c.s2 > kGapGrowth * gap)) break;
    }
    if (!(alpha > 0.0)) return false;
      // The step, and r_p, G'z and the figures Converged reads after it.
#if TIMEOPT_AVX2_ROWS
    if (wide_)
      avx2::StepPass<W>(Rows(), m_, alpha, &rp_max_, &gap_);
    else
#endif
      generic::StepPass<W>(Rows(), m_, alpha, &rp_max_, &gap_);
    for (size_t v = 0; v < gz_.size(); ++v) gz_[v] += alpha * g_dz_[v];
    // The bound rows keep x = s exactly (their residual is 0 and stays 0 up to rounding).
    for (size_t v = 0; v < static_cast<size_t>(n_); ++v) x_[v] = s_[v];
    return true;
  }

  // The passes over the rows (banded_ipm_rows.inc), four rows at a time where the processor
  // allows (RowPassesAvx2), else two.
  RowData<W> Rows() {
    RowData<W> d;
    d.s = s_.data();
    d.z = z_.data();
    d.rp = rp_.data();
    d.inv_sz = inv_sz_.data();
    d.ds = ds_.data();
    d.dz = dz_.data();
    for (int t = 0; t < W; ++t) d.v[t] = v_[t].data();
    return d;
  }
  // Pass 1: M = grad^2 J + G' (Z / S) G into factor_, the predictor's right-hand side into dx_,
  // G' (1 / s) into g_inv_s_; returns s'z.
  double MatrixPass() {
#if TIMEOPT_AVX2_ROWS
    if (wide_) return avx2::MatrixPass<W>(Rows(), runs_, dx_.data(), g_inv_s_.data(), &factor_);
#endif
    return generic::MatrixPass<W>(Rows(), runs_, dx_.data(), g_inv_s_.data(), &factor_);
  }
  // Passes 2 and 3: from dx_ (solved), ds and dz into ds_, dz_, and into *sums G' (ds o dz / s)
  // for the predictor (shift == nullptr), G' dz for the corrector.
  DirectionTotals Directions(const double* shift, std::vector<double>* sums) {
#if TIMEOPT_AVX2_ROWS
    if (wide_) return avx2::DirectionPass<W>(Rows(), runs_, dx_.data(), shift, sums->data());
#endif
    return generic::DirectionPass<W>(Rows(), runs_, dx_.data(), shift, sums->data());
  }

  BandedIpmWorkspace::Buffers& b_;
  const BandedProblem& p_;
  BandedIpmSettings settings_;
  std::vector<RowRun>& runs_ = b_.runs;
  int n_ = 0, m_ = 0;
  std::vector<int>& order_ = b_.order;  // row r here is row order_[r] of p_
  // Row r here, and its bound: p_'s row order_[r].
  const BandedRow& Row(size_t r) const { return p_.rows[static_cast<size_t>(order_[r])]; }
  double Bound(size_t r) const { return p_.h[static_cast<size_t>(order_[r])]; }
  std::vector<double>&x_ = b_.x, &s_ = b_.s, &z_ = b_.z;
  std::vector<double>&grad_ = b_.grad, &rd_ = b_.rd, &rp_ = b_.rp, &dx_ = b_.dx, &ds_ = b_.ds, &dz_ = b_.dz,
  &inv_sz_ = b_.inv_sz;
  // G'z (kept through the steps), and the sums over the rows of one iteration: G' (1 / s),
  // G' (ds_a o dz_a / s), G' dz, and the predictor's right-hand side.
  std::vector<double>&gz_ = b_.gz, &g_inv_s_ = b_.g_inv_s, &g_cross_ = b_.g_cross, &g_dz_ = b_.g_dz, &rhs_ = b_.rhs;
  std::vector<double> (&v_)[kMaxRowSpan] = b_.v;   // the rows' coefficients as columns (the first W)
  std::vector<CellWindow>& windows_ = b_.windows;  // per cell (over control values only)
  std::vector<char>& shares_ = b_.shares;          // per cell
  double objective_ = 0.0;
  double rp_max_ = 0.0, h_max_ = 1.0, gap_ = 0.0;  // from RowResiduals and Step
  const bool wide_ = RowPassesAvx2();
  Band &hess_ = b_.hess, &factor_ = b_.factor, &matrix_ = b_.matrix;
};

}  // namespace

bool SetWideRowPasses(bool on) { return wide_row_passes.exchange(on); }
bool WideRowPasses() { return RowPassesAvx2(); }

BandedIpmOutcome SolveBandedProblem(const BandedProblem& p, const std::vector<double>& y0,
                                    const BandedIpmSettings& settings, const std::vector<double>* warm,
                                    BandedIpmWorkspace* workspace, const std::vector<char>* subset) {
  // (A cell's two forms are read into a window of 2 kMaxRowSpan values in Evaluate.)
  if (p.bandwidth > settings.max_bandwidth || p.bandwidth >= 2 * kMaxRowSpan) {
    BandedIpmOutcome out;
    out.message = "half-bandwidth " + std::to_string(p.bandwidth);
    return out;
  }
  if (subset != nullptr && subset->size() != p.rows.size()) {
    BandedIpmOutcome out;
    out.message = "structured path: a row subset of the wrong size";
    return out;
  }
  int width = 1;
  for (size_t r = 0; r < p.rows.size(); ++r) {
    const BandedRow& row = p.rows[r];
    // (BandedIpm orders the rows by their first unknown through a table over the unknowns.)
    if (row.first < 0 || row.first + std::max<int>(row.count, 1) > p.n) {
      BandedIpmOutcome out;
      out.message = "structured path: a row outside the unknowns";
      return out;
    }
    if (subset == nullptr || (*subset)[r] != 0) width = std::max<int>(width, row.count);
  }
  BandedIpmWorkspace local;
  BandedIpmWorkspace::Buffers& buffers = (workspace != nullptr ? *workspace : local).buffers();
  if (width <= 2) return BandedIpm<2>(p, subset, settings, buffers).Run(y0, warm);
  if (width == 3) return BandedIpm<3>(p, subset, settings, buffers).Run(y0, warm);
  return BandedIpm<kMaxRowSpan>(p, subset, settings, buffers).Run(y0, warm);
}

BandedIpmOutcome SolveBanded(const TemporalDiscretization& d, const BandedIpmSettings& settings) {
  BandedIpmOutcome out;
  BandedProblem p;
  if (!BuildBandedProblem(d, &p, &out.message)) return out;
  std::vector<double> y0;
  if (!p.controls) {
    if (!GreedyProfile(p, &y0, 0.0)) {
      std::vector<double> unused;
      const bool infeasible = !GreedyProfile(p, &unused, kInfeasibleMargin);
      if (infeasible) out.kind = BandedIpmOutcome::Kind::kInfeasible;
      out.message = infeasible ? "no time allocation satisfies the limits: reachability along the path finds no "
                                 "profile (structured path)"
                               : "the reachability pass found no profile";
      return out;
    }
  } else if (d.start_b.size() == d.grid.size()) {
    y0.resize(static_cast<size_t>(p.n));
    for (int v = 0; v < p.n; ++v) y0[static_cast<size_t>(v)] = d.controls->FromGrid(v, d.start_b);
  }
  return SolveBandedProblem(p, y0, settings);
}

}  // namespace timeopt::internal
