#include "timeopt/map/esdf.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "timeopt/map/occupancy_map.h"
#include "timeopt/map/voxel_grid.h"

#include "../common/map_fixtures.h"

namespace timeopt {
namespace {

using test_support::RandomGrid;

// Independent truth: the definition in esdf.h evaluated by trying every pair of voxels.
double BruteForce(const OccupancyGrid& grid, const Eigen::Vector3i& index) {
  const bool self = grid.At(index);
  double best = std::numeric_limits<double>::infinity();
  const Eigen::Vector3i end = grid.box.end();
  for (int z = grid.box.min.z(); z < end.z(); ++z) {
    for (int y = grid.box.min.y(); y < end.y(); ++y) {
      for (int x = grid.box.min.x(); x < end.x(); ++x) {
        const Eigen::Vector3i other(x, y, z);
        if (grid.At(other) == self) continue;
        best = std::min(best, (grid.Centre(other) - grid.Centre(index)).norm());
      }
    }
  }
  const double unsigned_distance = best - 0.5 * grid.resolution;
  return self ? -unsigned_distance : unsigned_distance;
}

// Values are stored as float: relative rounding 6e-8 of distances below 2 m, so 1e-6 m is a
// generous bound that still catches any wrong voxel (errors of a whole voxel are >= 0.02 m here).
constexpr double kFloatStorageTolerance = 1e-6;

TEST(EsdfTest, ExactAtVoxelCentresAgainstBruteForce) {
  struct Case {
    Eigen::Vector3i min, size;
    double resolution, fill;
  };
  const std::vector<Case> cases = {
      {{0, 0, 0}, {11, 9, 7}, 0.1, 0.05},    // sparse obstacles: long distances
      {{-5, 3, -2}, {8, 13, 6}, 0.05, 0.3},  // negative indices, dense
      {{2, -7, 0}, {16, 5, 1}, 0.2, 0.1},    // a single layer (flat z)
      {{0, 0, 0}, {1, 12, 9}, 0.1, 0.15},    // flat x
      {{0, 0, 0}, {9, 9, 9}, 0.08, 0.7},     // mostly occupied: long negative distances
  };
  uint64_t seed = 7;
  for (const Case& c : cases) {
    for (int repeat = 0; repeat < 3; ++repeat) {
      const OccupancyGrid grid = RandomGrid(c.min, c.size, c.resolution, c.fill, ++seed);
      if (grid.CountOccupied() == 0 || grid.CountOccupied() == grid.box.num_voxels()) continue;
      const Esdf esdf(grid);
      const Eigen::Vector3i end = grid.box.end();
      for (int z = grid.box.min.z(); z < end.z(); ++z) {
        for (int y = grid.box.min.y(); y < end.y(); ++y) {
          for (int x = grid.box.min.x(); x < end.x(); ++x) {
            const Eigen::Vector3i index(x, y, z);
            const double truth = BruteForce(grid, index);
            ASSERT_NEAR(esdf.VoxelDistance(index), truth, kFloatStorageTolerance)
                << "voxel " << index.transpose() << " seed " << seed;
            // At a centre the interpolant reproduces the stored value (weights 0/1 up to the
            // rounding of (p - origin) / r, below 1e-12 cells here).
            ASSERT_NEAR(esdf.Distance(grid.Centre(index)), truth, kFloatStorageTolerance);
            ASSERT_EQ(truth > 0, !grid.At(index));
          }
        }
      }
    }
  }
}

TEST(EsdfTest, PlanarWallIsExactEverywhereWithUnitGradient) {
  // Occupied for x index < 0: d(p) = p.x exactly at centres (the half voxel puts the surface on
  // the face x = 0), and the trilinear interpolant of a linear function is the function itself.
  VoxelBox box;
  box.min = Eigen::Vector3i(-4, 0, 0);
  box.size = Eigen::Vector3i(12, 5, 4);
  OccupancyGrid grid(0.1, box);
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 5; ++y)
      for (int x = -4; x < 0; ++x) grid.Set(Eigen::Vector3i(x, y, z), true);
  const Esdf esdf(grid);
  std::mt19937_64 rng(3);
  const Eigen::AlignedBox3d domain = esdf.domain();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p =
        domain.min() + (domain.max() - domain.min()).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    Eigen::Vector3d g;
    const double d = esdf.DistanceAndGradient(p, &g);
    // Float storage of values up to 0.8 m: 1e-6 m; gradient: that over a 0.1 m cell, 1e-5.
    EXPECT_NEAR(d, p.x(), 1e-6) << p.transpose();
    EXPECT_NEAR((g - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-5) << p.transpose();
  }
}

TEST(EsdfTest, GradientMatchesFiniteDifferencesInsideCells) {
  const OccupancyGrid grid = RandomGrid({-3, -2, 0}, {14, 12, 10}, 0.1, 0.04, 11);
  const Esdf esdf(grid);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector3d first = esdf.domain().min();
  const Eigen::Vector3i cells = grid.box.size - Eigen::Vector3i::Ones();
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    // A random cell and a point in it at least 5% of a cell away from its faces: the stencil
    // (h = 1e-6 m = 1e-5 cells) stays in the cell, away from the kinks of the interpolant and
    // from the ridges of the distance (which lie on cell faces or inside, where the interpolant
    // is smooth anyway).
    Eigen::Vector3d u;
    for (int a = 0; a < 3; ++a) {
      const int cell = static_cast<int>(unit(rng) * cells(a));
      u(a) = cell + 0.05 + 0.9 * unit(rng);
    }
    const Eigen::Vector3d p = first + u * grid.resolution;
    Eigen::Vector3d g;
    esdf.DistanceAndGradient(p, &g);
    const double h = 1e-6;
    Eigen::Vector3d fd;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
      fd(a) = (esdf.Distance(p + e) - esdf.Distance(p - e)) / (2 * h);
    }
    // The interpolant is multilinear, so central differences are exact up to rounding:
    // eps * |d| / h = 2e-16 * 1 m / 1e-6 m = 2e-10; 1e-7 leaves room for the evaluation order.
    ASSERT_NEAR((g - fd).norm(), 0.0, 1e-7) << p.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}

TEST(EsdfTest, GradientPointsAwayFromASingleObstacle) {
  VoxelBox box;
  box.min = Eigen::Vector3i::Zero();
  box.size = Eigen::Vector3i(31, 31, 31);
  OccupancyGrid grid(0.1, box);
  grid.Set(Eigen::Vector3i(15, 15, 15), true);
  const Esdf esdf(grid);
  const Eigen::Vector3d obstacle = grid.Centre(Eigen::Vector3i(15, 15, 15));
  std::mt19937_64 rng(9);
  std::normal_distribution<double> normal;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d direction = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    const double radius = 0.6 + 0.8 * (i % 10) / 10.0;  // 6 to 14 voxels from the obstacle
    const Eigen::Vector3d p = obstacle + radius * direction;
    Eigen::Vector3d g;
    const double d = esdf.DistanceAndGradient(p, &g);
    // True field: |p - o| - r/2. Trilinear interpolation of a cone at distance R deviates by at
    // most about r^2 / (2 R) <= 0.01 / 1.2 m, under 0.01 m; its gradient direction by about
    // r / R <= 1/6 rad, so cos > 0.98 and |g| within 15% of 1.
    EXPECT_NEAR(d, radius - 0.05, 0.01);
    EXPECT_GT(g.normalized().dot(direction), 0.98);
    EXPECT_NEAR(g.norm(), 1.0, 0.15);
  }
}

TEST(EsdfTest, OutsideTheBoxAddsTheDistanceToTheBox) {
  const OccupancyGrid grid = RandomGrid({0, 0, 0}, {10, 8, 6}, 0.1, 0.1, 21);
  const Esdf esdf(grid);
  const Eigen::AlignedBox3d domain = esdf.domain();
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> unit(-1.0, 2.0);
  int outside = 0;
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p =
        domain.min() + (domain.max() - domain.min()).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    const Eigen::Vector3d q = p.cwiseMax(domain.min()).cwiseMin(domain.max());
    const double expected = esdf.Distance(q) + (p - q).norm();
    // Same float values, same arithmetic up to the order of additions.
    EXPECT_NEAR(esdf.Distance(p), expected, 1e-12);
    EXPECT_EQ(esdf.Contains(p), (p - q).norm() == 0.0);
    if (!esdf.Contains(p)) {
      ++outside;
      // The extension's gradient against central differences. Away from the clamping planes
      // (and the interior cell faces) the function is smooth; skip points within 1e-4 m of them.
      Eigen::Vector3d g;
      esdf.DistanceAndGradient(p, &g);
      bool near_kink = false;
      for (int a = 0; a < 3; ++a) {
        const double u = (q(a) - domain.min()(a)) / grid.resolution;
        near_kink |= std::abs(p(a) - domain.min()(a)) < 1e-4 || std::abs(p(a) - domain.max()(a)) < 1e-4 ||
                     (p(a) == q(a) && std::abs(u - std::round(u)) < 1e-3);
      }
      if (near_kink) continue;
      Eigen::Vector3d fd;
      const double h = 1e-6;
      for (int a = 0; a < 3; ++a) {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(a) * h;
        fd(a) = (esdf.Distance(p + e) - esdf.Distance(p - e)) / (2 * h);
      }
      // The norm term is smooth with curvature 1/|p - q| >= 1/3 m^-1: central-difference error
      // h^2 / 6 * 1/|p-q|^3 is negligible for points at least ~1e-3 m outside; rounding 1e-9.
      if ((p - q).norm() > 1e-3) {
        EXPECT_NEAR((g - fd).norm(), 0.0, 1e-6) << p.transpose();
      }
    }
  }
  EXPECT_GT(outside, 100);
  // Continuity across the boundary: just inside and just outside agree (2e-9 m apart with a
  // gradient of norm <= ~1: 2e-9; 1e-7 allows for float data and rounding of the clamp).
  const Eigen::Vector3d on_face(domain.max().x(), 0.5 * (domain.min().y() + domain.max().y()),
                                0.5 * (domain.min().z() + domain.max().z()));
  EXPECT_NEAR(esdf.Distance(on_face + Eigen::Vector3d(1e-9, 0, 0)),
              esdf.Distance(on_face - Eigen::Vector3d(1e-9, 0, 0)), 1e-7);
}

TEST(EsdfTest, BatchedQueriesEqualSingleQueries) {
  const OccupancyGrid grid = RandomGrid({0, 0, 0}, {12, 10, 8}, 0.1, 0.1, 33);
  const Esdf esdf(grid);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> unit(-0.2, 1.4);
  Eigen::Matrix3Xd points(3, 200);
  for (int j = 0; j < points.cols(); ++j) points.col(j) << unit(rng), unit(rng), unit(rng);
  Eigen::VectorXd distances, only_distances;
  Eigen::Matrix3Xd gradients;
  esdf.Distances(points, &distances, &gradients);
  esdf.Distances(points, &only_distances, nullptr);
  ASSERT_EQ(distances.size(), 200);
  ASSERT_EQ(gradients.cols(), 200);
  for (int j = 0; j < points.cols(); ++j) {
    Eigen::Vector3d g;
    const double d = esdf.DistanceAndGradient(points.col(j), &g);
    EXPECT_EQ(distances(j), d);  // the same code path: bit-identical
    EXPECT_EQ(only_distances(j), d);
    EXPECT_EQ(gradients.col(j), g);
  }
  // Through the interface the optimizers use, and its default batch loop.
  const DistanceField& field = esdf;
  EXPECT_EQ(field.Distance(points.col(3)), distances(3));
  Eigen::VectorXd base_distances;
  Eigen::Matrix3Xd base_gradients;
  field.DistanceField::Distances(points, &base_distances, &base_gradients);
  EXPECT_EQ(base_distances, distances);
  EXPECT_EQ(base_gradients, gradients);
}

TEST(EsdfTest, NonFinitePointGivesNonFiniteDistanceWithoutCrashing) {
  const OccupancyGrid grid = RandomGrid({0, 0, 0}, {6, 6, 6}, 0.1, 0.2, 1);
  const Esdf esdf(grid);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(esdf.Distance(Eigen::Vector3d(nan, 0.3, 0.3))));
  EXPECT_FALSE(std::isfinite(esdf.Distance(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0.3, 0.3))));
}

TEST(EsdfTest, InvalidGridsThrowClearErrors) {
  VoxelBox box;
  box.size = Eigen::Vector3i(4, 4, 4);
  const OccupancyGrid all_free(0.1, box, false);
  EXPECT_THROW(
      {
        try {
          Esdf esdf(all_free);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("no occupied voxel"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  const OccupancyGrid all_occupied(0.1, box, true);
  EXPECT_THROW(Esdf esdf(all_occupied), std::invalid_argument);
  OccupancyGrid wrong_size(0.1, box, false);
  wrong_size.occupied.pop_back();
  EXPECT_THROW(Esdf esdf(wrong_size), std::invalid_argument);
  OccupancyGrid bad_value(0.1, box, false);
  bad_value.occupied[0] = 7;
  EXPECT_THROW(Esdf esdf(bad_value), std::invalid_argument);
  VoxelBox zero = box;
  zero.size.z() = 0;
  EXPECT_THROW(OccupancyGrid(0.1, zero), std::invalid_argument);
  EXPECT_THROW(OccupancyGrid(0.0, box), std::invalid_argument);
  // Above the 2e8-voxel cap: refused by its size before any allocation (2^30 bytes here).
  VoxelBox huge = box;
  huge.size = Eigen::Vector3i(1024, 1024, 1024);
  try {
    const OccupancyGrid grid(0.1, huge);
    ADD_FAILURE() << "a 2^30-voxel grid was allocated";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("1073741824 voxels is above the 200000000 supported"), std::string::npos)
        << e.what();
  }
  const OccupancyGrid some(0.1, box, false);
  OccupancyGrid one = some;
  one.Set(Eigen::Vector3i(1, 1, 1), true);
  const Esdf esdf(one);
  EXPECT_THROW(esdf.VoxelDistance(Eigen::Vector3i(4, 0, 0)), std::invalid_argument);
  Eigen::VectorXd d;
  EXPECT_THROW(esdf.Distances(Eigen::Matrix3Xd(3, 2), nullptr, nullptr), std::invalid_argument);
  EXPECT_THROW(esdf.DistanceAndGradient(Eigen::Vector3d::Zero(), nullptr), std::invalid_argument);
}

// The field of a region of interest against the whole map's field (itself checked against brute
// force above). Walls on the cut faces make the region's field a lower bound everywhere, and equal
// wherever the whole map's nearest obstacle is closer than the nearest cut layer (it then lies
// inside the region): both facts follow from the definition, so they are asserted exactly, up to
// float storage. On a forest with cuts on four faces and none in z.
// The memory budget: a field whose peak (9 bytes per voxel) is at the budget is built, one byte
// less is refused with both figures in the message, for the whole map and for a region.
TEST(EsdfTest, AMemoryBudgetRefusesFieldsAboveItBeforeBuilding) {
  const test_support::ForestFixture forest(4, 0.15);
  const int64_t whole = Esdf::PeakBytes(forest.map.KnownBox());
  EXPECT_EQ(whole, forest.map.KnownBox().num_voxels() * 9);
  EXPECT_NO_THROW(Esdf::FromMap(forest.map, std::nullopt, whole));
  try {
    Esdf::FromMap(forest.map, std::nullopt, whole - 1);
    ADD_FAILURE() << "a field above its budget was built";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("above the memory budget"));
  }
  const Eigen::AlignedBox3d region(Eigen::Vector3d(2.0, 1.0, -5.0), Eigen::Vector3d(8.0, 9.0, 5.0));
  const Esdf part = Esdf::FromMapRegion(forest.map, region, Esdf::PeakBytes(VoxelBox{{20, 10, 0}, {60, 80, 30}}));
  EXPECT_EQ(part.box().num_voxels(), 60 * 80 * 30);
  EXPECT_THROW(Esdf::FromMapRegion(forest.map, region, 60 * 80 * 30 * 9 - 1), std::invalid_argument);
}

TEST(EsdfTest, AnObstacleFreeMapIsBoundedByItsFaces) {
  // A 10 x 10 x 3 m map with no tree: its distance field would be unbounded, so its box's faces
  // count as occupied. Truth: a voxel centre's distance to the nearest face layer is that of its
  // index to the layer, in voxels (the field is exact on the lattice, up to float storage).
  ForestOptions forest;
  forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 10, 3));
  forest.density = 0.0;
  const OccupancyMap map = OccupancyMap::FromGrid(GenerateForest(forest));
  for (const bool region : {false, true}) {
    // A region far larger than the map (a margin of 1e9 m) is the whole map.
    const Esdf esdf = region ? Esdf::FromMapRegion(map, Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-1e9),
                                                                            Eigen::Vector3d::Constant(1e9)))
                             : Esdf::FromMap(map);
    const VoxelBox box = esdf.box();
    ASSERT_EQ(box.size, Eigen::Vector3i(100, 100, 30)) << "region " << region;
    for (const Eigen::Vector3i& v :
         {Eigen::Vector3i(50, 50, 15), Eigen::Vector3i(3, 40, 20), Eigen::Vector3i(60, 97, 10)}) {
      const Eigen::Vector3i from_low = v - box.min, from_high = box.end() - Eigen::Vector3i::Ones() - v;
      const double voxels = std::min(from_low.minCoeff(), from_high.minCoeff());
      // A free centre k voxels from an occupied layer: the zero level set lies half a voxel out.
      EXPECT_NEAR(esdf.VoxelDistance(v), (voxels - 0.5) * map.resolution(), kFloatStorageTolerance)
          << v.transpose() << " region " << region;
    }
  }
}

TEST(EsdfTest, RegionOfInterestIsALowerBoundAndExactAwayFromItsCuts) {
  const test_support::ForestFixture forest(4, 0.15);
  const Esdf whole = Esdf::FromMap(forest.map);
  const Eigen::AlignedBox3d region(Eigen::Vector3d(2.0, 1.0, -5.0), Eigen::Vector3d(8.0, 9.0, 5.0));
  const Esdf part = Esdf::FromMapRegion(forest.map, region);
  const VoxelBox box = part.box();
  ASSERT_EQ(box.min, Eigen::Vector3i(20, 10, 0));  // clipped to the map in z
  ASSERT_EQ(box.size, Eigen::Vector3i(60, 80, 30));
  const double r = part.resolution();
  int equal = 0, checked = 0;
  for (int z = box.min.z(); z < box.end().z(); ++z) {
    for (int y = box.min.y(); y < box.end().y(); ++y) {
      for (int x = box.min.x(); x < box.end().x(); ++x) {
        const Eigen::Vector3i v(x, y, z);
        const double d_part = part.VoxelDistance(v), d_whole = whole.VoxelDistance(v);
        ++checked;
        ASSERT_LE(d_part, d_whole + kFloatStorageTolerance) << v.transpose();
        // Centre distance to the nearest cut layer (x and y faces are cut, z is not).
        const double to_cut =
            r * std::min({x - box.min.x(), box.end().x() - 1 - x, y - box.min.y(), box.end().y() - 1 - y});
        if (d_whole > 0.0 && d_whole + 0.5 * r < to_cut) {
          ASSERT_NEAR(d_part, d_whole, kFloatStorageTolerance) << v.transpose();
          ++equal;
        }
      }
    }
  }
  // The equality is checked on a large part of the region (44% of its voxels here).
  EXPECT_GT(equal, checked / 3);
  // A region that misses the map, and one of zero size, are refused.
  EXPECT_THROW(
      Esdf::FromMapRegion(forest.map, Eigen::AlignedBox3d(Eigen::Vector3d(20, 20, 0), Eigen::Vector3d(30, 30, 3))),
      std::invalid_argument);
  EXPECT_THROW(Esdf::FromMapRegion(forest.map, Eigen::AlignedBox3d(Eigen::Vector3d(2, 2, 1), Eigen::Vector3d(2, 8, 2))),
               std::invalid_argument);
  // A region holding the whole map has no cut: the same field as FromMap.
  const Esdf all = Esdf::FromMapRegion(
      forest.map, Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-50), Eigen::Vector3d::Constant(50)));
  ASSERT_EQ(all.box().size, whole.box().size);
  for (const Eigen::Vector3i& v :
       {Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(50, 50, 15), Eigen::Vector3i(99, 99, 29)}) {
    EXPECT_EQ(all.VoxelDistance(v), whole.VoxelDistance(v));
  }
}

TEST(VoxelBoxTest, CoveringSnapsOutwardsAndRejectsZeroSize) {
  const VoxelBox box =
      VoxelBox::Covering(Eigen::AlignedBox3d(Eigen::Vector3d(-0.15, 0.0, 0.31), Eigen::Vector3d(0.2, 0.05, 0.4)), 0.1);
  EXPECT_EQ(box.min, Eigen::Vector3i(-2, 0, 3));
  EXPECT_EQ(box.size, Eigen::Vector3i(4, 1, 1));
  EXPECT_THROW(VoxelBox::Covering(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 0)), 0.1),
               std::invalid_argument);
  EXPECT_THROW(VoxelBox::Covering(Eigen::AlignedBox3d(), 0.1), std::invalid_argument);
  EXPECT_THROW(VoxelBox::Covering(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()), -1.0),
               std::invalid_argument);
  EXPECT_THROW(VoxelBox::Covering(Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(1e6)), 0.1),
               std::invalid_argument);
}

}  // namespace
}  // namespace timeopt
