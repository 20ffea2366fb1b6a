// The A* front end: its statuses, and the optimality of its voxel path against an exhaustive
// Dijkstra search written here from path_search.h's cost model.

#include "timeopt/spatial/path_search.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <queue>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "timeopt/map/esdf.h"
#include "timeopt/map/voxel_grid.h"

#include "../common/map_fixtures.h"

namespace timeopt {
namespace {

using test_support::RandomGrid;
using test_support::WalledBox;

TEST(PathSearch, StatusesNameTheProblem) {
  // A box with a wall at x = 5 (full height and width): a goal behind it is unreachable.
  const Esdf esdf(WalledBox());
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
}

// The graph the search runs on, written from path_search.h: the voxels of the ESDF's box,
// 26-connected; a voxel may be entered when the distance d stored at its centre is at least the
// robot radius r, at the cost
//   step length (voxels) * (1 + clearance_cost_weight * max(0, r + margin - d) / margin).
// The goal's voxel is exempt from both (the search checks the goal point's own clearance instead).
class SearchGraph {
 public:
  SearchGraph(const Esdf& esdf, const PathSearchOptions& options) : esdf_(esdf), options_(options) {}

  // The voxel (world index) holding `point`.
  Eigen::Vector3i VoxelOf(const Eigen::Vector3d& point) const {
    return (point / esdf_.resolution()).array().floor().cast<int>();
  }

  // The cost of the step from voxel `from` into its neighbour `to`, or nothing when `to` may not
  // be entered.
  std::optional<double> StepCost(const Eigen::Vector3i& from, const Eigen::Vector3i& to,
                                 const Eigen::Vector3i& goal) const {
    const double length = (to - from).cast<double>().norm();
    if (to == goal) return length;
    const double d = esdf_.VoxelDistance(to);
    if (d < options_.robot_radius) return std::nullopt;
    const double inflated = options_.robot_radius + options_.clearance_margin;
    return length * (1.0 + options_.clearance_cost_weight * std::max(0.0, inflated - d) / options_.clearance_margin);
  }

  struct Optimum {
    double cost = 0.0;
    int steps = 0;  // of one optimal path
  };
  // Dijkstra's optimal cost from voxel `start` to voxel `goal` over every voxel of the box, or
  // nothing when the goal cannot be reached.
  std::optional<Optimum> Dijkstra(const Eigen::Vector3i& start, const Eigen::Vector3i& goal) const {
    const VoxelBox& box = esdf_.box();
    const auto index = [&box](const Eigen::Vector3i& v) {
      const Eigen::Vector3i l = v - box.min;
      return l.x() + box.size.x() * (l.y() + box.size.y() * l.z());
    };
    std::vector<double> cost(static_cast<size_t>(box.num_voxels()), std::numeric_limits<double>::infinity());
    std::vector<int> steps(cost.size(), 0);
    std::vector<bool> done(cost.size(), false);
    using Entry = std::pair<double, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    cost[index(start)] = 0.0;
    queue.emplace(0.0, index(start));
    while (!queue.empty()) {
      const auto [c, i] = queue.top();
      queue.pop();
      if (done[i]) continue;
      done[i] = true;
      const Eigen::Vector3i v = box.min + Eigen::Vector3i(i % box.size.x(), (i / box.size.x()) % box.size.y(),
                                                          i / (box.size.x() * box.size.y()));
      if (v == goal) return Optimum{c, steps[i]};
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const Eigen::Vector3i w = v + Eigen::Vector3i(dx, dy, dz);
            if (w == v || !box.Contains(w) || done[index(w)]) continue;
            const std::optional<double> step = StepCost(v, w, goal);
            if (step && c + *step < cost[index(w)]) {
              cost[index(w)] = c + *step;
              steps[index(w)] = steps[i] + 1;
              queue.emplace(cost[index(w)], index(w));
            }
          }
        }
      }
    }
    return std::nullopt;
  }

  // The cost of the search's voxel path (start point, voxel centres, goal point), checking that
  // every step goes to a neighbour that may be entered. Sets *steps to the number of steps.
  double PathCost(const PathSearchResult& result, int* steps) const {
    const Eigen::Vector3i goal = VoxelOf(result.voxel_path.rightCols<1>());
    double total = 0.0;
    *steps = static_cast<int>(result.voxel_path.cols()) - 1;
    for (int k = 0; k < *steps; ++k) {
      const Eigen::Vector3i a = VoxelOf(result.voxel_path.col(k));
      const Eigen::Vector3i b = VoxelOf(result.voxel_path.col(k + 1));
      EXPECT_EQ((b - a).cwiseAbs().maxCoeff(), 1) << "step " << k << " is not to a neighbour";
      const std::optional<double> step = StepCost(a, b, goal);
      EXPECT_TRUE(step.has_value()) << "step " << k << " enters a voxel below the robot radius";
      total += step.value_or(std::numeric_limits<double>::infinity());
    }
    return total;
  }

 private:
  const Esdf& esdf_;
  PathSearchOptions options_;
};

// Length of the polyline through the columns.
double PolylineLength(const Waypoints& points) {
  double length = 0.0;
  for (Eigen::Index k = 0; k + 1 < points.cols(); ++k) {
    length += (points.col(k + 1) - points.col(k)).norm();
  }
  return length;
}

// The shortest 26-connected lattice path between two voxels ignoring obstacles, in voxels.
double LatticeDistance(const Eigen::Vector3i& a, const Eigen::Vector3i& b) {
  Eigen::Vector3i d = (a - b).cwiseAbs();
  std::sort(d.data(), d.data() + 3);
  return std::sqrt(3.0) * d(0) + std::sqrt(2.0) * (d(1) - d(0)) + (d(2) - d(1));
}

// On small random maps, A* with heuristic_weight 1 finds the optimal voxel path of the graph above
// (its cost equals Dijkstra's), and with the default weight epsilon = 1.5 one at most epsilon
// times the optimum. The waypoints are the voxel path shortcut by line of sight, which optimizes
// nothing; of them only what the construction guarantees is checked: they are a subsequence of
// the voxel path with its start and goal, and their polyline is no longer than the voxel path's
// and no shorter than the straight line.
//
// Tolerance: A* keeps its costs in float (unit roundoff u = 2^-24). Each step rounds twice, the
// step's cost to float (u of the step) and the sum (u of the running cost), so its cost of a path
// of n steps is off by at most 2 n u relative, two paths can be ranked the wrong way when their
// costs differ by less than twice that, and the priority g + h adds one more rounding: (4 n + 2) u
// relative, n the longer path's step count (1e-5 at 40 steps; distinct voxel paths on these maps
// differ by far more, e.g. a sqrt(2) step against two axis steps).
TEST(PathSearch, VoxelPathIsOptimalAgainstDijkstra) {
  constexpr double kFloatRounding = 1.0 / (1 << 24);
  constexpr double kResolution = 0.2;  // m
  constexpr double kFill[] = {0.05, 0.12, 0.2};
  constexpr double kCostWeight[] = {0.0, 2.0, 5.0};
  int reachable = 0, unreachable = 0, detours = 0, weighted_suboptimal = 0;
  for (int seed = 1; seed <= 36; ++seed) {
    // 16 x 14 x 6 voxels with the box away from the origin (world and local indices differ); every
    // pairing of fill, cost weight and radius over the seeds. Radius 0.4 voxel blocks only
    // occupied voxels, 0.6 also their face neighbours; the soft margin spans 1.5 voxels.
    const Esdf esdf(RandomGrid(Eigen::Vector3i(-4, 3, -1), Eigen::Vector3i(16, 14, 6), kResolution, kFill[seed % 3],
                               static_cast<uint64_t>(seed)));
    PathSearchOptions options;
    options.clearance_cost_weight = kCostWeight[seed / 3 % 3];
    options.robot_radius = (seed / 9 % 2 ? 0.6 : 0.4) * kResolution;
    options.clearance_margin = 1.5 * kResolution;
    PathSearch search(esdf);
    const SearchGraph graph(esdf, options);
    std::mt19937 rng(static_cast<unsigned>(seed));
    const Eigen::AlignedBox3d domain = esdf.domain();
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const auto free_point = [&] {
      for (;;) {
        const Eigen::Vector3d unit(u(rng), u(rng), u(rng));
        const Eigen::Vector3d p = domain.min() + unit.cwiseProduct(domain.sizes());
        if (esdf.Distance(p) >= options.robot_radius) return p;
      }
    };
    for (int pair = 0; pair < 5; ++pair) {
      // Start and goal at least 4 voxels apart on some axis, so that paths have several steps.
      Eigen::Vector3d start, goal;
      do {
        start = free_point();
        goal = free_point();
      } while ((graph.VoxelOf(goal) - graph.VoxelOf(start)).cwiseAbs().maxCoeff() < 4);
      const auto optimum = graph.Dijkstra(graph.VoxelOf(start), graph.VoxelOf(goal));
      const std::string where = "seed " + std::to_string(seed) + " pair " + std::to_string(pair);

      options.heuristic_weight = 1.0;
      const PathSearchResult exact = search.Search(start, goal, options);
      if (!optimum) {
        EXPECT_EQ(exact.status, PathSearchStatus::kUnreachable) << where << ": " << exact.message;
        ++unreachable;
        continue;
      }
      ASSERT_TRUE(exact.is_success()) << where << ": " << exact.message;
      ++reachable;
      int steps = 0;
      const double cost = graph.PathCost(exact, &steps);
      const double tolerance = (4.0 * std::max(steps, optimum->steps) + 2.0) * kFloatRounding * optimum->cost;
      EXPECT_NEAR(cost, optimum->cost, tolerance) << where;
      if (optimum->cost > LatticeDistance(graph.VoxelOf(start), graph.VoxelOf(goal)) + tolerance) {
        ++detours;
      }

      options.heuristic_weight = 1.5;
      const PathSearchResult weighted = search.Search(start, goal, options);
      ASSERT_TRUE(weighted.is_success()) << where << ": " << weighted.message;
      const double weighted_cost = graph.PathCost(weighted, &steps);
      const double weighted_tolerance = (4.0 * std::max(steps, optimum->steps) + 2.0) * kFloatRounding * optimum->cost;
      EXPECT_GE(weighted_cost, optimum->cost - weighted_tolerance) << where;
      EXPECT_LE(weighted_cost, 1.5 * optimum->cost + weighted_tolerance) << where;
      if (weighted_cost > optimum->cost + weighted_tolerance) ++weighted_suboptimal;

      // The waypoints: a subsequence of the voxel path from start to goal, no longer than it
      // (triangle inequality on every replaced stretch; 1e-12 m: rounding of sums of ~40 norms of
      // ~1 m) and no shorter than the straight line.
      for (const PathSearchResult* r : {&exact, &weighted}) {
        ASSERT_GE(r->waypoints.cols(), 2);
        EXPECT_TRUE(r->waypoints.col(0) == start) << where;
        EXPECT_TRUE(r->waypoints.col(r->waypoints.cols() - 1) == goal) << where;
        Eigen::Index next = 0;
        for (Eigen::Index k = 0; k < r->waypoints.cols(); ++k) {
          while (next < r->voxel_path.cols() && r->voxel_path.col(next) != r->waypoints.col(k)) {
            ++next;
          }
          EXPECT_LT(next, r->voxel_path.cols()) << where << ": waypoint " << k << " is off the path";
        }
        EXPECT_LE(PolylineLength(r->waypoints), PolylineLength(r->voxel_path) + 1e-12) << where;
        EXPECT_GE(PolylineLength(r->waypoints), (goal - start).norm() - 1e-12) << where;
      }
    }
  }
  // The maps are not trivial: most pairs are connected, some are not, and in many the optimum
  // leaves the obstacle-free lattice path (around obstacles, or for the clearance cost).
  EXPECT_GE(reachable, 120);
  EXPECT_GE(unreachable, 1);
  EXPECT_GE(detours, reachable / 2);
  std::printf("%d reachable pairs (%d with a detour), %d unreachable; epsilon 1.5 suboptimal in %d\n", reachable,
              detours, unreachable, weighted_suboptimal);
}

}  // namespace
}  // namespace timeopt
