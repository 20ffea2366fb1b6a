#pragma once

// The solution of a temporal problem on its grid, and the exact map between time and s.
//
// A profile holds b = sdot^2 on a grid of K cells per piece, of length ds = 1 / K (a jerk-limited
// profile's cells may be graded towards rest points: then ds is each cell's own length, CellLength).
// Each cell has a shape (CellShape) that says how b runs between its grid values; with
// sigma = s - s_k in [0, ds]:
//
// - kLinear (profiles from the constructor): b linear, a = sddot constant, sdddot = 0. A cell that
//   starts at time t_k with speed sqrt(b^k) has s(t) = s_k + sqrt(b^k) (t - t_k) + a (t - t_k)^2 / 2,
//   sdot(t) = sqrt(b^k) + a (t - t_k), and takes 2 ds / (sqrt(b^k) + sqrt(b^{k+1})).
// - kQuadratic (jerk-limited profiles): b = b0 + c1 sigma + c2 sigma^2 through the values b0, bm, b1
//   at sigma = 0, ds / 2, ds, so c2 = 2 (b0 - 2 bm + b1) / ds^2, c1 = (-3 b0 + 4 bm - b1) / ds, and
//   sdot = sqrt(b), sddot = b' / 2 = (c1 + 2 c2 sigma) / 2 (linear in s, continuous across cells
//   when the neighbours' slopes of b agree), sdddot = d(sddot)/dt = c2 sdot.
// - kRestStart: from rest (sdot = sddot = 0). With w in [0, 1] the fraction of the cell's time
//   that has passed, sigma = ds w^3 and b = w^4 q(w), q = alpha + beta w linear in w, so that w
//   has a constant second derivative (w' = sqrt(q) / (3 ds)): sdot = w^2 sqrt(q), sddot = w (4 alpha
//   + 5 beta w) / (6 ds), sdddot = (4 alpha + 10 beta w) sqrt(q) / (18 ds^2). q(1) = b1 (b at the
//   far end) and q(2^(-1/3)) = 2^(4/3) bm (b at the middle in s) give alpha and beta; the cell
//   takes t1 = 6 ds / (sqrt(alpha) + sqrt(b1)). beta = 0 (bm = 2^(-4/3) b1) is a constant s-jerk
//   J = 2 b1^1.5 / (9 ds^2) from rest, b = b1 (sigma / ds)^(4/3); beta < 0 lets the s-jerk ease off
//   through the cell, as a curved start needs.
// - kRestEnd: the time mirror, arriving at rest: w is the fraction of the cell's time left,
//   ds - sigma = ds w^3, b = w^4 q(w) with q(1) = b0, sddot = -w (4 alpha + 5 beta w) / (6 ds)
//   (braking, 0 at the end), sdddot as above (positive where the braking eases off).
//
// - kRampStart: a cell of the ramp after a rest start (the cells after a rest cell on a curve), in
//   the coordinate w = s^(1/3) of the piece (s from the piece's start, the rest point): b = w^4 q(w)
//   with q quadratic in w through its values at the cell's ends and at its middle in w, w_m = (w0 +
//   w1) / 2 (so the cell's middle half point is at s = w_m^3, not at its middle in s). Then dw/dt =
//   sqrt(q) / 3, sdot = w^2 sqrt(q), sddot = w (4 q + w q') / 6, sdddot = sqrt(q) (4 q + 6 w q' +
//   w^2 q'') / 18 (q' = dq/dw), and the cell takes 3 times the time of a quadratic cell of length
//   w1 - w0 through the three values of q. A constant s-jerk from rest (q constant) is exact in it,
//   as a regular cell's sddot linear in s is not: its s-jerk is proportional to sdot.
// - kRampEnd: the mirror before a rest end, w = (1 - s)^(1/3) falling along the path: sddot = -w (4 q
//   + w q') / 6, sdot and sdddot as above.
//
// Cell times are closed forms of the integral of 1 / sqrt(b) (see temporal_profile.cpp for the
// forms free of cancellation); AtTime inverts them exactly (closed form for linear and rest cells,
// safeguarded Newton for quadratic ones).

#include <array>
#include <string>
#include <vector>

namespace timeopt {

// How b = sdot^2 runs over one cell (formulas in the header comment above).
enum class CellShape {
  kLinear,     // b linear in s, sddot constant, sdddot = 0 (every cell of a constructor-made profile)
  kQuadratic,  // b quadratic in s through the cell's three half-grid values; sddot linear in s
  kRestStart,  // leaves rest (b = 0 and sddot = 0 at the cell's start) with constant sdddot > 0
  kRestEnd,    // arrives at rest (b = 0 and sddot = 0 at the cell's end) with constant sdddot > 0
  kRampStart,  // after a rest start: b = w^4 q(w), q quadratic in w = s^(1/3) (see above)
  kRampEnd,    // before a rest end: the mirror, w = (1 - s)^(1/3)
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<CellShape, 6> kCellShapes = {
    CellShape::kLinear,  CellShape::kQuadratic, CellShape::kRestStart,
    CellShape::kRestEnd, CellShape::kRampStart, CellShape::kRampEnd,
};
// True for kRestStart and kRestEnd, and for kRampStart and kRampEnd.
inline bool IsRestShape(CellShape shape) { return shape == CellShape::kRestStart || shape == CellShape::kRestEnd; }
inline bool IsRampShape(CellShape shape) { return shape == CellShape::kRampStart || shape == CellShape::kRampEnd; }
const char* ToString(CellShape shape);
// The enumerator named `text` (as ToString writes it) into *shape; false when none is.
bool FromString(const std::string& text, CellShape* shape);

class TemporalProfile {
 public:
  TemporalProfile() = default;
  // A profile of linear cells. b[i] holds the K + 1 grid values of piece i (all pieces the same
  // K >= 1, values >= 0, a cell with b = 0 at both ends is not allowed). Throws
  // std::invalid_argument otherwise.
  explicit TemporalProfile(std::vector<std::vector<double>> b);

  // A jerk-limited profile. half_b[i] holds the 2K + 1 values of piece i at s = j ds / 2 (cell k
  // spans half points 2k, 2k + 1, 2k + 2), shapes[i] the K shapes of its cells (kQuadratic,
  // kRestStart, kRestEnd, kRampStart or kRampEnd; K >= 1 and the same for all pieces). A ramp cell
  // needs b > 0 at its three half points and q >= 0 between them, and lies off the rest point (a
  // kRampStart cell starts after s = 0, a kRampEnd cell ends before s = 1); its middle half point
  // is at its middle in w (see above). Values must be finite and >= 0.
  // A quadratic cell must have b > 0 inside and a finite time (b reaching 0 at an end with zero
  // slope there, e.g. b0 = 0 and c1 = 0, takes forever; b = 0 at both ends with bm > 0 is finite
  // and allowed). A rest-start cell needs b = 0 at its start and b > 0 at its end, a rest-end cell
  // the reverse, and its middle value at least 2^(-5/3) times its far-end value (alpha >= 0 above;
  // 2^(-4/3) times it is a constant s-jerk). Throws std::invalid_argument naming piece and cell.
  // cell_edges (optional): the K + 1 edges of every piece's cells in s, increasing from 0 to 1, for
  // a grid graded towards rest points; the half points are then the cells' middles (a ramp cell's:
  // its middle in w, RampMiddleS). Empty: K equal
  // cells of ds = 1 / K.
  static TemporalProfile JerkLimited(std::vector<std::vector<double>> half_b,
                                     std::vector<std::vector<CellShape>> shapes,
                                     std::vector<std::vector<double>> cell_edges = {});

  // The same motion along the path, `factor` times slower (factor > 0 and finite; below 1:
  // faster): every b divided by factor^2, the shapes and cells unchanged, and the times those of
  // the scaled values (the original's times factor to rounding). Throws std::invalid_argument for
  // another factor.
  TemporalProfile TimeScaled(double factor) const;

  int num_pieces() const { return static_cast<int>(b_.size()); }
  int cells_per_piece() const { return cells_per_piece_; }
  // Where cell k of piece i starts in s (k = K: 1), and its length: 1 / K each unless cell_edges
  // were given (a jerk-limited profile's cells are graded towards rest points).
  double CellStart(int piece, int k) const;
  double CellLength(int piece, int k) const;
  // True for a profile made by JerkLimited.
  bool jerk_limited() const { return !shapes_.empty(); }
  // The cell_edges given to JerkLimited (per piece K + 1 edges in s), empty for equal cells: with
  // half_b() and shape() what rebuilds the same profile (the trajectory file).
  const std::vector<std::vector<double>>& cell_edges() const { return edges_; }
  // b = sdot^2 at grid point k of piece i (half point 2k of a jerk-limited profile).
  double b(int piece, int k) const { return b_[piece][k]; }
  const std::vector<std::vector<double>>& b() const { return b_; }
  // b at half point j = 0..2K of piece i, s = j ds / 2. For a linear profile the odd points are
  // the cell midpoints (b^k + b^{k+1}) / 2.
  double half_b(int piece, int j) const;
  // The shape of cell k of piece i (kLinear for every cell of a constructor-made profile).
  CellShape shape(int piece, int k) const;
  // (b^{k+1} - b^k) / (2 ds): on a linear cell a = sddot; on any other cell the mean of sddot over
  // the cell in s (sddot = b'(s) / 2), not its value anywhere in particular. Use AtS for values.
  double a(int piece, int k) const;

  double total_time() const { return cell_start_.empty() ? 0.0 : cell_start_.back(); }
  std::vector<double> piece_durations() const;
  // Time at which the vehicle passes grid point k of piece i.
  double TimeAt(int piece, int k) const;
  // Time at which the vehicle passes s (clamped to [0, 1]) of piece i: the exact integral of
  // 1 / sdot from the start of the profile.
  double TimeAtS(int piece, double s) const;

  struct Point {
    int piece = 0;
    double s = 0.0;       // in [0, 1] on the piece
    double sdot = 0.0;    // ds/dt, 1/s
    double sddot = 0.0;   // d2s/dt2, 1/s^2 (constant on a linear cell)
    double sdddot = 0.0;  // d3s/dt3, 1/s^3 (0 on a linear cell)
  };
  // The state of the parameter at time t, clamped to [0, total_time()].
  Point AtTime(double t) const;
  // The state at s (clamped to [0, 1]) of piece i, straight from the cell's b(s) without inverting
  // time. A grid point belongs to the cell that starts there (s = 1: the last cell's end).
  Point AtS(int piece, double s) const;
  // The state at sigma (clamped to [0, CellLength(piece, k)]) from the start of cell k of piece i,
  // by that cell's own formulas at both of its ends (where AtS takes a grid point to the cell that
  // starts there): the left and right limits at a grid point where the jerk steps. Piece and cell
  // must be in range (0 <= k < cells_per_piece()); not checked.
  Point InCell(int piece, int k, double sigma) const { return StateInCell(piece, k, sigma); }
  // InCell at the n + 1 evenly spaced sigma = (j / n) CellLength(piece, k), j = 0 .. n, into
  // out[0 .. n], the cell's own formulas set up once (the same values as n + 1 calls of InCell).
  // n >= 1 and out must hold n + 1 points; not checked.
  void InCellSamples(int piece, int k, int n, Point* out) const;

  // A rest cell's q at its rest point (alpha, see the header comment) from b at its middle in s and
  // at its far end, and back: q is linear in w and b = w^4 q, with w^3 = 1/2 at the middle.
  // (Negative for a middle value below 2^(-5/3) times the far one, which makes no profile.)
  static double RestAlpha(double b_mid, double b_far);
  static double RestMiddle(double alpha, double b_far);
  // A ramp cell's coordinate w at s of its piece: s^(1/3) (kRampStart) or (1 - s)^(1/3) (kRampEnd).
  static double RampW(CellShape shape, double s);
  // Its inverse: s at w, w^3 (kRampStart) or 1 - w^3 (kRampEnd).
  static double RampS(CellShape shape, double w);
  // Where a ramp cell [s0, s1] has its middle half point: at w = (w0 + w1) / 2.
  static double RampMiddleS(CellShape shape, double s0, double s1);

 private:
  // Cell index and sigma = s - s_k for s in [0, 1] on a piece.
  void Locate(int piece, double s, int* k, double* sigma) const;
  // Time from the start of cell k of piece i to sigma in [0, ds] inside it.
  double TimeInCell(int piece, int k, double sigma) const;
  // The state at sigma in [0, ds] of cell k of piece i.
  Point StateInCell(int piece, int k, double sigma) const;

  std::vector<std::vector<double>> b_;
  int cells_per_piece_ = 0;
  std::vector<double> cell_start_;  // m K + 1 cumulative times, cell_start_[c] = start of cell c
  // Jerk-limited profiles only (empty otherwise): the 2K + 1 half-grid values and K shapes.
  std::vector<std::vector<double>> half_b_;
  std::vector<std::vector<CellShape>> shapes_;
  std::vector<std::vector<double>> edges_;  // per piece K + 1 cell edges; empty: uniform
};

}  // namespace timeopt
