// The planner's evaluation on the forest_gen maps (Oleynikova et al., IROS 2016) with their
// start/goal pairs: ../shared/maps/forest_gen/forest0..4.bt and start_and_end.csv (100 pairs per
// map). For every robot radius and formulation (the decoupled spatial stage and the time-coupled
// baseline) it plans every pair and writes one CSV row per plan, then prints a summary table:
// success rate, median and 95th percentile of each stage's time, trajectory duration.
// Times are wall-clock per plan once the map's ESDF is built (ESDF build time reported apart).
// Usage: experiment_planner_forest [--shared DIR] [--out FILE.csv] [--radius R ...]
//                                  [--formulation spatial|time_coupled|both] [--max-pairs N]

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/viz/plot.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/planner/planner.h"

namespace {

using namespace timeopt;

struct Pair {
  int trial = 0, map_id = 0;
  Eigen::Vector3d start, goal;
};

std::vector<Pair> ReadPairs(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<Pair> pairs;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream s(line);
    Pair p;
    s >> p.trial >> p.map_id >> p.start.x() >> p.start.y() >> p.start.z() >> p.goal.x() >> p.goal.y() >> p.goal.z();
    if (s) pairs.push_back(p);
  }
  return pairs;
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - i) * (v[j] - v[i]);
}

struct Row {
  double radius;
  std::string formulation;
  int map_id, trial;
  PlanResult plan;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Planner evaluation on the forest_gen maps"};
  std::string shared = "../shared";
  std::string out = "results/planner_forest.csv";
  std::vector<double> radii = {0.3, 0.5};
  std::string formulation = "both";
  int max_pairs = 1000;
  PlannerOptions base;
  app.add_option("--shared", shared, "Directory holding maps/forest_gen")->capture_default_str();
  app.add_option("--out", out, "CSV file, one row per plan")->capture_default_str();
  app.add_option("--radius", radii, "Robot radii, metres")->capture_default_str();
  app.add_option("--formulation", formulation, "spatial, time_coupled or both")
      ->check(CLI::IsMember({"spatial", "time_coupled", "both"}))
      ->capture_default_str();
  app.add_option("--max-pairs", max_pairs, "Pairs per map (at most)")->capture_default_str();
  app.add_option("--max-segment-length", base.max_segment_length, "PlannerOptions::max_segment_length, m")
      ->capture_default_str();
  app.add_option("--cells", base.temporal_cells_per_piece, "Temporal cells per piece K")->capture_default_str();
  double vmax = 2.0, amax = 2.0;  // the `timeopt plan` defaults
  double jmax = 0.0;              // the paper's evaluation: no jerk limit (the planner's default is 10 m/s^3)
  app.add_option("--max-velocity", vmax, "Per-axis velocity limit, m/s")->capture_default_str();
  app.add_option("--max-acceleration", amax, "Per-axis acceleration limit, m/s^2")->capture_default_str();
  app.add_option("--max-jerk", jmax, "Per-axis jerk limit, m/s^3 (0: none, the paper's profile)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  base.limits.max_velocity.setConstant(vmax);
  base.limits.max_acceleration.setConstant(amax);
  if (jmax > 0.0)
    base.limits.max_jerk = Eigen::Vector3d::Constant(jmax);
  else
    base.limits.max_jerk.reset();

  const std::string dir = shared + "/maps/forest_gen";
  std::vector<Pair> pairs;
  try {
    pairs = ReadPairs(dir + "/start_and_end.csv");
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 2;
  }
  std::vector<SpatialFormulation> formulations;
  if (formulation != "time_coupled") formulations.push_back(SpatialFormulation::kSpatial);
  if (formulation != "spatial") formulations.push_back(SpatialFormulation::kTimeCoupled);

  std::vector<Row> rows;
  std::vector<double> esdf_ms;
  for (int map_id = 0; map_id < 5; ++map_id) {
    const std::string path = dir + "/forest" + std::to_string(map_id) + ".bt";
    const OccupancyMap map = OccupancyMap::Load(path);
    const auto t0 = std::chrono::steady_clock::now();
    const Esdf esdf = Esdf::FromMap(map);
    esdf_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    Planner planner(esdf);
    for (double radius : radii) {
      for (SpatialFormulation f : formulations) {
        int count = 0;
        for (const Pair& p : pairs) {
          if (p.map_id != map_id || count++ >= max_pairs) continue;
          PlannerOptions options = base;
          options.robot_radius = radius;
          options.spatial.formulation = f;
          rows.push_back({radius, ToString(f), map_id, p.trial, planner.Plan(p.start, p.goal, options)});
        }
      }
    }
  }

  std::ofstream csv(out);
  csv << "# experiment_planner_forest: maps " << dir << ", PlannerOptions defaults except vmax "
      << base.limits.max_velocity.x() << " m/s, amax " << base.limits.max_acceleration.x() << " m/s^2 per axis, K "
      << base.temporal_cells_per_piece << ", max_segment_length " << base.max_segment_length
      << " m, certified constraints\n";
  csv << "radius,formulation,map_id,trial,status,attempts,pieces,search_ms,spatial_ms,check_ms,"
         "temporal_ms,total_ms,iterations,path_length,min_clearance,duration,baseline_duration,"
         "min_interior_speed,min_curvature_radius\n";
  for (const Row& r : rows) {
    double baseline = 0.0;
    for (double d : r.plan.spatial.durations) baseline += d;
    csv << r.radius << "," << r.formulation << "," << r.map_id << "," << r.trial << "," << ToString(r.plan.status)
        << "," << r.plan.spatial_attempts << "," << r.plan.curve.num_pieces() << ","
        << 1e3 * r.plan.times.search_seconds << "," << 1e3 * r.plan.times.spatial_seconds << ","
        << 1e3 * r.plan.times.check_seconds << "," << 1e3 * r.plan.times.temporal_seconds << ","
        << 1e3 * r.plan.times.total_seconds << "," << r.plan.spatial.iterations.size() << "," << r.plan.path_length
        << "," << r.plan.min_clearance << "," << (r.plan.is_success() ? r.plan.temporal.total_time : 0.0) << ","
        << baseline << "," << r.plan.min_interior_speed << "," << r.plan.min_curvature_radius << "\n";
  }

  // Convergence records (paper Fig. 4): the last spatial attempt's iterations, cost relative to
  // the initial cost, against solver time.
  const std::string iterations_path = out.size() > 4 && out.substr(out.size() - 4) == ".csv"
                                          ? out.substr(0, out.size() - 4) + "_iterations.csv"
                                          : out + "_iterations.csv";
  std::ofstream iters(iterations_path);
  iters << "# spatial optimizer iterations of every plan in " << out << "\n";
  iters << "radius,formulation,map_id,trial,iteration,time_ms,cost,relative_cost,step_accepted\n";
  for (const Row& r : rows) {
    const auto& its = r.plan.spatial.iterations;
    if (its.empty()) continue;
    const double initial = its.front().cost > 0.0 ? its.front().cost : 1.0;
    for (const SpatialIteration& it : its) {
      iters << r.radius << "," << r.formulation << "," << r.map_id << "," << r.trial << "," << it.iteration << ","
            << it.time_seconds * 1e3 << "," << it.cost << "," << it.cost / initial << "," << (it.step_accepted ? 1 : 0)
            << "\n";
    }
  }
  // Median relative cost reached within given solver times (the paper's "cost reduction in a
  // given time"), per radius and formulation.
  std::cout << "Median relative spatial cost (cost / initial cost) reached by solver time:\n"
            << "| radius | formulation | 0.5 ms | 1 ms | 2 ms | 5 ms | final | ms to within 1% of final "
               "(med/p95) | iterations (med/p95) |\n|---|---|---|---|---|---|---|---|---|\n";
  for (double radius : radii) {
    for (SpatialFormulation f : formulations) {
      std::vector<std::vector<double>> at(5);
      std::vector<double> settle_ms, iteration_counts;
      const double limits_ms[4] = {0.5, 1.0, 2.0, 5.0};
      for (const Row& r : rows) {
        if (r.radius != radius || r.formulation != ToString(f)) continue;
        const auto& its = r.plan.spatial.iterations;
        if (its.empty() || !(its.front().cost > 0.0)) continue;
        const double final_cost = its.back().cost;
        for (const SpatialIteration& it : its) {
          if (it.cost <= 1.01 * final_cost) {
            settle_ms.push_back(it.time_seconds * 1e3);
            break;
          }
        }
        iteration_counts.push_back(static_cast<double>(its.size() - 1));
        for (int q = 0; q < 5; ++q) {
          double c = its.front().cost;
          for (const SpatialIteration& it : its) {
            if (q < 4 && it.time_seconds * 1e3 > limits_ms[q]) break;
            c = it.cost;
          }
          at[q].push_back(c / its.front().cost);
        }
      }
      std::cout << "| " << radius << " | " << ToString(f);
      for (int q = 0; q < 5; ++q) std::cout << " | " << std::setprecision(3) << Percentile(at[q], 0.5);
      std::cout << " | " << Percentile(settle_ms, 0.5) << " / " << Percentile(settle_ms, 0.95) << " | "
                << Percentile(iteration_counts, 0.5) << " / " << Percentile(iteration_counts, 0.95) << " |\n";
    }
  }
  std::cout << "\n";

  // Convergence figure (like the paper's Fig. 4c): median cost / initial cost against solver time,
  // both formulations, one panel per radius.
  std::vector<PlotPanel> panels;
  for (double radius : radii) {
    PlotPanel panel;
    std::ostringstream title;
    title << "spatial optimizer convergence on forest_gen pairs, robot radius " << radius << " m (median over plans)";
    panel.title = title.str();
    panel.x_label = "solver time (ms)";
    panel.y_label = "cost / initial cost";
    panel.log_y = true;
    for (SpatialFormulation f : formulations) {
      PlotSeries series;
      series.label = ToString(f);
      series.rgb = f == SpatialFormulation::kSpatial ? std::array<double, 3>{0.85, 0.1, 0.1}
                                                     : std::array<double, 3>{0.1, 0.3, 0.8};
      for (double t_ms = 0.0; t_ms <= 10.0 + 1e-9; t_ms += 0.25) {
        std::vector<double> values;
        for (const Row& r : rows) {
          if (r.radius != radius || r.formulation != ToString(f)) continue;
          const auto& its = r.plan.spatial.iterations;
          if (its.empty() || !(its.front().cost > 0.0)) continue;
          double c = its.front().cost;
          for (const SpatialIteration& it : its) {
            if (it.time_seconds * 1e3 > t_ms) break;
            c = it.cost;
          }
          values.push_back(c / its.front().cost);
        }
        if (values.empty()) continue;
        series.x.push_back(t_ms);
        series.y.push_back(Percentile(values, 0.5));
      }
      panel.series.push_back(series);
    }
    panels.push_back(panel);
  }
  const std::string plot_path = iterations_path.substr(0, iterations_path.size() - 4) + ".png";
  try {
    WritePlotPng(panels, plot_path);
    std::cout << "convergence plot: " << plot_path << "\n\n";
  } catch (const std::exception& e) {
    std::cerr << "convergence plot not written: " << e.what() << "\n";
  }

  std::cout << "ESDF build per map (ms): ";
  for (double v : esdf_ms) std::cout << std::fixed << std::setprecision(1) << v << " ";
  std::cout << "\n\n| radius | formulation | success | failures | search ms (med/p95) | spatial ms "
               "(med/p95) | check ms (med/p95) | temporal ms (med/p95) | total ms (med/p95) | "
               "duration s (med/p95) |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (double radius : radii) {
    for (SpatialFormulation f : formulations) {
      std::vector<double> search, spatial, check, temporal, total, duration;
      int n = 0, ok = 0;
      std::map<std::string, int> failures;
      for (const Row& r : rows) {
        if (r.radius != radius || r.formulation != ToString(f)) continue;
        ++n;
        if (!r.plan.is_success()) {
          ++failures[ToString(r.plan.status)];
          continue;
        }
        ++ok;
        search.push_back(1e3 * r.plan.times.search_seconds);
        spatial.push_back(1e3 * r.plan.times.spatial_seconds);
        check.push_back(1e3 * r.plan.times.check_seconds);
        temporal.push_back(1e3 * r.plan.times.temporal_seconds);
        total.push_back(1e3 * r.plan.times.total_seconds);
        duration.push_back(r.plan.temporal.total_time);
      }
      std::ostringstream fail;
      for (const auto& [k, v] : failures) fail << k << " " << v << " ";
      auto mp = [](const std::vector<double>& v) {
        std::ostringstream s;
        s << std::fixed << std::setprecision(2) << Percentile(v, 0.5) << " / " << Percentile(v, 0.95);
        return s.str();
      };
      std::cout << "| " << radius << " | " << ToString(f) << " | " << ok << "/" << n << " | " << fail.str() << " | "
                << mp(search) << " | " << mp(spatial) << " | " << mp(check) << " | " << mp(temporal) << " | "
                << mp(total) << " | " << mp(duration) << " |\n";
    }
  }
  std::cout << "\nrows: " << out << ", iterations: " << iterations_path << "\n";
  return 0;
}
