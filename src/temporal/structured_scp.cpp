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
      if (t.rest_far == internal::kRampTemplate) {
        // A ramp cell's rows are in q = rho_j b_j: the largest q on the cell.
        const int piece = internal::PieceOf(d_, t.g0);
        bbar = internal::RampLinearizationPoint(internal::RampFrameOf(d_, piece, (t.g0 - d_.GridIndex(piece, 0)) / 2),
                                                lb, floor);
      } else if (t.rest_far < 0) {
        bbar = internal::LinearizationPoint(lb, floor);
      } else {
        const double alpha = lb[1], far = lb[t.rest_far];
        const int piece = internal::PieceOf(d_, t.g0);
        const std::vector<double>& e = d_.cell_edges[static_cast<size_t>(piece)];
        const size_t k = static_cast<size_t>((t.g0 - d_.GridIndex(piece, 0)) / 2);
        bbar = std::max({alpha + (far - alpha) * t.w0(), alpha + (far - alpha) * t.w1(),
                         internal::RestCellFloor(floor, e[k + 1] - e[k])});
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

namespace {

// One run of the structured programme (SolveStructuredScp). The banded problem p holds d's rows;
// the rows over a regular cell's three grid values, sum_j coef[j] b_{g0 + j} <= 1 (the velocity
// and acceleration templates, and the jerk rows of each linearization), go into p only when a
// solve takes them: on the benchmark's curves (m = 10, K = 50) a solve took 6,340 of 24,553
// velocity and acceleration rows and 978 of 9,141 jerk rows, and building every one of them was
// 10% of the whole solve. The others wait, tested at each answer on the grid values straight
// from their templates (a list of them, written and read again, cost more than it saved). Ids:
// d's rows first, then the cell rows, then the jerk rows (z_by_id, PredictedGain).
class StructuredProgramme {
 public:
  StructuredProgramme(const TemporalProblem& problem, const TemporalDiscretization& d,
                      const internal::JerkTemplates& templates, const internal::BandedIpmSettings& settings,
                      internal::SolveWorkspace* workspace, StructuredScp* out, bool thin_jerk)
      : problem_(problem),
        d_(d),
        templates_(templates),
        settings_(settings),
        workspace_(*workspace),
        out_(*out),
        thin_jerk_(thin_jerk),
        p_(workspace->problem),
        cell_map_(workspace->cell_maps),
        state_(workspace->row_state),
        flat_(workspace->waiting_rows),
        z_by_id_(workspace->multipliers),
        cell_rows_(templates.cell_rows.size()) {}

  // The whole programme from `linearization`; see SolveStructuredScp.
  bool Run(std::vector<double> linearization, bool jerk_aware) {
    linearization_ = std::move(linearization);
    jerk_aware_ = jerk_aware;
    if (!Prepare()) return false;
    for (int n = 0; n < problem_.max_scp_iterations; ++n) {
      const bool first_loose = n == 0 && loose_solves_ == 1;
      if (!TakeFirstWorkingSet()) return false;
      internal::BandedIpmOutcome outcome;
      if (!SolveWithWorkingSet(first_loose, &outcome)) return false;
      const Clock::time_point start = Clock::now();
      std::vector<double> answer = GridValues(d_, outcome.x);
      // What linearizing again at this answer would gain (see PredictedGain), for the stopping
      // test below; only after a solve whose answer counts.
      const double predicted = first_loose
                                   ? std::numeric_limits<double>::infinity()
                                   : PredictedGain(d_, templates_, static_rows_, z_by_id_, linearization_, answer);
      linearization_ = std::move(answer);
      double T = 0.0;
      try {
        T = ProfileTime(d_, linearization_);
      } catch (const std::invalid_argument& e) {
        // Values that make no profile (a knot rounded below zero): the general path decides, or
        // the best answer so far stays.
        out_.why = std::string("structured path: the solution makes no profile: ") + e.what();
        return false;
      }
      out_.build_seconds += SecondsSince(start);
      out_.history.push_back(T);
      if (!first_loose && T < best_) {
        best_ = T;
        out_.x = std::move(outcome.x);
      }
      y_ = std::move(outcome.y);
      // The stopping tests read the T of the solves whose answer counts: a loose first solve's is
      // too rough (up to kFirstSolveTolerance).
      if (!first_loose && Settled(T, predicted)) break;
    }
    return !out_.x.empty();
  }

 private:
  using FlatRow = internal::WaitingRow;
  // Each cell row's state in a round (by id - d_rows): waiting, in p, or none (a jerk row that
  // holds for every b >= 0).
  enum : char { kWaiting = 0, kInP = 1, kNone = 2 };

  // p from d, the cells' maps, the waiting rows' flat forms and the first start y: false (why in
  // out) when the structured path cannot take d.
  bool Prepare() {
    const Clock::time_point start = Clock::now();
    // p: every row (in the workspace, whose memory the previous programme has touched already); a
    // solve takes the working set `keep` of them.
    if (!internal::BuildBandedProblem(d_, &p_, &out_.why)) return false;
    // Every regular cell's grid values as forms on its window of control values, once (by g0).
    cell_map_.resize(d_.grid.size());
    mapped_.assign(d_.grid.size(), 0);
    // Room for every row at once: one allocation, not a copy of ~1 MB per growth.
    p_.Reserve(p_.rows.size() + cell_rows_ + templates_.jerk_rows.size());
    // The upper bound of each control that the essential rows and the point velocity bounds
    // (kCapKind, which a working set takes only near their bound) give alone (with y >= 0). A control
    // whose bound is far above its value (kLooseBound times) is held only by rows a working set
    // may leave out (a boundary value where the tangent and the curvature vanish is held only by
    // its cell's jerk rows), and a solve without them runs off towards infinite speed there: the
    // working set keeps every row over such a control.
    essential_bound_.assign(static_cast<size_t>(p_.n), std::numeric_limits<double>::infinity());
    for (size_t r = 0; r < p_.rows.size(); ++r) {
      const internal::BandedRow& row = p_.rows[r];
      if (!(p_.essential[r] || p_.rows[r].kind == internal::kCapKind) || !(p_.h[r] > 0.0)) continue;
      bool nonnegative = true;
      for (int t = 0; t < row.count; ++t) nonnegative = nonnegative && row.v[t] >= 0.0;
      if (!nonnegative) continue;
      for (int t = 0; t < row.count; ++t) {
        double& bound = essential_bound_[static_cast<size_t>(row.first + t)];
        if (row.v[t] > 0.0) bound = std::min(bound, p_.h[r] / row.v[t]);
      }
    }
    for (const internal::BandedRow& row : p_.rows) p_.bandwidth = std::max(p_.bandwidth, row.count - 1);
    d_rows_ = p_.rows.size();
    static_rows_ = d_rows_ + cell_rows_;  // in ids
    state_.assign(cell_rows_ + templates_.jerk_rows.size(), kWaiting);
    waiting_ = 0;
    // The constant part of b at every grid value, and its free part at some y (the rows' values).
    constant_.resize(d_.grid.size());
    free_b_.resize(d_.grid.size());
    for (size_t g = 0; g < d_.grid.size(); ++g) constant_[g] = p_.grid_form[g].constant;
    // Every waiting row flat, by id - d_rows: its coefficients over its cell's three grid values and
    // H = 1 - sum_j coef[j] constant_j, the bound of its free part (AppendRow scales a row by
    // 1 / |H|; H <= 0 makes it essential). The cell rows' once, the jerk rows' at each linearization:
    // the passes below read them two or three times per linearization (computed in each pass from
    // the templates, the solve took 57.6 M instructions at m = 10, K = 50; 55.2 M this way). Kept in
    // the workspace (see SolveWorkspace).
    flat_.resize(cell_rows_ + templates_.jerk_rows.size());
    for (size_t ci = 0; ci < cell_rows_; ++ci) {
      SetFlat(ci, templates_.cell_rows[ci].g0, templates_.cell_rows[ci].coef);
    }
    // Every cell's map, once (the first grid value g0 of each cell with rows; map_failed: MapCell
    // refused it, and its rows are refused when taken).
    map_failed_.assign(d_.grid.size(), 0);
    for (const int g0 : templates_.cells) Map(g0);
    cell_marked_.assign(d_.grid.size(), 0);
    // The first start: the control values of the guess.
    y_.resize(static_cast<size_t>(p_.n));
    for (int v = 0; v < p_.n; ++v) y_[static_cast<size_t>(v)] = d_.controls->FromGrid(v, linearization_);
    out_.build_seconds += SecondsSince(start);
    base_bandwidth_ = p_.bandwidth;
    // The last solve's multipliers by row id (NaN: not in it).
    z_by_id_.clear();
    // From a jerk-limited answer (the coarse programme's) the first solve starts as a warm one, with
    // no multipliers yet (kWarmSlack, not kGuessSlack: m = 10, K = 50, 111 M -> 103 M instructions).
    if (jerk_aware_) z_by_id_.assign(static_rows_ + templates_.jerk_rows.size(), std::nan(""));
    // 1 when the first solve, from the jerk-free guess, is a loose one (its T is out->history[0]).
    loose_solves_ = problem_.max_scp_iterations > 1 && !jerk_aware_ ? 1 : 0;
    return true;
  }

  void SetFreeB(const std::vector<double>& yy) {
    for (size_t g = 0; g < d_.grid.size(); ++g) free_b_[g] = p_.grid_form[g].Value(yy) - constant_[g];
  }
  void SetFlat(size_t i, int g0, const std::array<double, 3>& coef) {
    const size_t g = static_cast<size_t>(g0);
    flat_[i] = {coef, 1.0 - coef[0] * constant_[g] - coef[1] * constant_[g + 1] - coef[2] * constant_[g + 2], g0};
  }
  void SetJerkFlat(const std::vector<double>& at) {
    JerkCoefficients jerk_coefficients(d_, at);
    for (size_t ti = 0; ti < templates_.jerk_rows.size(); ++ti) {
      const internal::JerkRowTemplate& t = templates_.jerk_rows[ti];
      SetFlat(cell_rows_ + ti, t.g0, jerk_coefficients(t));
    }
  }
  // A flat row's free part at the y of SetFreeB.
  double RowValue(const FlatRow& r) const {
    const size_t g = static_cast<size_t>(r.g0);
    return r.coef[0] * free_b_[g] + r.coef[1] * free_b_[g + 1] + r.coef[2] * free_b_[g + 2];
  }
  void Map(int g0) {
    const size_t g = static_cast<size_t>(g0);
    if (mapped_[g]) return;
    mapped_[g] = 1;
    cells_.push_back(g);
    map_failed_[g] = !p_.MapCell(g0, &cell_map_[g]);
  }
  // Per cell: whether its map has a term over a marked control (TouchesMarked for the cell).
  void MarkCells(const std::vector<char>& marked) {
    for (const size_t g : cells_) {
      bool touches = false;
      if (!map_failed_[g]) {
        const internal::BandedProblem::CellMap& map = cell_map_[g];
        for (int t = 0; t < map.count && !touches; ++t) touches = marked[static_cast<size_t>(map.first + t)] != 0;
      }
      cell_marked_[g] = touches;
    }
  }
  // Puts the waiting rows `which` (by id - d_rows, in order) into p (kept by the solves); false when
  // one spans too many control values or is constant and violated.
  bool Materialize(const std::vector<size_t>& which) {
    for (const size_t i : which) {
      const FlatRow& r = flat_[i];
      const size_t g = static_cast<size_t>(r.g0);
      if (map_failed_[g]) return false;
      p_.kind = static_cast<int>(i < cell_rows_ ? templates_.cell_rows[i].kind : LinearRow::Kind::kJerk);
      p_.next_id = static_cast<int>(d_rows_ + i);
      const size_t before = p_.rows.size();
      if (!p_.AddCellRow(cell_map_[g], r.coef.data(), 1.0)) return false;
      if (p_.rows.size() > before) {
        p_.bandwidth = std::max(p_.bandwidth, p_.rows.back().count - 1);
        keep_.push_back(1);
      }
      state_[i] = kInP;
      --waiting_;
    }
    return true;
  }
  // The waiting rows (by id - d_rows) that `take` picks, in order, into p.
  template <typename Take>
  bool TakeWaiting(Take&& take) {
    ids_.clear();
    for (size_t i = 0; i < flat_.size(); ++i) {
      if (state_[i] == kWaiting && take(i, flat_[i])) ids_.push_back(i);
    }
    return Materialize(ids_);
  }
  bool TooWide() {
    out_.why = "a row over more than four control values, or a constant one violated";
    return false;
  }

  // A solve's first working set, from p reset to d's rows: the essential rows and those near
  // their bound at the start (kGuessFraction for the first solve, kWorkingSetFraction after it),
  // with the jerk rows linearized at linearization_.
  bool TakeFirstWorkingSet() {
    const Clock::time_point start = Clock::now();
    p_.rows.resize(d_rows_);
    p_.h.resize(d_rows_);
    p_.essential.resize(d_rows_);
    p_.id.resize(d_rows_);
    p_.bandwidth = base_bandwidth_;
    std::fill(state_.begin(), state_.end(), kWaiting);
    waiting_ = state_.size();
    // (The general path takes kUnsettledFraction while T still moves by more than
    // kWorkingSetSettled; from a warm start the tighter set costs fewer iterations: on the default
    // plan, the third solve took 25,585 rows and 15 iterations with it, 9,246 and 12 without.)
    const size_t h = out_.history.size();
    const double fraction = h == 0 ? kGuessFraction : kWorkingSetFraction;
    std::vector<char> loose(static_cast<size_t>(p_.n), 0);
    for (int c = 0; c < p_.n; ++c) {
      loose[static_cast<size_t>(c)] =
          essential_bound_[static_cast<size_t>(c)] > kLooseBound * std::max(y_[static_cast<size_t>(c)], 0.0);
    }
    keep_.assign(p_.rows.size(), 0);
    // A first solve from the jerk-free guess, which says nothing of where the jerk rows will bind,
    // takes all of them; one from the coarse programme's jerk-limited answer only those near
    // their bound there. Template rows join as d's rows would: essential (H <= 0), near their
    // bound, or over a loose control.
    PadForRows(y_, &padded_);
    for (size_t r = 0; r < p_.rows.size(); ++r) {
      keep_[r] = p_.essential[r] || p_.rows[r].PaddedValue(padded_.data()) >= fraction * p_.h[r] ||
                 TouchesMarked(p_.rows[r], loose);
    }
    SetFreeB(y_);
    SetJerkFlat(linearization_);
    MarkCells(loose);
    const bool every_jerk_row = h == 0 && !jerk_aware_;
    // From a jerk-limited start (the coarse programme's answer) the first solve takes a velocity or
    // acceleration row only when it is also within kGroupFraction of the nearest row of its cell
    // and kind (relative to their bounds): a cell near a bound has every Bernstein coefficient of
    // that limit near it, and the nearest few hold the others at the answer. group_best: that
    // nearest value, by cell row (rows of one cell and kind are consecutive).
    std::vector<double>& group_best = workspace_.group_best;
    const bool by_group = jerk_aware_ && h == 0;
    if (by_group) {
      group_best.resize(cell_rows_);
      for (size_t b = 0, e = 0; b < cell_rows_; b = e) {
        const internal::GridRow& first_row = templates_.cell_rows[b];
        double best_value = -std::numeric_limits<double>::infinity();
        for (e = b; e < cell_rows_ && templates_.cell_rows[e].g0 == first_row.g0 &&
                    templates_.cell_rows[e].kind == first_row.kind;
             ++e) {
          if (flat_[e].H > 0.0)
            best_value = std::max(best_value, RowValue(flat_[e]) / flat_[e].H);  // (H <= 0: taken anyway)
        }
        std::fill(group_best.begin() + static_cast<std::ptrdiff_t>(b),
                  group_best.begin() + static_cast<std::ptrdiff_t>(e), best_value);
      }
    }
    const bool taken = TakeWaiting([&](size_t i, const FlatRow& r) {
      if (r.coef[0] <= 0.0 && r.coef[1] <= 0.0 && r.coef[2] <= 0.0) {  // holds for b >= 0
        state_[i] = kNone;
        --waiting_;
        return false;
      }
      if (thin_jerk_ && i >= cell_rows_ && templates_.jerk_rows[i - cell_rows_].thin) {
        state_[i] = kNone;
        --waiting_;
        return false;
      }
      const size_t g = static_cast<size_t>(r.g0);
      if (map_failed_[g] || !(r.H > 0.0) || (every_jerk_row && i >= cell_rows_) || cell_marked_[g]) return true;
      const double value = RowValue(r);
      return value >= fraction * r.H && (!by_group || i >= cell_rows_ || value >= kGroupFraction * group_best[i] * r.H);
    });
    if (!taken) return TooWide();
    out_.build_seconds += SecondsSince(start);
    return true;
  }

  // The solve of the working set, again with the rows its answer violates (and those near them)
  // until it violates none; false (why in out) when a solve with every row is not optimal.
  bool SolveWithWorkingSet(bool first_loose, internal::BandedIpmOutcome* out_outcome) {
    internal::BandedIpmOutcome& outcome = *out_outcome;
    for (int round = 0;; ++round) {
      Clock::time_point start = Clock::now();
      // Every solve starts from the previous answer (the guess for the first) and the previous
      // multipliers (none for the first).
      // The first solve, from the jerk-free guess, only chooses the next linearization and start:
      // it stops at kFirstSolveTolerance and is never the answer.
      internal::BandedIpmSettings solve_settings = settings_;
      if (first_loose) {
        solve_settings.tolerance = std::max(settings_.tolerance, kFirstSolveTolerance);
        solve_settings.gap_tolerance = std::max(settings_.gap_tolerance, kFirstSolveTolerance);
      }
      // The working set's rows of p, in place (copying them out was 13% of the 100 m forest's
      // build time).
      outcome = internal::SolveBandedProblem(p_, y_, solve_settings, &z_by_id_, &workspace_.ipm, &keep_);
      out_.solve_seconds += SecondsSince(start);
      out_.iterations += outcome.iterations;
      out_.rows = outcome.rows;
      if (outcome.kind == internal::BandedIpmOutcome::Kind::kOptimal) {
        z_by_id_.assign(static_rows_ + templates_.jerk_rows.size(), std::nan(""));
        for (size_t r = 0; r < p_.rows.size(); ++r) {
          if (keep_[r]) z_by_id_[static_cast<size_t>(p_.id[r])] = outcome.z[r];
        }
      }
      const bool all =
          waiting_ == 0 && std::count(keep_.begin(), keep_.end(), 1) == static_cast<std::ptrdiff_t>(keep_.size());
      if (outcome.kind != internal::BandedIpmOutcome::Kind::kOptimal) {
        if (all) {
          // The general path decides. (Keeping an earlier answer instead, as the general path
          // does after its own failures, returned one 50% above Ipopt's T in the property sweep:
          // the structured path's first answers are linearized at the jerk-free guess.)
          out_.why = outcome.message;
          return false;
        }
        // The same solve with every row decides.
        std::fill(keep_.begin(), keep_.end(), 1);
        if (!TakeWaiting([](size_t, const FlatRow&) { return true; })) return TooWide();
        continue;
      }
      start = Clock::now();
      bool violated = false;
      if (!GrowWorkingSet(outcome, round, &violated)) return false;
      out_.build_seconds += SecondsSince(start);
      if (!violated) return true;
    }
  }

  // Rows left out that the answer violates (by more than the worst kept row: the solver meets its
  // rows only to its tolerance) join the set with every row near its bound at the answer
  // (kWorkingSetFraction) and the jerk rows near them (kViolatedReach; every row of every cell
  // that has a violated row, as GrowWorkingSet adds, took 2.4 x more rows to the next round on the
  // benchmark's curves); the last round takes every row. *violated: whether any was (then y is the
  // answer, the next round's start). False (why in out) when a row taken cannot join p.
  bool GrowWorkingSet(const internal::BandedIpmOutcome& outcome, int round, bool* any_violated) {
    // Every row's value at the answer, once per round.
    values_.resize(p_.rows.size());
    PadForRows(outcome.y, &padded_);
    double given = 0.0;
    for (size_t r = 0; r < p_.rows.size(); ++r) {
      values_[r] = p_.rows[r].PaddedValue(padded_.data());
      if (keep_[r]) given = std::max(given, values_[r] - p_.h[r]);
    }
    const auto left_out_violated = [&](size_t r) { return !keep_[r] && values_[r] - p_.h[r] > given; };
    // The waiting rows' values at the answer: violated by more than `given`, in p's scaled
    // units, the controls within kViolatedReach of it are marked: every jerk row over them joins.
    SetFreeB(outcome.y);
    std::vector<char> near(static_cast<size_t>(p_.n), 0);
    bool violated = false;
    const auto mark = [&](int first, int count) {
      violated = true;
      const int lo = std::max(0, first - kViolatedReach);
      const int hi = std::min(p_.n - 1, first + count - 1 + kViolatedReach);
      for (int c = lo; c <= hi; ++c) near[static_cast<size_t>(c)] = 1;
    };
    for (size_t r = 0; r < p_.rows.size(); ++r) {
      if (left_out_violated(r)) mark(p_.rows[r].first, p_.rows[r].count);
    }
    for (size_t i = 0; i < flat_.size(); ++i) {
      // (H > 0: a row with H <= 0 is essential and in p.) (value - H) / H > given, undivided.
      const FlatRow& r = flat_[i];
      if (state_[i] == kWaiting && RowValue(r) - r.H > given * r.H) {
        const internal::BandedProblem::CellMap& map = cell_map_[static_cast<size_t>(r.g0)];
        mark(map.first, map.count);
      }
    }
    if (violated) {
      for (size_t r = 0; r < p_.rows.size(); ++r) {
        const bool add = round + 1 >= kMaxWorkingSetRounds || values_[r] >= kWorkingSetFraction * p_.h[r] ||
                         (p_.id[r] >= static_cast<int>(static_rows_) && TouchesMarked(p_.rows[r], near));
        keep_[r] = keep_[r] || add;
      }
      MarkCells(near);
      const bool last_round = round + 1 >= kMaxWorkingSetRounds;
      const bool added = TakeWaiting([&](size_t i, const FlatRow& r) {
        return last_round || RowValue(r) >= kWorkingSetFraction * r.H ||
               (i >= cell_rows_ && cell_marked_[static_cast<size_t>(r.g0)]);
      });
      if (!added) return TooWide();
      y_ = outcome.y;
    }
    *any_violated = violated;
    return true;
  }

  // The stopping tests after a solve whose answer counts (T, and PredictedGain's prediction).
  bool Settled(double T, double predicted) const {
    const double* t = out_.history.data() + loose_solves_;
    const size_t k = out_.history.size() - loose_solves_;
    if (k >= 2 && std::abs(t[k - 2] - T) <= problem_.scp_tolerance * T) return true;
    // The next solve's gain predicted to first order is far below scp_tolerance: it would only
    // confirm this answer (on the default plan it saved the fourth solve, whose T moved by 2e-6).
    if (std::abs(predicted) <= kPredictedFraction * problem_.scp_tolerance * T) return true;
    // The programme converges geometrically (on the planner's curves T moves by 2.5%, 0.46%,
    // 0.012%, then 1e-6): with the last two steps shrinking at a rate r <= kScpRate, what is left
    // to gain is at most the last step times r / (1 - r) while the rate holds; stop when that is
    // below scp_tolerance (it saved the confirming solve, one in five, on the planner benchmark).
    if (k >= 3) {
      const double last = std::abs(t[k - 1] - t[k - 2]);
      const double before = std::abs(t[k - 2] - t[k - 3]);
      const double rate = before > 0.0 ? last / before : 1.0;
      if (rate <= kScpRate && last * rate / (1.0 - rate) <= problem_.scp_tolerance * T) return true;
    }
    return false;
  }

  const TemporalProblem& problem_;
  const TemporalDiscretization& d_;
  const internal::JerkTemplates& templates_;
  const internal::BandedIpmSettings& settings_;
  internal::SolveWorkspace& workspace_;
  StructuredScp& out_;
  const bool thin_jerk_;
  bool jerk_aware_ = false;
  internal::BandedProblem& p_;
  std::vector<internal::BandedProblem::CellMap>& cell_map_;
  std::vector<char>& state_;
  std::vector<FlatRow>& flat_;
  std::vector<double>& z_by_id_;
  const size_t cell_rows_;
  size_t d_rows_ = 0, static_rows_ = 0, waiting_ = 0, loose_solves_ = 0;
  int base_bandwidth_ = 0;
  std::vector<double> linearization_, y_, essential_bound_, constant_, free_b_;
  std::vector<double> padded_;  // y with zeros past its end, for BandedRow::PaddedValue
  std::vector<double> values_;  // the rows' values at a round's answer
  std::vector<char> mapped_, map_failed_, cell_marked_, keep_;
  std::vector<size_t> cells_, ids_;
  double best_ = std::numeric_limits<double>::infinity();
};

}  // namespace

// The sequential convex programme on the structured path (structured_scp.h; the steps in
// StructuredProgramme).
bool SolveStructuredScp(const TemporalProblem& problem, const TemporalDiscretization& d,
                        const internal::JerkTemplates& templates, std::vector<double> linearization,
                        const internal::BandedIpmSettings& settings, bool jerk_aware,
                        internal::SolveWorkspace* workspace, StructuredScp* out, bool thin_jerk) {
  StructuredProgramme programme(problem, d, templates, settings, workspace, out, thin_jerk);
  return programme.Run(std::move(linearization), jerk_aware);
}

}  // namespace timeopt::internal
