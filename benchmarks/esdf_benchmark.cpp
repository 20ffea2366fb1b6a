// Benchmarks of the ESDF (timeopt::Esdf) against OctoMap's DynamicEDTOctomap (libdynamicedt3d) on
// the same maps in the same run.
//
// Maps:
//   forest40  a 40 x 40 x 5 m random forest at 0.1 m (8 M voxels; GenerateForest, density 0.1
//             trees/m^2, radii 0.15-0.4 m, seed 1), written to a temporary .bt and loaded back;
//   geb079    OctoMap's scan of building 079 (0.08 m, 487 x 187 x 39 voxels), from
//             $TIMEOPT_SHARED_DIR/maps/geb079.bt or ../shared/maps/geb079.bt beside the source
//             tree; skipped with a message when absent.
// Unknown space counts as free for both (DynamicEDTOctomap's treatUnknownAsOccupied = false), both
// cover the map's known box.
//
//   BM_EsdfBuild/<map>            Esdf::FromMap: rasterize the octree, two exact distance transforms.
//   BM_DynamicEdtBuild/<map>/<d>  DynamicEDTOctomap constructor + update(): d = "full" uses a
//                                 maximum distance of the box diagonal (the same unbounded field as
//                                 ours), d = "2m" the clamped field planners often ask it for.
//   Counters: voxels, MiB_held (heap memory the built field holds: glibc mallinfo2 before and
//             after, while it is alive; temporaries freed during the build are not counted),
//             MiB_values (our distance array).
//   BM_Query{Random,Ordered}/<map>  DistanceAndGradient per point (virtual call through
//                                   DistanceField); ns_per_query = time / points.
//   BM_Batch{Random,Ordered}/<map>  Esdf::Distances with gradients on the same points.
//   BM_DynamicEdtQuery{Random,Ordered}/<map>  DynamicEDTOctomap::getDistance (nearest voxel, no
//                                   gradient) on the same points, for reference.
// Random points: 1 M uniform in the interpolation domain. Ordered points: 1 M points along random
// segments of 5 m inside the domain, 0.02 m apart (what a trajectory optimizer queries).
// Medians over repetitions are the aggregates named *_median.
//
// Run (the README table):
//   build-map/esdf_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//       --benchmark_out=esdf_benchmark.json --benchmark_out_format=json      (one command line)

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <malloc.h>
#include <octomap/OcTree.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"

namespace {

using timeopt::DistanceField;
using timeopt::Esdf;
using timeopt::OccupancyMap;

// Heap bytes in use (glibc: small blocks plus mmapped blocks), MiB. The difference before and
// after a build, while the field is alive, is the memory the field holds.
double HeapMiB() {
  const struct mallinfo2 info = mallinfo2();
  return static_cast<double>(info.uordblks + info.hblkhd) / (1024.0 * 1024.0);
}

struct BenchMap {
  std::string name;
  std::string path;
  std::unique_ptr<OccupancyMap> map;
  std::unique_ptr<octomap::OcTree> tree;  // the same file, for DynamicEDTOctomap
  std::unique_ptr<Esdf> esdf;
  Eigen::Matrix3Xd random_points, ordered_points;
};

void MakePoints(BenchMap* m) {
  const Eigen::AlignedBox3d domain = m->esdf->domain();
  const Eigen::Vector3d lo = domain.min(), extent = domain.max() - domain.min();
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int n = 1 << 20;
  m->random_points.resize(3, n);
  for (int j = 0; j < n; ++j) {
    m->random_points.col(j) = lo + extent.cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
  }
  m->ordered_points.resize(3, n);
  const double step = 0.02, length = 5.0;
  int j = 0;
  while (j < n) {
    const Eigen::Vector3d a = lo + extent.cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    Eigen::Vector3d b = a + length * Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
    b = b.cwiseMax(lo).cwiseMin(domain.max());
    const int samples = std::max(2, static_cast<int>((b - a).norm() / step));
    for (int k = 0; k < samples && j < n; ++k, ++j) {
      m->ordered_points.col(j) = a + (b - a) * (static_cast<double>(k) / (samples - 1));
    }
  }
}

std::vector<BenchMap>& Maps() {
  static std::vector<BenchMap> maps;
  return maps;
}

void LoadMap(const std::string& name, const std::string& path) {
  BenchMap m;
  m.name = name;
  m.path = path;
  m.map = std::make_unique<OccupancyMap>(OccupancyMap::Load(path));
  m.tree = std::make_unique<octomap::OcTree>(path);
  m.esdf = std::make_unique<Esdf>(Esdf::FromMap(*m.map));
  MakePoints(&m);
  Maps().push_back(std::move(m));
}

void SetMapCounters(benchmark::State& state, const BenchMap& m) {
  state.counters["voxels"] = static_cast<double>(m.esdf->box().num_voxels());
}

void BM_EsdfBuild(benchmark::State& state, const BenchMap* m) {
  double rss = 0.0;
  for (auto _ : state) {
    const double before = HeapMiB();
    Esdf esdf = Esdf::FromMap(*m->map);
    rss = HeapMiB() - before;
    benchmark::DoNotOptimize(esdf.resolution());
    state.counters["MiB_values"] = static_cast<double>(esdf.memory_bytes()) / (1024.0 * 1024.0);
  }
  state.counters["MiB_held"] = rss;
  SetMapCounters(state, *m);
}

void BM_DynamicEdtBuild(benchmark::State& state, const BenchMap* m, bool full) {
  const Eigen::AlignedBox3d domain = m->esdf->domain();  // first and last voxel centres
  const octomap::point3d lo(static_cast<float>(domain.min().x()), static_cast<float>(domain.min().y()),
                            static_cast<float>(domain.min().z()));
  const octomap::point3d hi(static_cast<float>(domain.max().x()), static_cast<float>(domain.max().y()),
                            static_cast<float>(domain.max().z()));
  const float max_distance = full ? static_cast<float>((domain.max() - domain.min()).norm() + 1.0) : 2.0f;
  double rss = 0.0;
  for (auto _ : state) {
    const double before = HeapMiB();
    DynamicEDTOctomap edt(max_distance, m->tree.get(), lo, hi, false);
    edt.update(true);
    rss = HeapMiB() - before;
    benchmark::DoNotOptimize(edt.getMaxDist());
  }
  state.counters["MiB_held"] = rss;
  SetMapCounters(state, *m);
}

void BM_Query(benchmark::State& state, const BenchMap* m, bool ordered) {
  const Eigen::Matrix3Xd& points = ordered ? m->ordered_points : m->random_points;
  const DistanceField& field = *m->esdf;
  Eigen::Vector3d g;
  double sum = 0.0;
  for (auto _ : state) {
    for (Eigen::Index j = 0; j < points.cols(); ++j) {
      sum += field.DistanceAndGradient(points.col(j), &g);
      sum += g.x();
    }
    benchmark::DoNotOptimize(sum);
  }
  state.counters["ns_per_query"] = benchmark::Counter(static_cast<double>(state.iterations() * points.cols()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  SetMapCounters(state, *m);
}

void BM_Batch(benchmark::State& state, const BenchMap* m, bool ordered) {
  const Eigen::Matrix3Xd& points = ordered ? m->ordered_points : m->random_points;
  Eigen::VectorXd distances(points.cols());
  Eigen::Matrix3Xd gradients(3, points.cols());
  for (auto _ : state) {
    m->esdf->Distances(points, &distances, &gradients);
    benchmark::DoNotOptimize(distances.data());
    benchmark::DoNotOptimize(gradients.data());
  }
  state.counters["ns_per_query"] = benchmark::Counter(static_cast<double>(state.iterations() * points.cols()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  SetMapCounters(state, *m);
}

void BM_DynamicEdtQuery(benchmark::State& state, const BenchMap* m, bool ordered) {
  // A full-range DynamicEDTOctomap, built once per benchmark (not timed).
  const Eigen::AlignedBox3d domain = m->esdf->domain();
  const octomap::point3d lo(static_cast<float>(domain.min().x()), static_cast<float>(domain.min().y()),
                            static_cast<float>(domain.min().z()));
  const octomap::point3d hi(static_cast<float>(domain.max().x()), static_cast<float>(domain.max().y()),
                            static_cast<float>(domain.max().z()));
  DynamicEDTOctomap edt(static_cast<float>((domain.max() - domain.min()).norm() + 1.0), m->tree.get(), lo, hi, false);
  edt.update(true);
  const Eigen::Matrix3Xd& points = ordered ? m->ordered_points : m->random_points;
  std::vector<octomap::point3d> p(static_cast<size_t>(points.cols()));
  for (Eigen::Index j = 0; j < points.cols(); ++j) {
    p[static_cast<size_t>(j)] = octomap::point3d(static_cast<float>(points(0, j)), static_cast<float>(points(1, j)),
                                                 static_cast<float>(points(2, j)));
  }
  double sum = 0.0;
  for (auto _ : state) {
    for (const auto& q : p) sum += edt.getDistance(q);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["ns_per_query"] = benchmark::Counter(static_cast<double>(state.iterations() * points.cols()),
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  SetMapCounters(state, *m);
}

std::string SharedMapPath() {
  if (const char* dir = std::getenv("TIMEOPT_SHARED_DIR")) {
    return std::string(dir) + "/maps/geb079.bt";
  }
  const std::filesystem::path source(__FILE__);
  return (source.parent_path().parent_path().parent_path() / "shared" / "maps" / "geb079.bt").string();
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  // forest40: generated, written and loaded back like any map file.
  timeopt::ForestOptions forest;
  forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(40, 40, 5));
  forest.resolution = 0.1;
  forest.density = 0.1;
  forest.seed = 1;
  const std::string forest_path =
      (std::filesystem::temp_directory_path() / "timeopt_esdf_benchmark_forest40.bt").string();
  OccupancyMap::FromGrid(timeopt::GenerateForest(forest)).Save(forest_path);
  LoadMap("forest40", forest_path);
  const std::string geb = SharedMapPath();
  if (std::filesystem::exists(geb)) {
    LoadMap("geb079", geb);
  } else {
    std::fprintf(stderr, "geb079 skipped: %s not found (set TIMEOPT_SHARED_DIR)\n", geb.c_str());
  }

  for (const BenchMap& m : Maps()) {
    const BenchMap* p = &m;
    benchmark::RegisterBenchmark(("BM_EsdfBuild/" + m.name).c_str(), BM_EsdfBuild, p)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(3);
    benchmark::RegisterBenchmark(("BM_DynamicEdtBuild/" + m.name + "/full").c_str(), BM_DynamicEdtBuild, p, true)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
    benchmark::RegisterBenchmark(("BM_DynamicEdtBuild/" + m.name + "/2m").c_str(), BM_DynamicEdtBuild, p, false)
        ->Unit(benchmark::kMillisecond)
        ->Iterations(1);
    for (const bool ordered : {false, true}) {
      const std::string kind = ordered ? "Ordered/" : "Random/";
      benchmark::RegisterBenchmark(("BM_Query" + kind + m.name).c_str(), BM_Query, p, ordered)
          ->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark(("BM_Batch" + kind + m.name).c_str(), BM_Batch, p, ordered)
          ->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark(("BM_DynamicEdtQuery" + kind + m.name).c_str(), BM_DynamicEdtQuery, p, ordered)
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::filesystem::remove(forest_path);
  return 0;
}
