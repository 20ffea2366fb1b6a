// Uses the installed library: fits a minimum-jerk curve and checks it passes through a waypoint.
#include <cmath>
#include <cstdio>

#include <timeopt/timeopt.h>

int main() {
  timeopt::Waypoints w(3, 3);
  w << 0, 1, 2, 0, 1, 0, 0, 0, 0;
  const timeopt::PiecewiseCurve curve = timeopt::MinimumJerkSpline(w);
  const double error = (curve.Evaluate(1, 0.0) - w.col(1)).norm();
  std::printf("timeopt %s consumer: %d pieces, waypoint error %.3g\n", TIMEOPT_VERSION_STRING, curve.num_pieces(),
              error);
  return error < 1e-12 ? 0 : 1;
}
