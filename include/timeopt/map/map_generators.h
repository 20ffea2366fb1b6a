#pragma once

// Synthetic maps for tests, experiments and the committed default maps in maps/.
//
// Each generator rasterizes its shapes into a dense OccupancyGrid over the voxel box covering
// `bounds` (every voxel known: free or occupied), so that unknown space never appears inside a
// generated map. A voxel is occupied when its centre lies inside a shape. Generation is
// deterministic for a given options struct (std::mt19937_64 with `seed`).

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "timeopt/map/voxel_grid.h"

namespace timeopt {

// Vertical cylinders ("trees") from the bottom to the top of the bounds, centres uniform in the
// xy rectangle, radius uniform in [min_radius, max_radius].
struct ForestOptions {
  Eigen::AlignedBox3d bounds{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 10, 3)};  // metres
  double resolution = 0.1;                                                           // voxel edge, metres
  double density = 0.1;      // trees per square metre; count = round(density * xy area)
  double min_radius = 0.15;  // metres
  double max_radius = 0.4;   // metres
  uint64_t seed = 1;

  // Throws std::invalid_argument naming the first bad field.
  void Validate() const;
};

// The paper's Sect. I example: a narrow corridor with a near-reverse turn. Inside the bounds
// everything is solid except the corridor: from its start the first leg runs along +x for
// `leg_length`, then the heading turns left by `turn_angle_deg` (180 would be a full reversal) and
// the second leg runs `leg_length` again. The corridor is the set of voxels whose centre lies
// within corridor_width / 2 of this polyline (in xy) and at z in [wall, wall + height]. The
// bounds start at the origin and fit the corridor plus `wall` of solid on every side (Bounds()),
// so that the legs' ends are closed.
struct SharpTurnOptions {
  double resolution = 0.1;      // voxel edge, metres
  double corridor_width = 1.2;  // metres
  double leg_length = 8.0;      // metres, each leg
  double turn_angle_deg = 160;  // heading change at the turn, degrees, in (0, 180]
  double height = 2.0;          // free height of the corridor, metres
  double wall = 0.5;            // solid margin around the corridor, metres

  void Validate() const;
  // Corridor polyline in the xy plane: start, turn point, end (metres).
  Eigen::Matrix<double, 2, 3> Polyline() const;
  // Bounds of the generated map.
  Eigen::AlignedBox3d Bounds() const;
};

// Axis-aligned boxes with sizes uniform in [min_size, max_size] per axis, centres uniform in the
// bounds (boxes are clipped to the bounds), plus an optional ground slab one voxel thick.
struct RandomBoxesOptions {
  Eigen::AlignedBox3d bounds{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 10, 3)};  // metres
  double resolution = 0.1;                                                           // voxel edge, metres
  int count = 20;                                                                    // number of boxes
  double min_size = 0.3;                                                             // metres, per axis
  double max_size = 1.5;                                                             // metres, per axis
  bool ground = false;                                                               // occupy the lowest voxel layer
  uint64_t seed = 1;

  void Validate() const;
};

OccupancyGrid GenerateForest(const ForestOptions& options);
OccupancyGrid GenerateSharpTurn(const SharpTurnOptions& options);
OccupancyGrid GenerateRandomBoxes(const RandomBoxesOptions& options);

}  // namespace timeopt
