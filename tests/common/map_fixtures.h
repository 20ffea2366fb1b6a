#pragma once

// Maps shared by the tests of several modules (map, spatial, planner): random occupancy grids,
// a generated forest with its ESDF, a walled box, and free points drawn on them.

#include <cstdint>
#include <memory>
#include <random>

#include <Eigen/Core>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/map/voxel_grid.h"

namespace timeopt::test_support {

// Every voxel of the box occupied with probability `fill`, independently (seeded, reproducible).
inline OccupancyGrid RandomGrid(const Eigen::Vector3i& min, const Eigen::Vector3i& size, double resolution, double fill,
                                uint64_t seed) {
  VoxelBox box;
  box.min = min;
  box.size = size;
  OccupancyGrid grid(resolution, box);
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution occupied(fill);
  for (auto& v : grid.occupied) v = occupied(rng) ? 1 : 0;
  return grid;
}

// A generated forest on 10 x 10 x 3 m at 0.1 m, as an octree (for brute-force collision checks
// against the voxels) and as the ESDF the planner uses.
struct ForestFixture {
  explicit ForestFixture(uint64_t seed, double density = 0.12) {
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 10, 3));
    forest.density = density;
    forest.seed = seed;
    const OccupancyGrid grid = GenerateForest(forest);
    map = OccupancyMap::FromGrid(grid);
    esdf = std::make_unique<Esdf>(grid);
  }
  OccupancyMap map{0.1};
  std::unique_ptr<Esdf> esdf;
};

// A free point at height 1.5 m with at least `clearance` (ESDF), x and y uniform in [lo, hi].
inline Eigen::Vector3d FreePoint(const Esdf& esdf, std::mt19937* rng, double clearance, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  for (;;) {
    const Eigen::Vector3d p(u(*rng), u(*rng), 1.5);
    if (esdf.Distance(p) >= clearance) return p;
  }
}

// A 10 x 4 x 2 m box at 0.1 m with a full wall at x = 5.0-5.3 m (nothing behind it is reachable)
// and one occupied voxel at (2.05, 3.05, 1.05), away from the free line y = 1-2, z = 1.
inline OccupancyGrid WalledBox() {
  OccupancyGrid grid(0.1, VoxelBox{Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(100, 40, 20)});
  for (int z = 0; z < 20; ++z) {
    for (int y = 0; y < 40; ++y) {
      for (int x = 50; x < 53; ++x) grid.Set(Eigen::Vector3i(x, y, z), true);
    }
  }
  grid.Set(Eigen::Vector3i(20, 30, 10), true);
  return grid;
}

}  // namespace timeopt::test_support
