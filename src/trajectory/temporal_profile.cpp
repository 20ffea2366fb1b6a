#include "timeopt/trajectory/temporal_profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace timeopt {

TemporalProfile::TemporalProfile(std::vector<std::vector<double>> b) : b_(std::move(b)) {
  if (b_.empty()) throw std::invalid_argument("TemporalProfile: expected at least 1 piece");
  const size_t points = b_.front().size();
  if (points < 2) throw std::invalid_argument("TemporalProfile: expected K >= 1 (2 grid points)");
  cells_per_piece_ = static_cast<int>(points) - 1;
  const double ds = 1.0 / cells_per_piece_;
  cell_start_.reserve(b_.size() * static_cast<size_t>(cells_per_piece_) + 1);
  cell_start_.push_back(0.0);
  for (size_t i = 0; i < b_.size(); ++i) {
    if (b_[i].size() != points) {
      throw std::invalid_argument("TemporalProfile: piece " + std::to_string(i) + " has " +
                                  std::to_string(b_[i].size()) + " grid values, expected " +
                                  std::to_string(points));
    }
    for (size_t k = 0; k < points; ++k) {
      if (!(b_[i][k] >= 0.0) || !std::isfinite(b_[i][k])) {
        throw std::invalid_argument("TemporalProfile: b of piece " + std::to_string(i) +
                                    " at grid point " + std::to_string(k) +
                                    " must be finite and >= 0");
      }
    }
    for (int k = 0; k < cells_per_piece_; ++k) {
      const double root = std::sqrt(b_[i][k]) + std::sqrt(b_[i][k + 1]);
      if (!(root > 0.0)) {
        throw std::invalid_argument("TemporalProfile: cell " + std::to_string(k) + " of piece " +
                                    std::to_string(i) + " has zero speed at both ends");
      }
      cell_start_.push_back(cell_start_.back() + 2.0 * ds / root);
    }
  }
}

double TemporalProfile::a(int piece, int k) const {
  return (b_[piece][k + 1] - b_[piece][k]) * 0.5 * cells_per_piece_;
}

std::vector<double> TemporalProfile::piece_durations() const {
  std::vector<double> out(b_.size());
  for (size_t i = 0; i < b_.size(); ++i) {
    out[i] = cell_start_[(i + 1) * cells_per_piece_] - cell_start_[i * cells_per_piece_];
  }
  return out;
}

double TemporalProfile::TimeAt(int piece, int k) const {
  return cell_start_[static_cast<size_t>(piece) * cells_per_piece_ + k];
}

TemporalProfile::Point TemporalProfile::AtTime(double t) const {
  Point p;
  if (b_.empty()) return p;
  const double T = total_time();
  t = std::clamp(std::isnan(t) ? 0.0 : t, 0.0, T);
  // Last cell whose start time is <= t.
  auto it = std::upper_bound(cell_start_.begin(), cell_start_.end(), t);
  size_t cell = static_cast<size_t>(std::distance(cell_start_.begin(), it));
  cell = cell == 0 ? 0 : cell - 1;
  const size_t num_cells = cell_start_.size() - 1;
  if (cell >= num_cells) cell = num_cells - 1;
  const int piece = static_cast<int>(cell / cells_per_piece_);
  const int k = static_cast<int>(cell % cells_per_piece_);
  const double tau = std::min(t - cell_start_[cell], cell_start_[cell + 1] - cell_start_[cell]);
  const double ds = 1.0 / cells_per_piece_;
  const double v0 = std::sqrt(b_[piece][k]);
  const double acc = a(piece, k);
  p.piece = piece;
  p.sddot = acc;
  p.sdot = std::max(0.0, v0 + acc * tau);
  p.s = std::clamp(k * ds + v0 * tau + 0.5 * acc * tau * tau, k * ds, (k + 1) * ds);
  return p;
}

}  // namespace timeopt
