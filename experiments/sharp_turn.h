// The paper's motivating example (Sect. I), shared by the experiments that fly it: a fast straight
// run into a near-reverse sharp turn, 7 waypoints at 1 m height.
#pragma once

#include "timeopt/curve/interpolation.h"

namespace timeopt::experiments {

inline Waypoints SharpTurn() {
  Waypoints w(3, 7);
  w << 0, 4, 8, 9.5, 8, 4, 0, 0, 0, 0, 0.8, 1.6, 1.6, 1.6, 1, 1, 1, 1, 1, 1, 1;
  return w;
}

}  // namespace timeopt::experiments
