// The front-end, the spatial optimizer and the whole planner on generated maps. Collision checks
// go to the occupancy map's voxels directly, not only through the ESDF the planner used.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/spatial/path_search.h"
#include "timeopt/planner/planner.h"
#include "timeopt/spatial/spatial_optimizer.h"

namespace timeopt {
namespace {

// Smallest distance from `p` to the cubes of the occupied voxels within `reach` of it, by asking
// the OcTree about every voxel of the surrounding block (brute force, independent of the ESDF).
double TrueClearance(const OccupancyMap& map, const Eigen::Vector3d& p, double reach) {
  const double r = map.resolution();
  const Eigen::Vector3i lo = ((p.array() - reach) / r).floor().cast<int>();
  const Eigen::Vector3i hi = ((p.array() + reach) / r).floor().cast<int>();
  double best = reach;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Eigen::Vector3d corner = Eigen::Vector3d(x, y, z) * r;
        const Eigen::Vector3d centre = corner + Eigen::Vector3d::Constant(0.5 * r);
        if (!map.IsOccupied(centre)) continue;
        const Eigen::Vector3d nearest = p.cwiseMax(corner).cwiseMin(corner + Eigen::Vector3d::Constant(r));
        best = std::min(best, (p - nearest).norm());
      }
    }
  }
  return best;
}

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

// A free point at height z with at least `clearance` (ESDF), drawn uniformly.
Eigen::Vector3d FreePoint(const Esdf& esdf, std::mt19937* rng, double clearance, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  for (;;) {
    const Eigen::Vector3d p(u(*rng), u(*rng), 1.5);
    if (esdf.Distance(p) >= clearance) return p;
  }
}

TEST(Planner, ForestPlansKeepTheRobotRadiusAgainstTheOctreeVoxels) {
  std::mt19937 rng(7);
  int successes = 0, trials = 0;
  for (uint64_t seed : {1, 2, 3}) {
    const ForestFixture f(seed);
    Planner planner(*f.esdf);
    for (int pair = 0; pair < 4; ++pair) {
      PlannerOptions options;
      options.robot_radius = 0.3;
      Eigen::Vector3d start = FreePoint(*f.esdf, &rng, 0.5, 0.5, 3.0);
      Eigen::Vector3d goal = FreePoint(*f.esdf, &rng, 0.5, 7.0, 9.5);
      const PlanResult plan = planner.Plan(start, goal, options);
      ++trials;
      ASSERT_TRUE(plan.is_success()) << "seed " << seed << " pair " << pair << ": "
                                     << ToString(plan.status) << ": " << plan.message;
      ++successes;
      EXPECT_GE(plan.min_clearance, options.robot_radius + options.clearance_check_margin);
      // Dense check of the curve against the occupied voxels' cubes, 0.01 m steps in s-chords:
      // between samples the robot centre moves at most 0.005 m, the tolerance below.
      double smallest = 1e9;
      for (int i = 0; i < plan.curve.num_pieces(); ++i) {
        const double chord = (plan.curve.Evaluate(i, 1.0) - plan.curve.Evaluate(i, 0.0)).norm();
        const int n = std::max(20, static_cast<int>(std::ceil(2.0 * chord / 0.01)));
        for (int k = 0; k <= n; ++k) {
          smallest = std::min(smallest, TrueClearance(f.map, plan.curve.Evaluate(i, double(k) / n), 1.0));
        }
      }
      EXPECT_GE(smallest, options.robot_radius - 0.005) << "seed " << seed << " pair " << pair;
      // End points are the requested ones (the optimizer keeps start and goal fixed), to round-off.
      EXPECT_LT((plan.curve.Evaluate(0, 0.0) - start).norm(), 1e-9);
      EXPECT_LT((plan.curve.Evaluate(plan.curve.num_pieces() - 1, 1.0) - goal).norm(), 1e-9);
      // Certified temporal rows: the limits hold on the dense check, up to the SOCP tolerance.
      EXPECT_LE(plan.temporal.max_velocity_ratio, 1.0 + 1e-6);
      EXPECT_LE(plan.temporal.max_acceleration_ratio, 1.0 + 1e-6);
      EXPECT_GT(plan.temporal.total_time, 0.0);
    }
  }
  EXPECT_EQ(successes, trials);
}

TEST(SpatialOptimizer, ReportedCostNeverIncreasesAndCollisionDrops) {
  const ForestFixture f(4, 0.2);
  std::mt19937 rng(11);
  for (SpatialFormulation formulation : {SpatialFormulation::kSpatial, SpatialFormulation::kTimeCoupled}) {
    for (int trial = 0; trial < 3; ++trial) {
      // A straight initial line through the forest: it crosses trees, so the collision term works.
      const Eigen::Vector3d a = FreePoint(*f.esdf, &rng, 0.5, 0.5, 2.0);
      const Eigen::Vector3d b = FreePoint(*f.esdf, &rng, 0.5, 8.0, 9.5);
      const Waypoints joints = SplitSegments((Waypoints(3, 2) << a, b).finished(), 0.8);
      SpatialOptimizerOptions options;
      options.formulation = formulation;
      options.safe_distance = 0.5;
      const SpatialResult result = OptimizeSpatialCurve(*f.esdf, joints, options);
      ASSERT_TRUE(result.is_usable()) << result.message;
      ASSERT_FALSE(result.iterations.empty());
      for (size_t k = 1; k < result.iterations.size(); ++k) {
        const SpatialIteration& it = result.iterations[k];
        // The iterate's cost never rises; an accepted step's cost (Ceres' own number) is at most
        // the previous iterate's. Exact comparisons: LM accepts only decreasing steps, and a
        // rejected step keeps the previous number.
        EXPECT_LE(it.cost, result.iterations[k - 1].cost)
            << ToString(formulation) << " trial " << trial << " iteration " << k;
        if (it.step_accepted) {
          EXPECT_LE(it.step_cost, result.iterations[k - 1].cost);
        }
      }
      // The record and the breakdown agree on the start and end cost (Ceres' own evaluation,
      // summation order differs: 1e-9 relative).
      EXPECT_NEAR(result.iterations.front().cost, result.initial_cost.total(),
                  1e-9 * result.initial_cost.total());
      EXPECT_NEAR(result.iterations.back().cost, result.final_cost.total(),
                  1e-9 * result.final_cost.total());
      EXPECT_LE(result.final_cost.collision, result.initial_cost.collision);
      EXPECT_EQ(result.curve.num_pieces(), joints.cols() - 1);
      if (formulation == SpatialFormulation::kSpatial) {
        // C2 in s by construction (shared joint states): round-off only.
        EXPECT_GE(result.curve.Continuity(2).ContinuousUpTo(1e-9), 2);
      } else {
        // C2 in time: f_i'(1) / T_i = f_{i+1}'(0) / T_{i+1} and the same with T^2 for f''.
        ASSERT_EQ(result.durations.size(), static_cast<size_t>(result.curve.num_pieces()));
        for (int i = 0; i + 1 < result.curve.num_pieces(); ++i) {
          const double t0 = result.durations[i], t1 = result.durations[i + 1];
          for (int d = 1; d <= 2; ++d) {
            const Eigen::Vector3d left = result.curve.Evaluate(i, 1.0, d) / std::pow(t0, d);
            const Eigen::Vector3d right = result.curve.Evaluate(i + 1, 0.0, d) / std::pow(t1, d);
            // Round-off of the coefficient products (values of order 1-10): 1e-9.
            EXPECT_LT((left - right).norm(), 1e-9) << "joint " << i << " order " << d;
          }
        }
      }
    }
  }
}

TEST(SpatialOptimizer, StraightLineInFreeSpaceStaysStraight) {
  // Far from every obstacle only jerk and length act; their optimum for rest-to-rest ends and
  // evenly split joints is the straight line (by symmetry the deviation is zero).
  const ForestFixture f(5, 0.01);
  const Waypoints joints = SplitSegments(
      (Waypoints(3, 2) << Eigen::Vector3d(-50, -50, 20), Eigen::Vector3d(-45, -47, 20)).finished(), 1.0);
  const SpatialResult result = OptimizeSpatialCurve(*f.esdf, joints, {});
  ASSERT_TRUE(result.is_usable()) << result.message;
  const Eigen::Vector3d a = joints.col(0), b = joints.col(joints.cols() - 1);
  const Eigen::Vector3d dir = (b - a).normalized();
  for (int i = 0; i < result.curve.num_pieces(); ++i) {
    for (double s : {0.0, 0.3, 0.7}) {
      const Eigen::Vector3d p = result.curve.Evaluate(i, s) - a;
      // Distance to the line: solver tolerances only (1e-6 m).
      EXPECT_LT((p - p.dot(dir) * dir).norm(), 1e-6);
    }
  }
}

TEST(SpatialOptimizer, InvalidInputIsReported) {
  const ForestFixture f(6);
  SpatialOptimizerOptions options;
  options.collision_weight = -1.0;
  const Waypoints joints = (Waypoints(3, 2) << Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(2, 2, 1)).finished();
  SpatialResult r = OptimizeSpatialCurve(*f.esdf, joints, options);
  EXPECT_EQ(r.status, SpatialStatus::kInvalidInput);
  EXPECT_NE(r.message.find("collision_weight"), std::string::npos) << r.message;
  r = OptimizeSpatialCurve(*f.esdf, Waypoints(3, 1), {});
  EXPECT_EQ(r.status, SpatialStatus::kInvalidInput);
  EXPECT_NE(r.message.find("waypoints"), std::string::npos) << r.message;
}

TEST(PathSearch, StatusesNameTheProblem) {
  // A box with a wall at x = 5 (full height and width except nothing): goal behind it unreachable.
  OccupancyGrid grid(0.1, VoxelBox{Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(100, 40, 20)});
  for (int z = 0; z < 20; ++z) {
    for (int y = 0; y < 40; ++y) {
      for (int x = 50; x < 53; ++x) grid.Set(Eigen::Vector3i(x, y, z), true);
    }
  }
  grid.Set(Eigen::Vector3i(20, 30, 10), true);  // one voxel, away from the free test line
  const Esdf esdf(grid);
  PathSearch search(esdf);
  PathSearchOptions options;
  options.robot_radius = 0.3;
  const Eigen::Vector3d start(1.0, 2.0, 1.0), free_goal(4.0, 1.0, 1.0);

  PathSearchResult r = search.Search(start, Eigen::Vector3d(8.0, 2.0, 1.0), options);
  EXPECT_EQ(r.status, PathSearchStatus::kUnreachable) << r.message;
  r = search.Search(start, Eigen::Vector3d(20.0, 2.0, 1.0), options);
  EXPECT_EQ(r.status, PathSearchStatus::kGoalOutsideMap);
  EXPECT_NE(r.message.find("outside"), std::string::npos);
  r = search.Search(Eigen::Vector3d(2.05, 3.05, 1.05), free_goal, options);
  EXPECT_EQ(r.status, PathSearchStatus::kStartInCollision);
  EXPECT_NE(r.message.find("below the robot radius"), std::string::npos);
  r = search.Search(start, Eigen::Vector3d(5.1, 2.0, 1.0), options);
  EXPECT_EQ(r.status, PathSearchStatus::kGoalInCollision);
  options.heuristic_weight = 0.5;
  r = search.Search(start, free_goal, options);
  EXPECT_EQ(r.status, PathSearchStatus::kInvalidInput);
  EXPECT_NE(r.message.find("heuristic_weight"), std::string::npos);
  options.heuristic_weight = 1.0;
  options.max_expanded_nodes = 5;
  r = search.Search(start, free_goal, options);
  EXPECT_EQ(r.status, PathSearchStatus::kNodeLimit);

  // Free straight line: shortcutting leaves only start and goal; reuse of the work arrays.
  options.max_expanded_nodes = 1000000;
  r = search.Search(start, free_goal, options);
  ASSERT_TRUE(r.is_success()) << r.message;
  EXPECT_EQ(r.waypoints.cols(), 2);
  r = search.Search(free_goal, start, options);
  ASSERT_TRUE(r.is_success()) << r.message;
  EXPECT_EQ(r.waypoints.cols(), 2);

  // The planner maps the statuses.
  PlannerOptions plan_options;
  EXPECT_EQ(Plan(esdf, start, Eigen::Vector3d(8.0, 2.0, 1.0), plan_options).status, PlanStatus::kUnreachable);
  plan_options.limits.max_velocity.x() = -1.0;
  const PlanResult bad = Plan(esdf, start, free_goal, plan_options);
  EXPECT_EQ(bad.status, PlanStatus::kInvalidInput);
  EXPECT_NE(bad.message.find("max_velocity"), std::string::npos) << bad.message;

  // Nested options are validated before any stage runs: a status naming the field, never an
  // exception (Planner::Plan used to throw from the temporal solver's factory here).
  Planner planner(esdf);
  PlannerOptions nested;
  nested.socp.tolerance = -1.0;
  PlanResult r2;
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, nested));
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("options.socp.tolerance"), std::string::npos) << r2.message;
  nested = PlannerOptions();
  nested.limits.max_acceleration_change = std::numeric_limits<double>::quiet_NaN();
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, nested));
  EXPECT_EQ(r2.status, PlanStatus::kInvalidInput);
  EXPECT_NE(r2.message.find("max_acceleration_change"), std::string::npos) << r2.message;
  // The same planner then plans with valid options (its solver is remade for them).
  ASSERT_NO_THROW(r2 = planner.Plan(start, free_goal, PlannerOptions()));
  EXPECT_TRUE(r2.is_success()) << r2.message;
}

}  // namespace
}  // namespace timeopt
