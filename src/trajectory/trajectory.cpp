#include "timeopt/trajectory/trajectory.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace timeopt {

Trajectory::Trajectory(PiecewiseCurve curve, TemporalProfile profile)
    : curve_(std::move(curve)), profile_(std::move(profile)) {
  if (curve_.num_pieces() != profile_.num_pieces()) {
    throw std::invalid_argument("Trajectory: the curve has " + std::to_string(curve_.num_pieces()) +
                                " pieces but the profile has " + std::to_string(profile_.num_pieces()));
  }
}

TrajectoryState Trajectory::Evaluate(double t) const {
  return AtPoint(profile_.AtTime(t), std::isnan(t) ? 0.0 : std::min(std::max(t, 0.0), duration()));
}

TrajectoryState Trajectory::AtPoint(const TemporalProfile::Point& p, double t) const {
  const auto d = curve_.piece(p.piece).EvaluateAll(p.s, 3);
  TrajectoryState x;
  x.t = t;
  x.position = d.col(0);
  x.velocity = ChainVelocity(d.col(1), p.sdot);
  x.acceleration = ChainAcceleration(d.col(1), d.col(2), p.sdot, p.sddot);
  x.jerk = ChainJerk(d.col(1), d.col(2), d.col(3), p.sdot, p.sddot, p.sdddot);
  return x;
}

void Trajectory::CheckSampleRate(double rate_hz) const {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("Trajectory::Sample: rate must be a positive number of Hz");
  }
  const double T = duration();
  if (!(std::floor(T * rate_hz) <= kMaxSamples)) {
    std::ostringstream os;
    os << "Trajectory::Sample: " << T << " s at " << rate_hz << " Hz is more than 1e8 samples (lower the rate)";
    throw std::invalid_argument(os.str());
  }
}

std::vector<TrajectoryState> Trajectory::Sample(double rate_hz) const {
  CheckSampleRate(rate_hz);
  const double T = duration();
  const double count = std::floor(T * rate_hz);
  std::vector<TrajectoryState> out;
  out.reserve(static_cast<size_t>(count) + 2);
  for (long i = 0; i <= static_cast<long>(count); ++i) {
    const double t = i / rate_hz;
    if (t >= T) break;
    out.push_back(Evaluate(t));
  }
  // The last sample is the end state at exactly T; a regular sample closer to it than a
  // millionth of the period (solver round-off in T) is replaced rather than duplicated.
  if (!out.empty() && T - out.back().t < 1e-6 / rate_hz) out.pop_back();
  out.push_back(Evaluate(T));
  return out;
}

}  // namespace timeopt
