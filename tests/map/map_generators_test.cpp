#include "timeopt/map/map_generators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "timeopt/map/esdf.h"

namespace timeopt {
namespace {

TEST(MapGeneratorsTest, ForestIsDeterministicAndHasTheRequestedTrees) {
  ForestOptions options;
  options.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(6, 5, 2));
  options.density = 0.2;
  options.seed = 4;
  const OccupancyGrid a = GenerateForest(options);
  const OccupancyGrid b = GenerateForest(options);
  EXPECT_EQ(a.occupied, b.occupied);
  EXPECT_EQ(a.box.size, Eigen::Vector3i(60, 50, 20));
  options.seed = 5;
  EXPECT_NE(GenerateForest(options).occupied, a.occupied);
  // Six trees (0.2 * 30 m^2) of radius 0.15..0.4 m cover at least one disc of the smallest
  // radius (they may overlap; half of it allows for the voxel rasterization of a 3-voxel disc)
  // and at most six discs of the largest radius, 6 * pi * 0.4^2 = 3.0 m^2 per layer.
  const double layer_area = a.CountOccupied() / 20.0 * 0.01;
  EXPECT_GT(layer_area, 3.14159 * 0.15 * 0.15 * 0.5);
  EXPECT_LT(layer_area, 6 * 3.14159 * 0.4 * 0.4 + 0.5);  // + rasterization slack
  // Vertical: every layer is the same.
  const int64_t plane = 60 * 50;
  for (int z = 1; z < 20; ++z) {
    EXPECT_TRUE(std::equal(a.occupied.begin(), a.occupied.begin() + plane, a.occupied.begin() + z * plane));
  }
  options.min_radius = 0.5;
  options.max_radius = 0.4;
  EXPECT_THROW(GenerateForest(options), std::invalid_argument);
}

TEST(MapGeneratorsTest, SharpTurnCorridorIsFreeAlongThePolylineAndSolidOutside) {
  SharpTurnOptions options;
  const OccupancyGrid grid = GenerateSharpTurn(options);
  const Eigen::Matrix<double, 2, 3> line = options.Polyline();
  const double z = options.wall + 0.5 * options.height;
  const Esdf esdf(grid);
  for (int i = 0; i <= 20; ++i) {
    const double t = i / 20.0;
    for (int leg = 0; leg < 2; ++leg) {
      const Eigen::Vector2d p = line.col(leg) + t * (line.col(leg + 1) - line.col(leg));
      const Eigen::Vector3d point(p.x(), p.y(), z);
      // On the centre line the clearance is at most half the width (rasterization can widen it
      // by up to a voxel) and positive.
      EXPECT_GT(esdf.Distance(point), 0.0);
      EXPECT_LT(esdf.Distance(point), 0.5 * options.corridor_width + options.resolution);
    }
  }
  // The turn is near-reverse: the legs' directions differ by turn_angle_deg.
  const Eigen::Vector2d d0 = (line.col(1) - line.col(0)).normalized();
  const Eigen::Vector2d d1 = (line.col(2) - line.col(1)).normalized();
  // acos of a rounded dot product: 1e-9 degrees is far above double rounding, far below any bug.
  EXPECT_NEAR(std::acos(d0.dot(d1)) * 180.0 / 3.14159265358979, options.turn_angle_deg, 1e-9);
  // Solid walls around: the box's corner is inside an obstacle.
  EXPECT_LT(esdf.VoxelDistance(grid.box.min), 0.0);
  options.turn_angle_deg = 190;
  EXPECT_THROW(GenerateSharpTurn(options), std::invalid_argument);
}

TEST(MapGeneratorsTest, RandomBoxesFillTheirVoxels) {
  RandomBoxesOptions options;
  options.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 4, 2));
  options.count = 1;
  options.min_size = 1.0;
  options.max_size = 1.0;
  options.ground = true;
  const OccupancyGrid grid = GenerateRandomBoxes(options);
  const int64_t ground = 40 * 40;
  // One 1 m box (10^3 voxels before clipping at the bounds, possibly overlapping the ground).
  EXPECT_GT(grid.CountOccupied(), ground);
  EXPECT_LE(grid.CountOccupied(), ground + 1000);
  options.count = -1;
  EXPECT_THROW(GenerateRandomBoxes(options), std::invalid_argument);
}

}  // namespace
// Absurd counts are refused before any work (they used to run for hours): more than 1e6 trees
// (1e5 per m^2 on 100 m^2) or boxes.
TEST(MapGeneratorsTest, AbsurdCountsAreRefused) {
  ForestOptions forest;
  forest.density = 1e5;
  EXPECT_THROW(GenerateForest(forest), std::invalid_argument);
  RandomBoxesOptions boxes;
  boxes.count = 2000000;
  EXPECT_THROW(GenerateRandomBoxes(boxes), std::invalid_argument);
}

}  // namespace timeopt
