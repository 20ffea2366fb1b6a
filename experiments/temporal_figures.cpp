// Reproduces the temporal-stage figures of Gao et al. (IROS 2018) as CSV files plus PNG plots:
//   1. optimal time allocation vs. a heuristic allocation on the same curve (paper Sect. V-C),
//   2. the effect of rho (paper Fig. 5a-d), 3. the effect of K (Fig. 5e-h),
//   4. solve times of the SOCP (our conic solver) and Ipopt against problem size.
// Usage: experiment_temporal_figures [--out DIR] [--repetitions N]
// Every CSV starts with a comment line giving the conditions of the run.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/curve/interpolation.h"
#include "timeopt/viz/plot.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"

#include "sharp_turn.h"

namespace {

using namespace timeopt;

using experiments::SharpTurn;

Waypoints RandomWalk(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  Waypoints w(3, count);
  w.col(0).setZero();
  for (int i = 1; i < count; ++i) w.col(i) = w.col(i - 1) + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
  return w;
}

TemporalProblem MakeProblem(const PiecewiseCurve& curve, int K, double rho) {
  TemporalProblem p;
  p.curve = curve;
  p.limits.max_velocity.setConstant(3.0);
  p.limits.max_acceleration.setConstant(2.0);
  p.cells_per_piece = K;
  p.rho = rho;
  return p;
}

// Heuristic allocation: every piece gets the same duration h (so the curve, C4 in s, stays C4 in
// time), the smallest h for which velocity and acceleration limits hold everywhere (checked on
// 201 samples per piece). This is the uniform time scaling many planners apply after fitting.
double HeuristicTime(const PiecewiseCurve& curve, const TemporalLimits& limits, std::vector<double>* durations) {
  const int m = curve.num_pieces();
  std::vector<double> h(m, 1.0);
  // With durations h_i: v = f'/h, a = f''/h^2. Scaling all by k: v/k, a/k^2.
  double k = 0.0;
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j <= 200; ++j) {
      const double s = j / 200.0;
      const Eigen::Vector3d v = curve.Evaluate(i, s, 1) / h[i];
      const Eigen::Vector3d a = curve.Evaluate(i, s, 2) / (h[i] * h[i]);
      k = std::max(k, v.cwiseAbs().cwiseQuotient(limits.max_velocity).maxCoeff());
      k = std::max(k, std::sqrt(a.cwiseAbs().cwiseQuotient(limits.max_acceleration).maxCoeff()));
    }
  }
  double total = 0.0;
  durations->assign(m, 0.0);
  for (int i = 0; i < m; ++i) {
    (*durations)[i] = h[i] * k;
    total += (*durations)[i];
  }
  return total;
}

struct Csv {
  explicit Csv(const std::filesystem::path& path, const std::string& conditions, const std::string& header)
      : out(path) {
    if (!out) throw std::runtime_error("cannot write " + path.string());
    out << "# " << conditions << "\n" << header << "\n";
    out.precision(12);
  }
  std::ofstream out;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Temporal-stage figures of Gao et al. 2018 (CSV + PNG)"};
  std::string out_dir = "results/experiments";
  int repetitions = 7;
  app.add_option("--out", out_dir, "Output directory")->capture_default_str();
  app.add_option("--repetitions", repetitions, "Repetitions per timing (median reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const std::filesystem::path dir(out_dir);
  std::filesystem::create_directories(dir);
  const auto socp = MakeSocpTemporalSolver();
  const auto ipopt = MakeIpoptTemporalSolver();
  const std::array<double, 3> kColors[6] = {{0.1, 0.1, 0.1},   {0.85, 0.2, 0.15}, {0.15, 0.6, 0.2},
                                            {0.15, 0.3, 0.85}, {0.7, 0.4, 0.0},   {0.6, 0.1, 0.6}};

  // ---- 1. optimal vs heuristic allocation ----
  {
    Csv csv(dir / "allocation.csv", "vmax 3 m/s, amax 2 m/s^2 per axis, K 50, rho 0, paper rows, rest to rest",
            "case,pieces,optimal_T,heuristic_T,ratio");
    PlotPanel panel{
        "speed along the sharp-turn course: optimal vs heuristic allocation", "t [s]", "|v| [m/s]", {}, false};
    struct Case {
      std::string name;
      Waypoints w;
    };
    std::vector<Case> cases = {{"sharp_turn", SharpTurn()}};
    for (unsigned seed = 1; seed <= 5; ++seed) cases.push_back({"random_" + std::to_string(seed), RandomWalk(9, seed)});
    for (const Case& c : cases) {
      const PiecewiseCurve curve = MinimumJerkSpline(c.w);
      const TemporalProblem p = MakeProblem(curve, 50, 0.0);
      const TemporalResult r = socp->Solve(p);
      std::vector<double> h;
      const double heuristic = HeuristicTime(curve, p.limits, &h);
      csv.out << c.name << "," << curve.num_pieces() << "," << (r.is_success() ? r.total_time : NAN) << "," << heuristic
              << "," << heuristic / r.total_time << "\n";
      if (c.name == "sharp_turn" && r.is_success()) {
        const Trajectory traj(curve, r.profile);
        PlotSeries opt{"optimal (SOCP)", {}, {}, kColors[1], false};
        for (const auto& s : traj.Sample(200.0)) {
          opt.x.push_back(s.t);
          opt.y.push_back(s.velocity.norm());
        }
        PlotSeries heu{"uniform time scaling", {}, {}, kColors[3], false};
        double t0 = 0.0;
        for (int i = 0; i < curve.num_pieces(); ++i) {
          for (int j = 0; j <= 100; ++j) {
            const double s = j / 100.0;
            heu.x.push_back(t0 + s * h[i]);
            heu.y.push_back(curve.Evaluate(i, s, 1).norm() / h[i]);
          }
          t0 += h[i];
        }
        panel.series = {opt, heu};
      }
    }
    WritePlotPng({panel}, (dir / "allocation.png").string());
  }

  // ---- 2. rho sweep and 3. K sweep on the sharp turn ----
  const PiecewiseCurve turn = MinimumJerkSpline(SharpTurn());
  {
    Csv csv(dir / "rho_sweep.csv", "sharp turn, vmax 3, amax 2, K 50, SOCP", "rho,T,sum_a2_ds,iterations");
    PlotPanel speed{"speed for several rho (paper Fig. 5a-d)", "t [s]", "|v| [m/s]", {}, false};
    PlotPanel acc{"acceleration magnitude for several rho", "t [s]", "|a| [m/s^2]", {}, false};
    int color = 0;
    for (double rho : {0.0, 1.0, 10.0, 100.0}) {
      const TemporalResult r = socp->Solve(MakeProblem(turn, 50, rho));
      if (!r.is_success()) {
        csv.out << rho << ",nan,nan," << r.iterations << "\n";
        continue;
      }
      double energy = 0.0;
      for (int i = 0; i < r.profile.num_pieces(); ++i)
        for (int k = 0; k < r.profile.cells_per_piece(); ++k) energy += std::pow(r.profile.a(i, k), 2) * r.profile.CellLength(i, k);
      csv.out << rho << "," << r.total_time << "," << energy << "," << r.iterations << "\n";
      const Trajectory traj(turn, r.profile);
      PlotSeries sv{"rho " + std::to_string(static_cast<int>(rho)), {}, {}, kColors[color], false}, sa = sv;
      for (const auto& s : traj.Sample(200.0)) {
        sv.x.push_back(s.t);
        sv.y.push_back(s.velocity.norm());
        sa.x.push_back(s.t);
        sa.y.push_back(s.acceleration.norm());
      }
      speed.series.push_back(sv);
      acc.series.push_back(sa);
      ++color;
    }
    WritePlotPng({speed, acc}, (dir / "rho_sweep.png").string());
  }
  {
    Csv csv(dir / "k_sweep.csv", "sharp turn, vmax 3, amax 2, rho 0, SOCP; T against K",
            "K,T,iterations,solve_ms_median,max_acceleration_ratio");
    PlotPanel tk{"total time against K (paper Fig. 5e-h)", "K", "T [s]", {}, false};
    PlotSeries series{"T", {}, {}, kColors[0], false};
    for (int K : {5, 10, 20, 30, 50, 100, 200}) {
      std::vector<double> times;
      TemporalResult r;
      for (int rep = 0; rep < repetitions; ++rep) {
        r = socp->Solve(MakeProblem(turn, K, 0.0));
        times.push_back(r.solve_time_seconds * 1e3);
      }
      csv.out << K << "," << (r.is_success() ? r.total_time : NAN) << "," << r.iterations << "," << Median(times) << ","
              << r.max_acceleration_ratio << "\n";
      if (r.is_success()) {
        series.x.push_back(K);
        series.y.push_back(r.total_time);
      }
    }
    tk.series.push_back(series);
    WritePlotPng({tk}, (dir / "k_sweep.png").string());
  }

  // ---- 4. solve times against size ----
  {
    Csv csv(dir / "solve_times.csv",
            "random-walk natural cubics, vmax 3, amax 2, rho 0, paper rows; median of " + std::to_string(repetitions) +
                " solves (Ipopt: of 3)",
            "pieces,K,cells,socp_ms,socp_iterations,ipopt_ms,ipopt_iterations,T_socp,T_ipopt");
    PlotPanel panel{"solve time against cells N = m K", "cells", "median solve time [ms] (log)", {}, true};
    PlotSeries s_socp{"SOCP (ours)", {}, {}, kColors[1], false}, s_ipopt{"Ipopt", {}, {}, kColors[3], false};
    for (int m : {5, 10, 20}) {
      for (int K : {30, 50, 100}) {
        const TemporalProblem p = MakeProblem(NaturalCubicSpline(RandomWalk(m + 1, 99)), K, 0.0);
        std::vector<double> ts, ti;
        TemporalResult a, b;
        for (int rep = 0; rep < repetitions; ++rep) {
          a = socp->Solve(p);
          ts.push_back(a.solve_time_seconds * 1e3);
        }
        for (int rep = 0; rep < 3; ++rep) {
          b = ipopt->Solve(p);
          ti.push_back(b.solve_time_seconds * 1e3);
        }
        csv.out << m << "," << K << "," << m * K << "," << Median(ts) << "," << a.iterations << "," << Median(ti) << ","
                << b.iterations << "," << a.total_time << "," << b.total_time << "\n";
        s_socp.x.push_back(m * K);
        s_socp.y.push_back(Median(ts));
        s_ipopt.x.push_back(m * K);
        s_ipopt.y.push_back(Median(ti));
      }
    }
    // Sort by cells for a clean line.
    for (PlotSeries* s : {&s_socp, &s_ipopt}) {
      std::vector<size_t> idx(s->x.size());
      for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
      std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return s->x[a] < s->x[b]; });
      PlotSeries sorted = *s;
      for (size_t i = 0; i < idx.size(); ++i) {
        sorted.x[i] = s->x[idx[i]];
        sorted.y[i] = s->y[idx[i]];
      }
      *s = sorted;
    }
    panel.series = {s_socp, s_ipopt};
    WritePlotPng({panel}, (dir / "solve_times.png").string());
  }
  std::cout << "experiment results written to " << dir.string() << "\n";
  return 0;
}
