// The spatial optimizer on generated forests: its reported cost never rises, the curve keeps its
// continuity, a free straight line stays straight, and invalid input is reported.

#include "timeopt/spatial/spatial_optimizer.h"

#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "timeopt/map/esdf.h"
#include "timeopt/planner/planner.h"  // SplitSegments: the joints the planner hands the optimizer

#include "../common/map_fixtures.h"

namespace timeopt {
namespace {

using test_support::ForestFixture;
using test_support::FreePoint;

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
      EXPECT_NEAR(result.iterations.front().cost, result.initial_cost.total(), 1e-9 * result.initial_cost.total());
      EXPECT_NEAR(result.iterations.back().cost, result.final_cost.total(), 1e-9 * result.final_cost.total());
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
  const Waypoints joints =
      SplitSegments((Waypoints(3, 2) << Eigen::Vector3d(-50, -50, 20), Eigen::Vector3d(-45, -47, 20)).finished(), 1.0);
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

}  // namespace
}  // namespace timeopt
