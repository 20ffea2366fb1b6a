// Planner stages on a generated 10 x 10 x 3 m forest at 0.1 m (GenerateForest, 0.12 trees/m^2,
// seed 1; no files needed): front-end search, spatial optimization (both formulations) and the
// whole plan, over 16 fixed random start/goal pairs at 1.5 m height cycled through the
// iterations. The forest_gen evaluation with success rates and percentiles is
// experiments/planner_forest.cpp. BM_PlanForest100: one long plan through a 100 x 100 x 4 m forest.

#include <algorithm>
#include <memory>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/spatial/path_search.h"
#include "timeopt/planner/planner.h"
#include "timeopt/spatial/spatial_optimizer.h"

namespace {

using namespace timeopt;

struct Scene {
  std::unique_ptr<Esdf> esdf;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
  std::vector<Waypoints> joints;  // split front-end waypoints of every pair
};

const Scene& GetScene() {
  static const Scene scene = [] {
    Scene s;
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(10, 10, 3));
    forest.density = 0.12;
    forest.seed = 1;
    s.esdf = std::make_unique<Esdf>(GenerateForest(forest));
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> lo(0.5, 3.0), hi(7.0, 9.5);
    PathSearch search(*s.esdf);
    const PlannerOptions options;
    while (s.pairs.size() < 16) {
      const Eigen::Vector3d a(lo(rng), lo(rng), 1.5), b(hi(rng), hi(rng), 1.5);
      if (s.esdf->Distance(a) < 0.5 || s.esdf->Distance(b) < 0.5) continue;
      const PathSearchResult r = search.Search(a, b);
      if (!r.is_success()) continue;
      s.pairs.emplace_back(a, b);
      s.joints.push_back(SplitSegments(r.waypoints, options.max_segment_length));
    }
    return s;
  }();
  return scene;
}

void BM_PathSearch(benchmark::State& state) {
  const Scene& s = GetScene();
  PathSearch search(*s.esdf);
  size_t i = 0;
  for (auto _ : state) {
    const auto& [a, b] = s.pairs[i++ % s.pairs.size()];
    benchmark::DoNotOptimize(search.Search(a, b));
  }
}
BENCHMARK(BM_PathSearch)->Unit(benchmark::kMillisecond);

void BM_SpatialOptimizer(benchmark::State& state) {
  const Scene& s = GetScene();
  SpatialOptimizerOptions options;
  options.formulation = state.range(0) == 0 ? SpatialFormulation::kSpatial : SpatialFormulation::kTimeCoupled;
  options.safe_distance = 0.5;
  state.SetLabel(ToString(options.formulation));
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(OptimizeSpatialCurve(*s.esdf, s.joints[i++ % s.joints.size()], options));
  }
}
BENCHMARK(BM_SpatialOptimizer)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Plans over the scene's start/goal pairs. Arg 0: the paper's temporal profile (no jerk limit, as
// before the planner's default became jerk-limited, so that the figure stays comparable); arg 1:
// the planner's default, jerk-limited at 10 m/s^3.
void BM_Plan(benchmark::State& state) {
  const Scene& s = GetScene();
  Planner planner(*s.esdf);
  PlannerOptions options;
  options.limits.max_velocity.setConstant(2.0);
  options.limits.max_acceleration.setConstant(2.0);
  if (state.range(0) == 0) options.limits.max_jerk.reset();
  size_t i = 0, failures = 0;
  double temporal_ms = 0.0, solves = 0.0, iterations = 0.0;
  for (auto _ : state) {
    const auto& [a, b] = s.pairs[i++ % s.pairs.size()];
    const PlanResult r = planner.Plan(a, b, options);
    failures += r.is_success() ? 0 : 1;
    temporal_ms += 1e3 * r.times.temporal_seconds;
    solves += r.temporal.scp_iterations;
    iterations += r.temporal.iterations;
  }
  const double n = static_cast<double>(std::max<size_t>(i, 1));
  state.counters["failures"] = static_cast<double>(failures);
  // Means per plan: the temporal stage's time, its convex solves and interior-point iterations.
  state.counters["temporal_ms"] = temporal_ms / n;
  state.counters["scp"] = solves / n;
  state.counters["iterations"] = iterations / n;
}
BENCHMARK(BM_Plan)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// A 100 m plan: a 100 x 100 x 4 m forest at 0.1 m (0.05 trees/m^2, seed 3; as `timeopt map
// generate forest --bounds 0 0 0 100 100 4 --density 0.05 --seed 3`), from (5, 5, 1.5) to (95, 95,
// 1.5). Its distance field (40 million voxels, ~360 MB) is built once. Arg 0 without a jerk limit,
// 1 the planner's default. Counters: the temporal stage's share (temporal_ms) and T.
void BM_PlanForest100(benchmark::State& state) {
  static const std::unique_ptr<Esdf> esdf = [] {
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(100, 100, 4));
    forest.density = 0.05;
    forest.seed = 3;
    return std::make_unique<Esdf>(GenerateForest(forest));
  }();
  Planner planner(*esdf);
  PlannerOptions options;
  if (state.range(0) == 0) options.limits.max_jerk.reset();
  PlanResult r;
  for (auto _ : state) r = planner.Plan(Eigen::Vector3d(5, 5, 1.5), Eigen::Vector3d(95, 95, 1.5), options);
  if (!r.is_success()) state.SkipWithError(r.message.c_str());
  state.counters["temporal_ms"] = 1e3 * r.times.temporal_seconds;
  state.counters["T"] = r.temporal.total_time;
}
BENCHMARK(BM_PlanForest100)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
