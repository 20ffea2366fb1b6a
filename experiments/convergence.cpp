// The paper's Fig. 4: convergence of the spatial stage with and without the time terms. Random
// forest maps from the project's generator at several obstacle densities (trees per square metre,
// 20 x 20 x 3 m, seeded), and per density N random start/goal pairs in free space at least 10 m
// apart. Each pair is planned twice by the planner, whose front end gives both the same waypoints:
// the decoupled spatial optimization (jerk in s, collision, length) and the time-coupled baseline
// (time-parameterized, with its dynamic-feasibility terms), with the same Levenberg-Marquardt
// budget (100 iterations; no wall-clock limit, so runs are deterministic but for their timings).
// The optimizer's iteration records give the cost against time.
//
// Both final curves are timed by the same temporal stage, the planner's default (jerk-limited, the
// same limits), so that flight time, squared jerk and clearance compare curves flown alike.
//
// Outputs in --out DIR: convergence.csv (one row per iteration per test), convergence_summary.csv
// (per density and formulation: success rate, cost reduction reached within --budget-ms, median
// time to converge, final clearance, smoothness = the integral of |jerk|^2 over the flight, then
// the median flight time and the median cost reduction at each budget of kBudgetsMs),
// convergence.png (normalized cost against time on a logarithmic axis, median and quartiles),
// convergence_budgets.png (cost reduction against the budget), convergence_density.png (cost
// reduction at --budget-ms, clearance, smoothness and flight time against density),
// convergence_topview_decoupled.png and convergence_topview_coupled.png (the paper's Fig. 4(a)/(b):
// both trajectories of one test over its forest, coloured by speed on one scale; the first test at
// the second density, or the only one, that both formulations plan). The paper's names and
// colours: with decoupling red, without blue. Tests run in parallel on all cores, each timed on its own thread;
// progress on stderr. Usage: experiment_convergence --out DIR [--tests N] [--budget-ms MS] [--densities D ...]

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/planner/planner.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/viz/plan_plot.h"
#include "timeopt/viz/plot.h"

namespace {

using namespace timeopt;

constexpr const char* kFormulationNames[2] = {"decoupled", "coupled"};                    // in the CSVs
constexpr const char* kFormulationLabels[2] = {"with decoupling", "without decoupling"};  // in the figures
// Budgets at which the cost reduction is read, ms: both formulations converge within a few ms here,
// so the paper's 50 ms alone compares converged objectives.
const std::vector<double> kBudgetsMs = {0.25, 0.5, 1.0, 2.0, 5.0, 50.0};
constexpr SpatialFormulation kFormulations[2] = {SpatialFormulation::kSpatial, SpatialFormulation::kTimeCoupled};

struct Run {
  bool success = false;
  std::vector<SpatialIteration> iterations;
  double clearance = 0.0;
  double smoothness = 0.0;  // integral of |jerk|^2 dt, m^2/s^5
  double converge_ms = 0.0;
  double flight_time = 0.0;  // T of the jerk-limited profile, s
  // The plan's curve quality (PlanResult): NaN for a flight of at most 2 s.
  double min_interior_speed = std::nan("");
  double min_curvature_radius = std::nan("");
};

struct Test {
  double density = 0.0;
  int index = 0;
  int seed = 0;  // the forest's
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), goal = Eigen::Vector3d::Zero();
  Run runs[2];
};

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

// The normalized cost reached by `ms` of solver time (the initial cost / 1 when no iteration has).
double NormalizedCostAt(const std::vector<SpatialIteration>& its, double ms) {
  if (its.empty() || !(its.front().cost > 0.0)) return 1.0;
  double c = its.front().cost;
  for (const SpatialIteration& it : its) {
    if (it.time_seconds * 1e3 > ms) break;
    c = it.cost;
  }
  return c / its.front().cost;
}

PlannerOptions OptionsFor(SpatialFormulation f) {
  PlannerOptions options;
  options.spatial.formulation = f;
  // The same budget for both: the iteration limit (100). No wall-clock limit, so that a run is
  // deterministic whatever the machine's load (the forest plans converge in 10-40 iterations).
  options.spatial.max_solver_time_seconds = 10.0;
  return options;
}

Run PlanOnce(Planner& planner, const Eigen::Vector3d& start, const Eigen::Vector3d& goal, SpatialFormulation f) {
  // Both curves timed by the planner's temporal stage (jerk-limited, the same limits).
  const PlanResult plan = planner.Plan(start, goal, OptionsFor(f));
  Run run;
  run.iterations = plan.spatial.iterations;
  run.success = plan.is_success();
  run.converge_ms = plan.spatial.solve_time_seconds * 1e3;
  if (run.success) {
    run.clearance = plan.min_clearance;
    run.flight_time = plan.temporal.total_time;
    run.min_interior_speed = plan.min_interior_speed;
    run.min_curvature_radius = plan.min_curvature_radius;
    const std::vector<TrajectoryState> samples = Trajectory(plan.curve, plan.temporal.profile).Sample(1000.0);
    for (size_t k = 0; k + 1 < samples.size(); ++k) {
      run.smoothness += samples[k].jerk.squaredNorm() * (samples[k + 1].t - samples[k].t);
    }
  }
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Spatial-stage convergence with and without the time terms (paper Fig. 4)"};
  std::string out = "results/experiments";
  int tests = 500;
  double budget_ms = 50.0;
  std::vector<double> densities = {0.05, 0.1, 0.15, 0.2};
  unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  app.add_option("--out", out, "Output directory")->capture_default_str();
  app.add_option("--tests", tests, "Start/goal pairs per density")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--budget-ms", budget_ms, "Solver time at which the cost reduction is read, ms")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--densities", densities, "Trees per square metre")->capture_default_str();
  app.add_option("--threads", threads, "Worker threads (each test timed on its own)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(out);

  const auto wall_start = std::chrono::steady_clock::now();
  std::vector<Test> all;
  for (size_t di = 0; di < densities.size(); ++di) {
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(20, 20, 3));
    forest.density = densities[di];
    forest.seed = 100 + di;
    const OccupancyMap map = OccupancyMap::FromGrid(GenerateForest(forest));
    const Esdf esdf = Esdf::FromMap(map);
    // Start/goal pairs: seeded, in free space (1 m from obstacles), at least 10 m apart, at 1.5 m.
    std::mt19937 rng(static_cast<unsigned>(7 + di));
    std::uniform_real_distribution<double> u(1.0, 19.0);
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
    while (static_cast<int>(pairs.size()) < tests) {
      const Eigen::Vector3d a(u(rng), u(rng), 1.5), b(u(rng), u(rng), 1.5);
      if ((a - b).norm() < 10.0 || esdf.Distance(a) < 1.0 || esdf.Distance(b) < 1.0) continue;
      pairs.emplace_back(a, b);
    }
    std::vector<Test> results(static_cast<size_t>(tests));
    std::atomic<int> next{0}, done{0};
    std::mutex progress;
    const auto worker = [&] {
      Planner planner(esdf);
      for (int t = next++; t < tests; t = next++) {
        Test& test = results[static_cast<size_t>(t)];
        test.density = densities[di];
        test.index = t;
        test.seed = static_cast<int>(forest.seed);
        test.start = pairs[static_cast<size_t>(t)].first;
        test.goal = pairs[static_cast<size_t>(t)].second;
        for (int f = 0; f < 2; ++f)
          test.runs[f] = PlanOnce(planner, pairs[static_cast<size_t>(t)].first, pairs[static_cast<size_t>(t)].second,
                                  kFormulations[f]);
        const int count = ++done;
        if (count % 25 == 0 || count == tests) {
          std::lock_guard<std::mutex> lock(progress);
          std::cerr << "density " << densities[di] << ": " << count << "/" << tests << " tests, "
                    << std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count() << " s\n";
        }
      }
    };
    std::vector<std::thread> pool;
    for (unsigned k = 0; k < std::min<unsigned>(threads, static_cast<unsigned>(tests)); ++k) pool.emplace_back(worker);
    for (std::thread& th : pool) th.join();
    all.insert(all.end(), results.begin(), results.end());
    // Fig. 4(a)/(b): the first test that both plan, planned again (deterministic) for its curves.
    if (di == std::min<size_t>(1, densities.size() - 1)) {
      for (const Test& t : results) {
        if (!t.runs[0].success || !t.runs[1].success) continue;
        Planner planner(esdf);
        std::vector<Trajectory> trajectories;
        double top_speed = 0.0;
        for (int f = 0; f < 2; ++f) {
          const PlanResult plan =
              planner.Plan(pairs[static_cast<size_t>(t.index)].first, pairs[static_cast<size_t>(t.index)].second,
                           OptionsFor(kFormulations[f]));
          trajectories.emplace_back(plan.curve, plan.temporal.profile);
          for (const TrajectoryState& s : trajectories.back().Sample(100.0))
            top_speed = std::max(top_speed, s.velocity.norm());
        }
        for (int f = 0; f < 2; ++f) {
          PlanImageOptions image;
          image.speed_scale = top_speed;
          image.slice_height = pairs[static_cast<size_t>(t.index)].first.z();  // the same slice for both
          std::ostringstream title;
          title << kFormulationLabels[f] << " (density " << densities[di] << ", test " << t.index << ")";
          image.title = title.str();
          WritePlanPng(esdf, trajectories[f], out + "/convergence_topview_" + kFormulationNames[f] + ".png", image);
        }
        break;
      }
    }
  }

  std::ofstream csv(out + "/convergence.csv");
  csv << "density,test,formulation,time_ms,iteration,cost,normalized_cost\n";
  for (const Test& t : all) {
    for (int f = 0; f < 2; ++f) {
      const auto& its = t.runs[f].iterations;
      const double initial = its.empty() || !(its.front().cost > 0.0) ? 1.0 : its.front().cost;
      for (const SpatialIteration& it : its) {
        csv << t.density << "," << t.index << "," << kFormulationNames[f] << "," << it.time_seconds * 1e3 << ","
            << it.iteration << "," << it.cost << "," << it.cost / initial << "\n";
      }
    }
  }
  // Every test's plans: where, and the figures of each formulation's flight.
  std::ofstream per_test(out + "/convergence_tests.csv");
  per_test << "density,seed,test,start_x,start_y,start_z,goal_x,goal_y,goal_z,formulation,success,flight_time,"
              "clearance,min_interior_speed,min_curvature_radius\n";
  for (const Test& t : all) {
    for (int f = 0; f < 2; ++f) {
      const Run& r = t.runs[f];
      per_test << t.density << "," << t.seed << "," << t.index << "," << t.start.x() << "," << t.start.y() << ","
               << t.start.z() << "," << t.goal.x() << "," << t.goal.y() << "," << t.goal.z() << ","
               << kFormulationNames[f] << "," << (r.success ? 1 : 0) << "," << r.flight_time << "," << r.clearance
               << "," << r.min_interior_speed << "," << r.min_curvature_radius << "\n";
    }
  }
  std::ofstream summary(out + "/convergence_summary.csv");
  summary << "density,formulation,tests,success_rate,median_cost_reduction,q1_cost_reduction,q3_cost_reduction,"
             "median_converge_ms,median_clearance,median_smoothness,median_flight_time";
  for (double b : kBudgetsMs) summary << ",median_cost_reduction_" << b << "ms";
  summary << ",slowest_interior_speed,median_min_curvature_radius\n";
  std::vector<double> reduction_med[2], clearance_med[2], smooth_med[2], flight_med[2];
  std::vector<std::vector<double>> budget_med[2];  // [formulation][density][budget]
  for (double density : densities) {
    for (int f = 0; f < 2; ++f) {
      std::vector<double> reduction, converge, clearance, smooth, flight, radius;
      double slowest = std::numeric_limits<double>::infinity();
      std::vector<std::vector<double>> at_budget(kBudgetsMs.size());
      int success = 0, count = 0;
      for (const Test& t : all) {
        if (t.density != density) continue;
        const Run& r = t.runs[f];
        ++count;
        reduction.push_back(1.0 - NormalizedCostAt(r.iterations, budget_ms));
        for (size_t b = 0; b < kBudgetsMs.size(); ++b)
          at_budget[b].push_back(1.0 - NormalizedCostAt(r.iterations, kBudgetsMs[b]));
        converge.push_back(r.converge_ms);
        if (r.success) {
          ++success;
          clearance.push_back(r.clearance);
          smooth.push_back(r.smoothness);
          flight.push_back(r.flight_time);
          if (std::isfinite(r.min_interior_speed)) slowest = std::min(slowest, r.min_interior_speed);
          if (std::isfinite(r.min_curvature_radius)) radius.push_back(r.min_curvature_radius);
        }
      }
      summary << density << "," << kFormulationNames[f] << "," << count << ","
              << static_cast<double>(success) / std::max(1, count) << "," << Quantile(reduction, 0.5) << ","
              << Quantile(reduction, 0.25) << "," << Quantile(reduction, 0.75) << "," << Quantile(converge, 0.5) << ","
              << Quantile(clearance, 0.5) << "," << Quantile(smooth, 0.5) << "," << Quantile(flight, 0.5);
      std::vector<double> medians;
      for (const auto& values : at_budget) {
        medians.push_back(Quantile(values, 0.5));
        summary << "," << medians.back();
      }
      summary << "," << (std::isfinite(slowest) ? slowest : std::nan("")) << "," << Quantile(radius, 0.5) << "\n";
      budget_med[f].push_back(medians);
      flight_med[f].push_back(Quantile(flight, 0.5));
      reduction_med[f].push_back(Quantile(reduction, 0.5));
      clearance_med[f].push_back(Quantile(clearance, 0.5));
      smooth_med[f].push_back(Quantile(smooth, 0.5));
    }
  }

  // Normalized cost against time, median and quartiles on a common time grid, per density.
  const std::array<double, 3> colors[2] = {{0.85, 0.15, 0.15}, {0.15, 0.35, 0.85}};  // the paper's red, blue
  // The time axis: up to the budget, or to 1.5 x the 95th percentile of the time to converge when
  // that is shorter (the solves here take a few ms, well inside a 50 ms budget).
  std::vector<double> converge_all;
  for (const Test& t : all) {
    for (const Run& r : t.runs) converge_all.push_back(r.converge_ms);
  }
  const double axis_ms = std::min(budget_ms, std::max(1.0, 1.5 * Quantile(converge_all, 0.95)));
  std::vector<PlotPanel> panels;
  for (double density : densities) {
    PlotPanel panel;
    std::ostringstream title;
    title << "density " << density << " trees/m^2: cost / initial cost (median, dashed quartiles)";
    panel.title = title.str();
    panel.x_label = "solver time (ms, logarithmic)";
    panel.y_label = "normalized cost";
    panel.log_x = true;
    for (int f = 0; f < 2; ++f) {
      std::vector<double> x, med, q1, q3;
      constexpr double kFirstMs = 0.05;
      for (int k = 0; k <= 100; ++k) {
        const double ms = kFirstMs * std::pow(axis_ms / kFirstMs, k / 100.0);
        std::vector<double> at;
        for (const Test& t : all) {
          if (t.density == density) at.push_back(NormalizedCostAt(t.runs[f].iterations, ms));
        }
        x.push_back(ms);
        med.push_back(Quantile(at, 0.5));
        q1.push_back(Quantile(at, 0.25));
        q3.push_back(Quantile(at, 0.75));
      }
      panel.series.push_back({kFormulationLabels[f], x, med, colors[f], false});
      panel.series.push_back({"", x, q1, colors[f], true});
      panel.series.push_back({"", x, q3, colors[f], true});
    }
    panels.push_back(panel);
  }
  WritePlotPng(panels, out + "/convergence.png");
  // Cost reduction against the budget, per density.
  std::vector<PlotPanel> budget_panels;
  for (size_t di = 0; di < densities.size(); ++di) {
    PlotPanel panel;
    std::ostringstream title;
    title << "density " << densities[di] << " trees/m^2: cost reduction reached within the budget (median)";
    panel.title = title.str();
    panel.x_label = "budget (ms, logarithmic)";
    panel.y_label = "1 - cost/initial";
    panel.log_x = true;
    for (int f = 0; f < 2; ++f)
      panel.series.push_back({kFormulationLabels[f], kBudgetsMs, budget_med[f][di], colors[f], false});
    budget_panels.push_back(panel);
  }
  WritePlotPng(budget_panels, out + "/convergence_budgets.png");
  PlotPanel reduction{"cost reduction reached in the budget (median)", "density (trees/m^2)", "1 - cost/initial", {}};
  PlotPanel clearance{"final minimum clearance (median)", "density (trees/m^2)", "m", {}};
  PlotPanel smoothness{
      "smoothness: integral of |jerk|^2 over the jerk-limited flight (median)", "density (trees/m^2)", "m^2/s^5", {}};
  PlotPanel flight_time{"flight time of the jerk-limited profile (median)", "density (trees/m^2)", "s", {}};
  for (int f = 0; f < 2; ++f) {
    reduction.series.push_back({kFormulationLabels[f], densities, reduction_med[f], colors[f], false});
    clearance.series.push_back({kFormulationLabels[f], densities, clearance_med[f], colors[f], false});
    smoothness.series.push_back({kFormulationLabels[f], densities, smooth_med[f], colors[f], false});
    flight_time.series.push_back({kFormulationLabels[f], densities, flight_med[f], colors[f], false});
  }
  WritePlotPng({reduction, clearance, smoothness, flight_time}, out + "/convergence_density.png");
  std::cout << "experiment_convergence: " << all.size() << " tests per formulation, written to " << out << "\n";
  return 0;
}
