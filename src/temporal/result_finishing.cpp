// The finishing step of every temporal solve (solver_internal.h): the profile, T and the objective
// of an optimal answer, and its limit ratios checked densely along the exact trajectory.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "discretization_internal.h"
#include "solver_internal.h"
#include "timeopt/core/vehicle_limits.h"
#include "timeopt/trajectory/trajectory.h"

namespace timeopt {

namespace {

// The dense feasibility check: largest |v_axis|/vmax_axis, |acc_axis|/amax_axis and (with a jerk
// limit) |jerk_axis|/jmax_axis along the exact trajectory, sampling every cell at
// `samples_per_cell` + 1 evenly spaced values of s.
void DenseLimitRatios(const TemporalProblem& problem, const TemporalProfile& profile, int samples_per_cell,
                      TemporalResult* result) {
  if (samples_per_cell < 1) throw std::invalid_argument("DenseLimitRatios: samples_per_cell < 1");
  double vr = 0.0, ar = 0.0, jr = 0.0;
  const int K = profile.cells_per_piece();
  const double ds = 1.0 / K;  // the cells of a profile without a jerk limit
  const Eigen::Vector3d inv_v = problem.limits.max_velocity.cwiseInverse();
  const Eigen::Vector3d inv_a = problem.limits.max_acceleration.cwiseInverse();
  const bool jerk = problem.limits.max_jerk.has_value();
  const Eigen::Vector3d inv_j =
      jerk ? Eigen::Vector3d(problem.limits.max_jerk->cwiseInverse()) : Eigen::Vector3d::Zero();
  // The quadrotor's limits at one sample (velocity, acceleration).
  const TemporalLimits& L = problem.limits;
  const bool norms = L.HasNormLimits();
  QuadrotorExtremes quadrotor;
  const auto quad = [&](const Eigen::Vector3d& vel, const Eigen::Vector3d& acc) {
    quadrotor.Note(vel, acc, L.gravity);
  };
  std::vector<TemporalProfile::Point> states(jerk ? static_cast<size_t>(samples_per_cell) + 1 : 0);
  for (int i = 0; i < profile.num_pieces(); ++i) {
    // The derivatives' coefficients once per piece, then Horner's rule per sample: finishing a
    // result at m = 10, K = 50 took 0.27 ms (of a 6.3 ms Solve) when the piece derived its
    // coefficients at every sample, 0.18 ms this way.
    const PolynomialPiece& piece = problem.curve.piece(i);
    const PolynomialPiece::Coefficients d1 = piece.Derivative(1).coefficients();
    const PolynomialPiece::Coefficients d2 = piece.Derivative(2).coefficients();
    const PolynomialPiece::Coefficients d3 =
        piece.degree() >= 3 ? piece.Derivative(3).coefficients() : PolynomialPiece::Coefficients::Zero(3, 1);
    const auto horner = [](const PolynomialPiece::Coefficients& c, double s) {
      Eigen::Vector3d v = c.col(c.cols() - 1);
      for (Eigen::Index q = c.cols() - 2; q >= 0; --q) v = v * s + c.col(q);
      return v;
    };
    for (int k = 0; k < K; ++k) {
      const double b0 = profile.b(i, k), b1 = profile.b(i, k + 1);
      const double a = jerk ? 0.0 : profile.a(i, k);
      const double start = jerk ? profile.CellStart(i, k) : 0.0, length = jerk ? profile.CellLength(i, k) : 0.0;
      // Each cell's own state at both of its ends: the jerk's left and right limits at a grid
      // point (AtS would evaluate the next cell at this cell's end), and no search for the cell.
      if (jerk) profile.InCellSamples(i, k, samples_per_cell, states.data());
      for (int j = 0; j <= samples_per_cell; ++j) {
        const double u = static_cast<double>(j) / samples_per_cell;
        const double s = jerk ? start + u * length : (k + u) * ds;
        const Eigen::Vector3d f1 = horner(d1, s), f2 = horner(d2, s);
        if (!jerk) {
          // b is linear in s on the cell, and sddot = a constant.
          const double sdot = std::sqrt(std::max(0.0, b0 + (b1 - b0) * u));
          const Eigen::Vector3d velocity = ChainVelocity(f1, sdot), acceleration = ChainAcceleration(f1, f2, sdot, a);
          vr = std::max(vr, velocity.cwiseAbs().cwiseProduct(inv_v).maxCoeff());
          ar = std::max(ar, acceleration.cwiseAbs().cwiseProduct(inv_a).maxCoeff());
          if (norms) quad(velocity, acceleration);
          continue;
        }
        const TemporalProfile::Point& p = states[static_cast<size_t>(j)];
        const Eigen::Vector3d f3 = horner(d3, s);
        const Eigen::Vector3d velocity = ChainVelocity(f1, p.sdot);
        const Eigen::Vector3d acceleration = ChainAcceleration(f1, f2, p.sdot, p.sddot);
        vr = std::max(vr, velocity.cwiseAbs().cwiseProduct(inv_v).maxCoeff());
        ar = std::max(ar, acceleration.cwiseAbs().cwiseProduct(inv_a).maxCoeff());
        if (norms) quad(velocity, acceleration);
        const Eigen::Vector3d jerk_vector = ChainJerk(f1, f2, f3, p.sdot, p.sddot, p.sdddot);
        jr = std::max(jr, jerk_vector.cwiseAbs().cwiseProduct(inv_j).maxCoeff());
      }
    }
  }
  result->max_velocity_ratio = vr;
  result->max_acceleration_ratio = ar;
  quadrotor.WriteRatios(L, result);
  result->max_jerk_ratio = jr;
}

}  // namespace

namespace internal {

// Fills total_time, objective, piece_durations, profile and the dense feasibility ratios of an
// optimal result from the discretization's free values x (the skeleton's finishing step).
void FinishOptimalResult(const TemporalProblem& problem, const TemporalDiscretization& d, const std::vector<double>& x,
                         TemporalResult* result) {
  const int K = d.cells_per_piece;  // half cells in the jerk-limited mode
  // b at every grid value (interior-point iterates may sit a rounding error below zero); a
  // jerk-limited rest cell's middle value is q at its rest point in d, b at its middle in the profile.
  std::vector<double> flat(d.grid.size());
  for (size_t g = 0; g < d.grid.size(); ++g) flat[g] = std::max(0.0, d.GridB(static_cast<int>(g), x));
  if (d.jerk_limited) RestAlphaToMiddles(d, &flat);
  std::vector<std::vector<double>> b(static_cast<size_t>(d.num_pieces));
  for (int i = 0; i < d.num_pieces; ++i) {
    b[static_cast<size_t>(i)].assign(flat.begin() + d.GridIndex(i, 0), flat.begin() + d.GridIndex(i, K) + 1);
  }
  if (d.jerk_limited) {
    const int full = K / 2;
    std::vector<std::vector<CellShape>> shapes(static_cast<size_t>(d.num_pieces));
    for (int i = 0; i < d.num_pieces; ++i) {
      shapes[i].assign(d.shapes.begin() + i * full, d.shapes.begin() + (i + 1) * full);
    }
    result->profile = TemporalProfile::JerkLimited(std::move(b), std::move(shapes), d.cell_edges);
  } else {
    result->profile = TemporalProfile(std::move(b));
  }
  result->total_time = result->profile.total_time();
  result->piece_durations = result->profile.piece_durations();
  // The objective with the profile's exact time (the discretization's time of a jerk-limited cell
  // is an approximation; for the paper's cells the two agree).
  double time = 0.0;
  const double objective = d.Objective(x, &time);
  result->objective = d.jerk_limited ? objective - time + result->total_time : objective;
  result->status = TemporalStatus::kOptimal;
  // 32 samples per cell: the polynomials on a cell have degree <= 2n - 1, so a 1/32 spacing
  // resolves their extrema well below the cell's size.
  DenseLimitRatios(problem, result->profile, 32, result);
}

}  // namespace internal

}  // namespace timeopt
