// The sequential convex programme of the jerk-limited solve on the structured path
// (structured_scp.h): over the control values of a jerk-limited discretization, whose equality
// rows hold by construction, each convex solve a banded interior-point solve (banded_ipm.h) of
// the rows its working set takes.

#include "structured_scp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace timeopt::internal {
namespace {

using Clock = SteadyClock;

// See SolveStructuredScp's first working set from a jerk-limited start. Measured on the benchmark's
// curves (BM_SocpJerkLimited): 0.8 took 2,805 acceleration rows of 3,054 at m = 10, K = 50 and
// 12 iterations instead of 13 (ratio to paper mode 4.00 -> 3.92; m = 20: -4%; K = 200 the same);
// 0.95 and 0.99 left out rows that the answer violated, a round more each.
constexpr double kGroupFraction = 0.8;
// A jerk row left out of a working set and violated by its answer is, in the cases seen, one whose
// mirror (the other sign) was in the set: the answer swung the cell's s-jerk from one limit to the
// other, and the next round then found the neighbouring cells' rows violated in turn. So a round
// adds every jerk row within kViolatedReach control values of a violated row. Measured on the
// 100 m forest's plan (smoothness weight 2): its second convex solve took 3 more rounds, the last
// with all 251,296 rows, without; 2 more with a reach of 0 or 1; 1 with 2 (60,030 rows). On 100
// forest_gen plans, rows x iterations 27.2 M -> 26.6 M; the benchmark's curves have no such round.
constexpr int kViolatedReach = 2;
// The relative row and gap tolerance of the structured programme's first solve from the jerk-free
// guess (its answer is only the next linearization point and start; the stopping tests skip its
// T). Measured at 1e-5 / 1e-3 / 1e-2 (convex solves' rows x iterations, summed): the default plan
// 1.23 M / 0.96 M / 0.84 M (the first solve, 27,853 rows: 24 iterations and a second round of 8,
// 19 and 3, 16 and none); every 5th pair of the forest_gen set (100 plans) 29.7 M / 27.0 M /
// 25.6 M, with the same T (largest change 1.2e-7 relative at 1e-3); but the 100 m forest's second
// solve then missed rows at 3e-3 and 1e-2 (three more rounds, the last with all 251,297 rows).
constexpr double kFirstSolveTolerance = 1e-3;
// The structured programme stops early when its last two changes of T shrink at most at this rate
// and the rest they predict is below scp_tolerance (see SolveStructuredScp).
constexpr double kScpRate = 0.25;
// The programme stops when the gain of linearizing again that PredictedGain predicts is below this
// fraction of scp_tolerance. The prediction ran 3-10% below the next solve's actual change of T on
// the benchmark's curves and the default plan (3.8e-5 against 4.1e-5, 8.7e-4 against 8.9e-4), so
// half leaves room for that.
constexpr double kPredictedFraction = 0.5;
// A control whose essential rows bound it at more than kLooseBound times its value keeps all its
// rows in a working set (see SolveStructuredScp). On the default plan (27 pieces, K = 20) 10
// kept 1.9 x the rows of 1000 in the settled solves; without the rule a solve ran off to infinite
// speed at the curve's ends (tangent and curvature vanish there) and hit the iteration limit.
constexpr double kLooseBound = 1000.0;

// The coefficients of the linearized jerk rows over their cell's three half-grid values at a
// linearization (b at every half-grid value): |P| + j b / (2 bbar^1.5) <= 3 j / (2 sqrt(bbar))
// divided by its bound, bbar the cell's LinearizationPoint (a rest cell's: per part). A cell's (or
// part's) templates are consecutive, so bbar is found once per cell or part.
class JerkCoefficients {
 public:
  JerkCoefficients(const TemporalDiscretization& d, const std::vector<double>& linearization)
      : d_(d), linearization_(linearization), floors_(internal::LinearizationFloors(d, linearization)) {}
  std::array<double, 3> operator()(const internal::JerkRowTemplate& t) {
    if (t.g0 != g0_ || t.part != part_) {
      g0_ = t.g0;
      part_ = t.part;
      const size_t g = static_cast<size_t>(t.g0);
      const double lb[3] = {linearization_[g], linearization_[g + 1], linearization_[g + 2]};
      const double floor = floors_[static_cast<size_t>(internal::PieceOf(d_, t.g0))];
      double bbar = 0.0;
      if (t.rest_far < 0) {
        bbar = internal::LinearizationPoint(lb, floor);
      } else {
        const double alpha = lb[1], far = lb[t.rest_far];
        bbar = std::max({alpha + (far - alpha) * t.w0(), alpha + (far - alpha) * t.w1(), floor});
      }
      root_ = 2.0 * std::sqrt(bbar) / 3.0;
      cb_ = 1.0 / (3.0 * bbar);
    }
    return {t.a[0] * root_ + t.basis[0] * cb_, t.a[1] * root_ + t.basis[1] * cb_, t.a[2] * root_ + t.basis[2] * cb_};
  }

 private:
  const TemporalDiscretization& d_;
  const std::vector<double>& linearization_;
  std::vector<double> floors_;
  int g0_ = -1;
  int part_ = -1;
  double root_ = 0.0, cb_ = 0.0;
};

// The gain in J, to first order, of linearizing the jerk rows again at `answer` (b at every grid
// value) instead of at `linearization`: a jerk row with multiplier z that the new linearization
// loosens by delta at the answer (in the scaled row's units, bound +-1) lowers the optimum by
// about z delta, the rows' matrix moving along with their bound. z_by_id holds the multipliers of
// the solve that gave the answer, by row id (jerk template ti has id static_rows + ti).
double PredictedGain(const TemporalDiscretization& d, const internal::JerkTemplates& templates, size_t static_rows,
                     const std::vector<double>& z_by_id, const std::vector<double>& linearization,
                     const std::vector<double>& answer) {
  JerkCoefficients old_rows(d, linearization), new_rows(d, answer);
  // A row's value minus its bound at the answer, scaled as BandedProblem scales it.
  const auto excess = [&](const internal::JerkRowTemplate& t, const std::array<double, 3>& coef) {
    double value = -1.0, fixed = 1.0;
    for (size_t j = 0; j < 3; ++j) {
      const double b = answer[static_cast<size_t>(t.g0) + j];
      value += coef[j] * b;
      if (d.grid[static_cast<size_t>(t.g0) + j].var < 0) fixed -= coef[j] * b;
    }
    const double scale = std::abs(fixed) > 0.0 ? std::abs(fixed) : 1.0;
    return value / scale;
  };
  double gain = 0.0;
  for (size_t ti = 0; ti < templates.jerk_rows.size(); ++ti) {
    const size_t id = static_rows + ti;
    const double z = id < z_by_id.size() ? z_by_id[id] : 0.0;
    if (!(z > 0.0)) continue;
    const internal::JerkRowTemplate& t = templates.jerk_rows[ti];
    gain += z * (excess(t, old_rows(t)) - excess(t, new_rows(t)));
  }
  return gain;
}

// y followed by internal::kMaxRowSpan - 1 zeros, into *out (for BandedRow::PaddedValue).
void PadForRows(const std::vector<double>& y, std::vector<double>* out) {
  out->assign(y.begin(), y.end());
  out->resize(y.size() + internal::kMaxRowSpan - 1, 0.0);
}

// Whether the row has a term over a marked unknown.
bool TouchesMarked(const internal::BandedRow& row, const std::vector<char>& marked) {
  for (int t = 0; t < row.count; ++t) {
    if (marked[static_cast<size_t>(row.first + t)]) return true;
  }
  return false;
}

}  // namespace

std::vector<double> GridValues(const TemporalDiscretization& d, const std::vector<double>& x) {
  std::vector<double> b(d.grid.size());
  for (size_t g = 0; g < d.grid.size(); ++g) b[g] = std::max(0.0, d.GridB(static_cast<int>(g), x));
  return b;
}

TemporalProfile ProfileOf(const TemporalDiscretization& d, std::vector<double> b) {
  internal::RestAlphaToMiddles(d, &b);
  const int half = d.cells_per_piece, full = half / 2;
  std::vector<std::vector<double>> piece_b(static_cast<size_t>(d.num_pieces));
  std::vector<std::vector<CellShape>> shapes(static_cast<size_t>(d.num_pieces));
  for (int i = 0; i < d.num_pieces; ++i) {
    piece_b[static_cast<size_t>(i)].assign(b.begin() + d.GridIndex(i, 0), b.begin() + d.GridIndex(i, half) + 1);
    shapes[static_cast<size_t>(i)].assign(d.shapes.begin() + i * full, d.shapes.begin() + (i + 1) * full);
  }
  return TemporalProfile::JerkLimited(std::move(piece_b), std::move(shapes), d.cell_edges);
}

// The profile's exact time for b at every half-grid value of the jerk-limited d.
double ProfileTime(const TemporalDiscretization& d, const std::vector<double>& b) {
  return ProfileOf(d, b).total_time();
}

// The sequential convex programme on the structured path (banded_ipm.h), over d's control values:
// d (from DiscretizeJerkLimitedTemplates) and the velocity and acceleration templates become a
// BandedProblem once; each convex solve adds the jerk rows linearized at the previous answer (from
// `templates`, no new discretization) and starts from that answer and its multipliers. The first
// linearization is `linearization` (b at every half-grid value: the jerk-free certified optimum).
// Each solve gets a working set (see the loop); an answer that violates a row left out is solved
// again with it. False, with the reason in *why, when a solve does not end optimal: the general
// path then decides, so statuses never depend on this one. thin_jerk: a programme whose answer is
// only a linearization point (the coarse one) leaves out the jerk rows marked `thin`, so it bounds
// the jerk at every other Bernstein coefficient (m = 10, K = 50: its solve over 3,800 rows instead
// of 4,750, in as many iterations, and the fine solve unchanged).
bool SolveStructuredScp(const TemporalProblem& problem, const TemporalDiscretization& d,
                        const internal::JerkTemplates& templates, std::vector<double> linearization,
                        const internal::BandedIpmSettings& settings, bool jerk_aware,
                        internal::SolveWorkspace* workspace, StructuredScp* out, bool thin_jerk) {
  Clock::time_point start = Clock::now();
  // p: every row (in the workspace, whose memory the previous programme has touched already); a
  // solve takes the working set `keep` of them.
  internal::BandedProblem& p = workspace->problem;
  if (!internal::BuildBandedProblem(d, &p, &out->why)) return false;
  // Every regular cell's grid values as forms on its window of control values, once (by g0).
  std::vector<internal::BandedProblem::CellMap>& cell_map = workspace->cell_maps;
  cell_map.resize(d.grid.size());
  std::vector<char> mapped(d.grid.size(), 0);
  // The rows over a regular cell's three grid values, sum_j coef[j] b_{g0 + j} <= 1 (the velocity
  // and acceleration templates, and the jerk rows of each linearization), go into p only when a
  // solve takes them: on the benchmark's curves (m = 10, K = 50) a solve took 6,340 of 24,553
  // velocity and acceleration rows and 978 of 9,141 jerk rows, and building every one of them was
  // 10% of the whole solve. The others wait, tested at each answer on the grid values straight
  // from their templates (a list of them, written and read again, cost more than it saved). Ids:
  // d's rows first, then the cell rows, then the jerk rows (z_by_id, PredictedGain).
  const size_t cell_rows = templates.cell_rows.size();
  // Room for every row at once: one allocation, not a copy of ~1 MB per growth.
  p.Reserve(p.rows.size() + cell_rows + templates.jerk_rows.size());
  // The upper bound of each control that the essential rows and the point velocity bounds
  // (kCapKind, which a working set takes only near their bound) give alone (with y >= 0). A control
  // whose bound is far above its value (kLooseBound times) is held only by rows a working set
  // may leave out (a boundary value where the tangent and the curvature vanish is held only by
  // its cell's jerk rows), and a solve without them runs off towards infinite speed there: the
  // working set keeps every row over such a control.
  std::vector<double> essential_bound(static_cast<size_t>(p.n), std::numeric_limits<double>::infinity());
  for (size_t r = 0; r < p.rows.size(); ++r) {
    const internal::BandedRow& row = p.rows[r];
    if (!(p.essential[r] || p.rows[r].kind == internal::kCapKind) || !(p.h[r] > 0.0)) continue;
    bool nonnegative = true;
    for (int t = 0; t < row.count; ++t) nonnegative = nonnegative && row.v[t] >= 0.0;
    if (!nonnegative) continue;
    for (int t = 0; t < row.count; ++t) {
      double& bound = essential_bound[static_cast<size_t>(row.first + t)];
      if (row.v[t] > 0.0) bound = std::min(bound, p.h[r] / row.v[t]);
    }
  }
  for (const internal::BandedRow& row : p.rows) p.bandwidth = std::max(p.bandwidth, row.count - 1);
  const size_t d_rows = p.rows.size();
  const size_t static_rows = d_rows + cell_rows;  // in ids
  // Each cell row's state this round (by id - d_rows): waiting, in p, or none (a jerk row that
  // holds for every b >= 0).
  enum : char { kWaiting = 0, kInP = 1, kNone = 2 };
  std::vector<char>& state = workspace->row_state;
  state.assign(cell_rows + templates.jerk_rows.size(), kWaiting);
  size_t waiting = 0;
  // The constant part of b at every grid value, and its free part at some y (the rows' values).
  std::vector<double> constant(d.grid.size()), free_b(d.grid.size());
  for (size_t g = 0; g < d.grid.size(); ++g) constant[g] = p.grid_form[g].constant;
  const auto set_free_b = [&](const std::vector<double>& yy) {
    for (size_t g = 0; g < d.grid.size(); ++g) free_b[g] = p.grid_form[g].Value(yy) - constant[g];
  };
  // Every waiting row flat, by id - d_rows: its coefficients over its cell's three grid values and
  // H = 1 - sum_j coef[j] constant_j, the bound of its free part (AppendRow scales a row by
  // 1 / |H|; H <= 0 makes it essential). The cell rows' once, the jerk rows' at each linearization:
  // the passes below read them two or three times per linearization (computed in each pass from
  // the templates, the solve took 57.6 M instructions at m = 10, K = 50; 55.2 M this way). Kept in
  // the workspace (see SolveWorkspace).
  using FlatRow = internal::WaitingRow;
  std::vector<FlatRow>& flat = workspace->waiting_rows;
  flat.resize(cell_rows + templates.jerk_rows.size());
  const auto set_flat = [&](size_t i, int g0, const std::array<double, 3>& coef) {
    const size_t g = static_cast<size_t>(g0);
    flat[i] = {coef, 1.0 - coef[0] * constant[g] - coef[1] * constant[g + 1] - coef[2] * constant[g + 2], g0};
  };
  for (size_t ci = 0; ci < cell_rows; ++ci) set_flat(ci, templates.cell_rows[ci].g0, templates.cell_rows[ci].coef);
  const auto set_jerk_flat = [&](const std::vector<double>& at) {
    JerkCoefficients jerk_coefficients(d, at);
    for (size_t ti = 0; ti < templates.jerk_rows.size(); ++ti) {
      const internal::JerkRowTemplate& t = templates.jerk_rows[ti];
      set_flat(cell_rows + ti, t.g0, jerk_coefficients(t));
    }
  };
  // A flat row's free part at the y of set_free_b.
  const auto row_value = [&](const FlatRow& r) {
    const size_t g = static_cast<size_t>(r.g0);
    return r.coef[0] * free_b[g] + r.coef[1] * free_b[g + 1] + r.coef[2] * free_b[g + 2];
  };
  // Every cell's map, once (the first grid value g0 of each cell with rows; map_failed: MapCell
  // refused it, and its rows are refused when taken).
  std::vector<size_t> cells;
  std::vector<char> map_failed(d.grid.size(), 0);
  const auto map = [&](int g0) {
    const size_t g = static_cast<size_t>(g0);
    if (mapped[g]) return;
    mapped[g] = 1;
    cells.push_back(g);
    map_failed[g] = !p.MapCell(g0, &cell_map[g]);
  };
  for (const int g0 : templates.cells) map(g0);
  // Per cell: whether its map has a term over a marked control (TouchesMarked for the cell).
  std::vector<char> cell_marked(d.grid.size(), 0);
  const auto mark_cells = [&](const std::vector<char>& marked) {
    for (const size_t g : cells) {
      bool touches = false;
      if (!map_failed[g]) {
        const internal::BandedProblem::CellMap& map = cell_map[g];
        for (int t = 0; t < map.count && !touches; ++t) touches = marked[static_cast<size_t>(map.first + t)] != 0;
      }
      cell_marked[g] = touches;
    }
  };
  // Puts the waiting rows `ids` (by id - d_rows, in order) into p (kept by the solves); false when
  // one spans too many control values or is constant and violated.
  std::vector<char> keep;
  std::vector<size_t> ids;
  const auto materialize = [&](const std::vector<size_t>& which) {
    for (const size_t i : which) {
      const FlatRow& r = flat[i];
      const size_t g = static_cast<size_t>(r.g0);
      if (map_failed[g]) return false;
      p.kind = static_cast<int>(i < cell_rows ? templates.cell_rows[i].kind : LinearRow::Kind::kJerk);
      p.next_id = static_cast<int>(d_rows + i);
      const size_t before = p.rows.size();
      if (!p.AddCellRow(cell_map[g], r.coef.data(), 1.0)) return false;
      if (p.rows.size() > before) {
        p.bandwidth = std::max(p.bandwidth, p.rows.back().count - 1);
        keep.push_back(1);
      }
      state[i] = kInP;
      --waiting;
    }
    return true;
  };
  // The waiting rows (by id - d_rows) that `take` picks, in order, into p.
  const auto take_waiting = [&](auto&& take) {
    ids.clear();
    for (size_t i = 0; i < flat.size(); ++i) {
      if (state[i] == kWaiting && take(i, flat[i])) ids.push_back(i);
    }
    return materialize(ids);
  };
  const std::string too_wide = "a row over more than four control values, or a constant one violated";
  // The first start: the control values of the guess.
  std::vector<double> y(static_cast<size_t>(p.n));
  for (int v = 0; v < p.n; ++v) y[static_cast<size_t>(v)] = d.controls->FromGrid(v, linearization);
  double best = std::numeric_limits<double>::infinity();
  out->build_seconds += SecondsSince(start);
  const int base_bandwidth = p.bandwidth;
  // The last solve's multipliers by row id (NaN: not in it).
  std::vector<double>& z_by_id = workspace->multipliers;
  z_by_id.clear();
  std::vector<double> padded;  // y with zeros past its end, for BandedRow::PaddedValue
  // From a jerk-limited answer (the coarse programme's) the first solve starts as a warm one, with
  // no multipliers yet (kWarmSlack, not kGuessSlack: m = 10, K = 50, 111 M -> 103 M instructions).
  if (jerk_aware) z_by_id.assign(static_rows + templates.jerk_rows.size(), std::nan(""));
  // 1 when the first solve, from the jerk-free guess, is a loose one (its T is out->history[0]).
  const size_t loose_solves = problem.max_scp_iterations > 1 && !jerk_aware ? 1 : 0;
  for (int n = 0; n < problem.max_scp_iterations; ++n) {
    const bool first_loose = n == 0 && loose_solves == 1;
    start = Clock::now();
    p.rows.resize(d_rows);
    p.h.resize(d_rows);
    p.essential.resize(d_rows);
    p.id.resize(d_rows);
    p.bandwidth = base_bandwidth;
    std::fill(state.begin(), state.end(), kWaiting);
    waiting = state.size();
    // The working set: the essential rows and those near their bound at the start: kGuessFraction
    // for the first solve, kWorkingSetFraction after it. (The general path takes
    // kUnsettledFraction while T still moves by more than kWorkingSetSettled; from a warm start
    // the tighter set costs fewer iterations: on the default plan, the third solve took 25,585 rows
    // and 15 iterations with it, 9,246 and 12 without.)
    const size_t h = out->history.size();
    const double fraction = h == 0 ? kGuessFraction : kWorkingSetFraction;
    std::vector<char> loose(static_cast<size_t>(p.n), 0);
    for (int c = 0; c < p.n; ++c) {
      loose[static_cast<size_t>(c)] =
          essential_bound[static_cast<size_t>(c)] > kLooseBound * std::max(y[static_cast<size_t>(c)], 0.0);
    }
    keep.assign(p.rows.size(), 0);
    // A first solve from the jerk-free guess, which says nothing of where the jerk rows will bind,
    // takes all of them; one from the coarse programme's jerk-limited answer only those near
    // their bound there. Template rows join as d's rows would: essential (H <= 0), near their
    // bound, or over a loose control.
    PadForRows(y, &padded);
    for (size_t r = 0; r < p.rows.size(); ++r) {
      keep[r] = p.essential[r] || p.rows[r].PaddedValue(padded.data()) >= fraction * p.h[r] ||
                TouchesMarked(p.rows[r], loose);
    }
    set_free_b(y);
    set_jerk_flat(linearization);
    mark_cells(loose);
    const bool every_jerk_row = h == 0 && !jerk_aware;
    // From a jerk-limited start (the coarse programme's answer) the first solve takes a velocity or
    // acceleration row only when it is also within kGroupFraction of the nearest row of its cell
    // and kind (relative to their bounds): a cell near a bound has every Bernstein coefficient of
    // that limit near it, and the nearest few hold the others at the answer. group_best: that
    // nearest value, by cell row (rows of one cell and kind are consecutive).
    std::vector<double>& group_best = workspace->group_best;
    const bool by_group = jerk_aware && h == 0;
    if (by_group) {
      group_best.resize(cell_rows);
      for (size_t b = 0, e = 0; b < cell_rows; b = e) {
        const internal::GridRow& first_row = templates.cell_rows[b];
        double best_value = -std::numeric_limits<double>::infinity();
        for (e = b; e < cell_rows && templates.cell_rows[e].g0 == first_row.g0 &&
                    templates.cell_rows[e].kind == first_row.kind;
             ++e) {
          if (flat[e].H > 0.0)
            best_value = std::max(best_value, row_value(flat[e]) / flat[e].H);  // (H <= 0: taken anyway)
        }
        std::fill(group_best.begin() + static_cast<std::ptrdiff_t>(b),
                  group_best.begin() + static_cast<std::ptrdiff_t>(e), best_value);
      }
    }
    const bool taken = take_waiting([&](size_t i, const FlatRow& r) {
      if (r.coef[0] <= 0.0 && r.coef[1] <= 0.0 && r.coef[2] <= 0.0) {  // holds for b >= 0
        state[i] = kNone;
        --waiting;
        return false;
      }
      if (thin_jerk && i >= cell_rows && templates.jerk_rows[i - cell_rows].thin) {
        state[i] = kNone;
        --waiting;
        return false;
      }
      const size_t g = static_cast<size_t>(r.g0);
      if (map_failed[g] || !(r.H > 0.0) || (every_jerk_row && i >= cell_rows) || cell_marked[g]) return true;
      const double value = row_value(r);
      return value >= fraction * r.H && (!by_group || i >= cell_rows || value >= kGroupFraction * group_best[i] * r.H);
    });
    if (!taken) {
      out->why = too_wide;
      return false;
    }
    out->build_seconds += SecondsSince(start);
    internal::BandedIpmOutcome outcome;
    std::vector<double> values;  // the rows' values at a round's answer
    for (int round = 0;; ++round) {
      start = Clock::now();
      // Every solve starts from the previous answer (the guess for the first) and the previous
      // multipliers (none for the first).
      // The first solve, from the jerk-free guess, only chooses the next linearization and start:
      // it stops at kFirstSolveTolerance and is never the answer.
      internal::BandedIpmSettings solve_settings = settings;
      if (first_loose) {
        solve_settings.tolerance = std::max(settings.tolerance, kFirstSolveTolerance);
        solve_settings.gap_tolerance = std::max(settings.gap_tolerance, kFirstSolveTolerance);
      }
      // The working set's rows of p, in place (copying them out was 13% of the 100 m forest's
      // build time).
      outcome = internal::SolveBandedProblem(p, y, solve_settings, &z_by_id, &workspace->ipm, &keep);
      out->solve_seconds += SecondsSince(start);
      out->iterations += outcome.iterations;
      out->rows = outcome.rows;
      if (outcome.kind == internal::BandedIpmOutcome::Kind::kOptimal) {
        z_by_id.assign(static_rows + templates.jerk_rows.size(), std::nan(""));
        for (size_t r = 0; r < p.rows.size(); ++r) {
          if (keep[r]) z_by_id[static_cast<size_t>(p.id[r])] = outcome.z[r];
        }
      }
      const bool all =
          waiting == 0 && std::count(keep.begin(), keep.end(), 1) == static_cast<std::ptrdiff_t>(keep.size());
      if (outcome.kind != internal::BandedIpmOutcome::Kind::kOptimal) {
        if (all) {
          // The general path decides. (Keeping an earlier answer instead, as the general path
          // does after its own failures, returned one 50% above Ipopt's T in the property sweep:
          // the structured path's first answers are linearized at the jerk-free guess.)
          out->why = outcome.message;
          return false;
        }
        // The same solve with every row decides.
        std::fill(keep.begin(), keep.end(), 1);
        if (!take_waiting([](size_t, const FlatRow&) { return true; })) {
          out->why = too_wide;
          return false;
        }
        continue;
      }
      // Rows left out that the answer violates (by more than the worst kept row: the solver meets
      // its rows only to its tolerance) join the set with every row near its bound at the answer
      // (kWorkingSetFraction) and the jerk rows near them (kViolatedReach; every row of every cell
      // that has a violated row, as GrowWorkingSet adds, took 2.4 x more rows to the next round
      // on the benchmark's curves); the last round takes every row.
      start = Clock::now();
      // Every row's value at the answer, once per round.
      values.resize(p.rows.size());
      PadForRows(outcome.y, &padded);
      double given = 0.0;
      for (size_t r = 0; r < p.rows.size(); ++r) {
        values[r] = p.rows[r].PaddedValue(padded.data());
        if (keep[r]) given = std::max(given, values[r] - p.h[r]);
      }
      const auto left_out_violated = [&](size_t r) { return !keep[r] && values[r] - p.h[r] > given; };
      // The waiting rows' values at the answer: violated by more than `given`, in p's scaled
      // units, the controls within kViolatedReach of it are marked: every jerk row over them joins.
      set_free_b(outcome.y);
      std::vector<char> near(static_cast<size_t>(p.n), 0);
      bool violated = false;
      const auto mark = [&](int first, int count) {
        violated = true;
        const int lo = std::max(0, first - kViolatedReach);
        const int hi = std::min(p.n - 1, first + count - 1 + kViolatedReach);
        for (int c = lo; c <= hi; ++c) near[static_cast<size_t>(c)] = 1;
      };
      for (size_t r = 0; r < p.rows.size(); ++r) {
        if (left_out_violated(r)) mark(p.rows[r].first, p.rows[r].count);
      }
      for (size_t i = 0; i < flat.size(); ++i) {
        // (H > 0: a row with H <= 0 is essential and in p.) (value - H) / H > given, undivided.
        const FlatRow& r = flat[i];
        if (state[i] == kWaiting && row_value(r) - r.H > given * r.H) {
          const internal::BandedProblem::CellMap& map = cell_map[static_cast<size_t>(r.g0)];
          mark(map.first, map.count);
        }
      }
      if (violated) {
        for (size_t r = 0; r < p.rows.size(); ++r) {
          const bool add = round + 1 >= kMaxWorkingSetRounds || values[r] >= kWorkingSetFraction * p.h[r] ||
                           (p.id[r] >= static_cast<int>(static_rows) && TouchesMarked(p.rows[r], near));
          keep[r] = keep[r] || add;
        }
        mark_cells(near);
        const bool last_round = round + 1 >= kMaxWorkingSetRounds;
        const bool added = take_waiting([&](size_t i, const FlatRow& r) {
          return last_round || row_value(r) >= kWorkingSetFraction * r.H ||
                 (i >= cell_rows && cell_marked[static_cast<size_t>(r.g0)]);
        });
        if (!added) {
          out->why = too_wide;
          return false;
        }
        y = outcome.y;
      }
      out->build_seconds += SecondsSince(start);
      if (!violated) break;
    }
    start = Clock::now();
    std::vector<double> answer = GridValues(d, outcome.x);
    // What linearizing again at this answer would gain (see PredictedGain), for the stopping
    // test below; only after a solve whose answer counts.
    const double predicted = first_loose ? std::numeric_limits<double>::infinity()
                                         : PredictedGain(d, templates, static_rows, z_by_id, linearization, answer);
    linearization = std::move(answer);
    double T = 0.0;
    try {
      T = ProfileTime(d, linearization);
    } catch (const std::invalid_argument& e) {
      // Values that make no profile (a knot rounded below zero): the general path decides, or
      // the best answer so far stays.
      out->why = std::string("structured path: the solution makes no profile: ") + e.what();
      return false;
    }
    out->build_seconds += SecondsSince(start);
    out->history.push_back(T);
    if (!first_loose && T < best) {
      best = T;
      out->x = std::move(outcome.x);
    }
    y = std::move(outcome.y);
    // The stopping tests read the T of the solves whose answer counts: a loose first solve's is
    // too rough (up to kFirstSolveTolerance).
    if (first_loose) continue;
    const double* t = out->history.data() + loose_solves;
    const size_t k = out->history.size() - loose_solves;
    if (k >= 2 && std::abs(t[k - 2] - T) <= problem.scp_tolerance * T) break;
    // The next solve's gain predicted to first order is far below scp_tolerance: it would only
    // confirm this answer (on the default plan it saved the fourth solve, whose T moved by 2e-6).
    if (std::abs(predicted) <= kPredictedFraction * problem.scp_tolerance * T) break;
    // The programme converges geometrically (on the planner's curves T moves by 2.5%, 0.46%,
    // 0.012%, then 1e-6): with the last two steps shrinking at a rate r <= kScpRate, what is left
    // to gain is at most the last step times r / (1 - r) while the rate holds; stop when that is
    // below scp_tolerance (it saved the confirming solve, one in five, on the planner benchmark).
    if (k >= 3) {
      const double last = std::abs(t[k - 1] - t[k - 2]);
      const double before = std::abs(t[k - 2] - t[k - 3]);
      const double rate = before > 0.0 ? last / before : 1.0;
      if (rate <= kScpRate && last * rate / (1.0 - rate) <= problem.scp_tolerance * T) break;
    }
  }
  return !out->x.empty();
}

}  // namespace timeopt::internal
