#pragma once

// The solution of a temporal problem on its grid, and the exact map between time and s.
//
// On every cell b = sdot^2 is linear in s and a = sddot is constant, so within a cell that starts
// at time t_k with speed sqrt(b^k):  s(t) = s_k + sqrt(b^k) (t - t_k) + a (t - t_k)^2 / 2,
// sdot(t) = sqrt(b^k) + a (t - t_k), and the cell takes 2 ds / (sqrt(b^k) + sqrt(b^{k+1})).

#include <vector>

namespace timeopt {

class TemporalProfile {
 public:
  TemporalProfile() = default;
  // b[i] holds the K + 1 grid values of piece i (all pieces the same K >= 1, values >= 0, a cell
  // with b = 0 at both ends is not allowed). Throws std::invalid_argument otherwise.
  explicit TemporalProfile(std::vector<std::vector<double>> b);

  int num_pieces() const { return static_cast<int>(b_.size()); }
  int cells_per_piece() const { return cells_per_piece_; }
  double ds() const { return 1.0 / cells_per_piece_; }
  // b = sdot^2 at grid point k of piece i.
  double b(int piece, int k) const { return b_[piece][k]; }
  const std::vector<std::vector<double>>& b() const { return b_; }
  // a = sddot on cell k of piece i: (b^{k+1} - b^k) / (2 ds).
  double a(int piece, int k) const;

  double total_time() const { return cell_start_.empty() ? 0.0 : cell_start_.back(); }
  std::vector<double> piece_durations() const;
  // Time at which the vehicle passes grid point k of piece i.
  double TimeAt(int piece, int k) const;

  struct Point {
    int piece = 0;
    double s = 0.0;      // in [0, 1] on the piece
    double sdot = 0.0;   // ds/dt
    double sddot = 0.0;  // d2s/dt2 (constant on the cell)
  };
  // The state of the parameter at time t, clamped to [0, total_time()].
  Point AtTime(double t) const;

 private:
  std::vector<std::vector<double>> b_;
  int cells_per_piece_ = 0;
  std::vector<double> cell_start_;  // m K + 1 cumulative times, cell_start_[c] = start of cell c
};

}  // namespace timeopt
