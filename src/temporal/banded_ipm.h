#pragma once

// Library-internal: the structured path of the SOCP backend. The temporal problem of
// discretization.h without equality rows is
//
//   minimize    J(x) = sum over cells [ w 2 ds / (sqrt(b0) + sqrt(b1)) + rho (b1 - b0)^2 / (4 ds) ]
//   subject to  G x <= h   (the linear rows, x >= 0 and x <= var_upper)
//
// with b = scale * x (or a fixed value) at each cell's two grid points: a convex objective over
// the free grid values and linear rows. Every cell and every row touches a few neighbouring values
// along the path, so the Newton system of a primal-dual interior-point method on this problem,
// grad^2 J + G' (Z / S) G, is banded (tridiagonal for the paper's and the certified rows), and one
// iteration is a few passes over the rows plus a banded Cholesky factorization in O(n). The SOCP
// (socp_backend.cpp) is the same problem with sqrt(b) and the cell times lifted into cones; this
// path solves it without the lift, from a reachability start (GreedyProfile in banded_ipm.cpp).
//
// An empty controllable set proves the problem infeasible when it stays empty with every row's
// bound loosened by 1e-6 relative (kInfeasible): far above the solvers' tolerances, so the conic
// solver would say so too, at several times the cost. A borderline one goes to the conic solver.
//
// Used only when it applies (every row over one value or two neighbouring ones: not lambda_a's
// rows, not the jerk-limited mode's equalities, no cone or cubic rows; no cell whose two values are
// both fixed at 0; a reachability profile exists) and trusted only when it ends optimal: anything
// else (the iteration limit, a factorization that breaks down, an infeasible problem, which it
// does not try to certify) is handed to the conic solver, which decides. So statuses never depend
// on this path.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "discretization_internal.h"
#include "discretization.h"

namespace timeopt::internal {

struct BandedIpmSettings {
  // Relative primal and dual residual for optimal (the conic solver's feasibility tolerance).
  double tolerance = 1e-8;
  // s'z relative to J for optimal. J - J* <= s'z at a feasible, dual-feasible point (J is
  // convex), so this bounds the objective's error.
  double gap_tolerance = 1e-10;
  int max_iterations = 60;
  // The largest half-bandwidth of the Newton system it takes on.
  int max_bandwidth = 4;
};

struct BandedIpmOutcome {
  enum class Kind {
    kNotApplicable,  // the problem has equality rows, a wide band, or an infinite cell time
    kOptimal,        // x is the answer to the tolerances
    kGaveUp,         // the conic solver decides (message says why)
    kInfeasible,     // reachability proves it: no profile, even with every bound 1e-6 looser
  };
  Kind kind = Kind::kNotApplicable;
  int iterations = 0;
  int rows = 0;  // inequality rows it solved with, but the unknowns' bounds
  std::string message;
  std::vector<double> x;  // d.num_vars values when optimal
  std::vector<double> y;  // the unknowns when optimal
  std::vector<double> z;  // the rows' multipliers when optimal (one per row of the problem)
};

BandedIpmOutcome SolveBanded(const TemporalDiscretization& d, const BandedIpmSettings& settings);

// The problem in the structured path's own terms, for callers that solve a family of problems
// with the same unknowns (the jerk-limited sequential convex programme): unknowns y (the free
// values, or d.controls' control values), rows G y <= h over at most kMaxRowSpan consecutive
// unknowns and scaled so that h is +-1 or 0, the first n of them the bounds -y <= 0, and the
// cells' time terms with b as forms in y.
inline constexpr int kMaxRowSpan = ControlForm::kMaxTerms;
// The kind of the rows x_v <= var_upper_v (the point velocity bounds). With control values they
// are not essential: a solve takes them when they are near their bound, and an answer that violates
// one is solved again with it.
inline constexpr short kCapKind = -2;
struct BandedRow {
  int first = 0;
  short count = 0;
  short kind = -1;  // the LinearRow::Kind it came from (-1: a bound of the unknowns; kCapKind)
  double v[kMaxRowSpan] = {};
  double Value(const std::vector<double>& y) const {
    double value = 0.0;
    for (int t = 0; t < count; ++t) value += v[t] * y[static_cast<size_t>(first + t)];
    return value;
  }
  // The same over y padded with kMaxRowSpan - 1 finite values past its end (the terms past `count`
  // are 0): a fixed number of terms, for the passes over every row.
  double PaddedValue(const double* y) const {
    const double* x = y + first;
    return (v[0] * x[0] + v[1] * x[1]) + (v[2] * x[2] + v[3] * x[3]);
  }
};
static_assert(kMaxRowSpan == 4, "BandedRow::PaddedValue takes four terms");
struct BandedCell {
  ControlForm b[2];
  double c = 0.0;    // time = c / (sqrt(b0) + sqrt(b1)): 2 ds time_weight
  double reg = 0.0;  // rho / (4 ds): the regularization rho (b1 - b0)^2 / (4 ds)
};
struct BandedProblem {
  int n = 0;
  int bandwidth = 1;
  bool controls = false;  // y are control values (else the free values themselves)
  std::vector<BandedRow> rows;
  std::vector<double> h;
  std::vector<BandedCell> cells;
  std::vector<ControlForm> grid_form;  // b at every grid value
  std::vector<ControlForm> x_form;     // every free value of d
  std::vector<double> cap;             // per unknown: a size for the uniform part of the start
  // Per row: 1 for the rows a working set always keeps (the bounds -y <= 0 and x <= var_upper,
  // rows with h <= 0), which keep every unknown bounded whatever else is left out.
  std::vector<char> essential;
  // Per row: an identity that survives a working set and a new linearization (the multiplier of a row
  // in one solve starts the next; see SolveBandedProblem). AddRow and AppendRow give next_id, or
  // the row's index when next_id < 0.
  std::vector<int> id;
  int next_id = -1;
  int kind = -1;  // the kind AddRow gives its rows
  // Room for `count` rows in rows, h, essential and id.
  void Reserve(size_t count);
  // Back to a default BandedProblem, keeping the vectors' memory.
  void Clear();
  // Appends sum over (free value, coef) <= bound as a row over y; false when it spans more than
  // kMaxRowSpan unknowns or is constant and violated (a constant one that holds is dropped).
  bool AddRow(const std::vector<std::pair<int, double>>& terms, double sign, double bound, bool essential = false);
  // Appends sum_t v[t] y[first + t] <= bound (t < count), scaled so that the bound is +-1 or 0 (a
  // row without terms: false when it is violated, else dropped).
  bool AppendRow(int first, int count, const double (&v)[kMaxRowSpan], double bound);
  // The three consecutive grid values g0, g0 + 1, g0 + 2 (a jerk-limited cell) as forms on one
  // window of unknowns, so that a row over them maps to the unknowns by a 3 x kMaxRowSpan product.
  struct CellMap {
    int first = 0, count = 0;
    double m[3][kMaxRowSpan] = {};
    double constant[3] = {};
  };
  bool MapCell(int g0, CellMap* map) const;
  // Appends sum_j coef[j] b_{g0 + j} <= bound through the cell's map (as AppendRow: false when it
  // is constant and violated).
  bool AddCellRow(const CellMap& map, const double* coef, double bound);
};

// The working memory of SolveBandedProblem (about 12 doubles per row), to keep between
// solves: the sequential convex programme's solves then reuse pages already touched, where fresh
// ones cost a page fault each (measured: 12% of a jerk-limited solve's time, in the kernel). Not
// for two solves at once.
class BandedIpmWorkspace {
 public:
  BandedIpmWorkspace();
  ~BandedIpmWorkspace();
  BandedIpmWorkspace(const BandedIpmWorkspace&) = delete;
  BandedIpmWorkspace& operator=(const BandedIpmWorkspace&) = delete;
  struct Buffers;
  Buffers& buffers() { return *buffers_; }

 private:
  std::unique_ptr<Buffers> buffers_;
};

// The working memory of the structured sequential convex programme (jerk_solver.cpp): its
// problem, its rows' templates and states, and the interior-point solver's vectors. A TemporalSolver keeps
// one from one jerk-limited solve to the next, so that their pages are mapped already.
// A template row of the structured programme over its cell's three grid values while it waits
// outside the problem: coefficients and H, the bound of its free part (jerk_solver.cpp).
struct WaitingRow {
  std::array<double, 3> coef;
  double H;
  int g0;
};
// What the structured programme keeps from one solve to the next. Besides sparing the
// allocations, this keeps its large vectors off fresh pages: where the allocator returns memory
// at once (Dask's workers set MALLOC_TRIM_THRESHOLD_=65536, which also fixes glibc's mmap
// threshold at 128 KiB) every vector of more than 128 KiB allocated per solve was mapped afresh
// and faulted in page by page.
struct SolveWorkspace {
  BandedIpmWorkspace ipm;
  BandedProblem problem;
  JerkTemplates templates, coarse_templates;      // of the grid and of the coarse programme's grid
  std::vector<char> row_state;                    // per template row: waiting, in the problem, or none
  std::vector<WaitingRow> waiting_rows;           // per template row
  std::vector<double> multipliers;                // per row id (SolveStructuredScp's z_by_id)
  std::vector<double> group_best;                 // per template cell row (SolveStructuredScp)
  std::vector<BandedProblem::CellMap> cell_maps;  // per grid value (by a cell's first)
};

// The structured problem of d (rows, cells and forms); false (not applicable) with a reason.
bool BuildBandedProblem(const TemporalDiscretization& d, BandedProblem* out, std::string* why);

// Solves p from y0 (weighted with a uniform profile inside the rows that hold at 0; empty: that
// profile alone). On kOptimal, x holds d's free values (through x_form), y the unknowns and z the
// rows' multipliers. With `warm` (a multiplier per row id, NaN for none: a previous solve of a
// nearby problem; empty: none yet), the start is y0 itself with those multipliers, re-centred.
// With `subset` (one flag per row of p), only the flagged rows and the bounds (the first n rows,
// always) take part; z then holds 0 for the rows left out.
BandedIpmOutcome SolveBandedProblem(const BandedProblem& p, const std::vector<double>& y0,
                                    const BandedIpmSettings& settings, const std::vector<double>* warm = nullptr,
                                    BandedIpmWorkspace* workspace = nullptr, const std::vector<char>* subset = nullptr);

// The passes over the rows go four at a time (AVX2 and FMA) on a processor that has them, else
// two at a time (SSE2, or scalars). SetWideRowPasses(false) makes every solve after it take the
// two-row passes anyway (tests compare the two); it returns whether the wide passes were on.
// Process-wide.
bool SetWideRowPasses(bool on);
// Whether solves take the four-row passes now (on and supported).
bool WideRowPasses();

}  // namespace timeopt::internal
