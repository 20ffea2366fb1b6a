// Paper vs certified constraint mode (issue 8) on 20 random curves (10 natural cubics and 10
// rest-to-rest minimum-jerk quintics through seeded random walks of 8 waypoints), at K = 30 and 50:
// T increase of certified over paper (median, max), solve-time ratio (median of per-curve ratios of
// median solve times), and the largest limit ratios the dense check finds in each mode.
// Usage: experiment_certified_vs_paper [--out DIR] [--repetitions N]

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/curve/interpolation.h"
#include "timeopt/temporal/temporal_solver.h"

namespace {

using namespace timeopt;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Paper vs certified constraint mode on random curves"};
  std::string out_dir = "results/experiments";
  int repetitions = 7;
  app.add_option("--out", out_dir, "Output directory")->capture_default_str();
  app.add_option("--repetitions", repetitions, "Solves per case (median time)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(out_dir);
  std::ofstream csv(std::filesystem::path(out_dir) / "certified_vs_paper.csv");
  csv << "# vmax 3,3,2 m/s, amax 2,2,1.5 m/s^2, rho 0, rest to rest, SOCP backend, certified_thinning "
      << TemporalProblem().certified_thinning << " (default), median of " << repetitions << " solves\n"
      << "curve,kind,K,T_paper,T_certified,increase_percent,paper_ms,certified_ms,time_ratio,"
         "paper_max_acc_ratio,certified_max_acc_ratio,certified_max_vel_ratio,paper_iterations,"
         "certified_iterations\n";
  csv.precision(10);
  const auto solver = MakeSocpTemporalSolver();
  for (int K : {30, 50}) {
    std::vector<double> increases, ratios, paper_acc, cert_worst;
    for (int c = 0; c < 20; ++c) {
      std::mt19937 rng(1000 + c);
      std::uniform_real_distribution<double> u(-4.0, 4.0);
      Waypoints w(3, 8);
      w.col(0).setZero();
      for (int i = 1; i < 8; ++i) w.col(i) = w.col(i - 1) + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
      const bool quintic = c >= 10;
      TemporalProblem p;
      p.curve = quintic ? MinimumJerkSpline(w) : NaturalCubicSpline(w);
      p.limits.max_velocity = Eigen::Vector3d(3.0, 3.0, 2.0);
      p.limits.max_acceleration = Eigen::Vector3d(2.0, 2.0, 1.5);
      p.cells_per_piece = K;
      TemporalResult r[2];
      double ms[2];
      for (int mode = 0; mode < 2; ++mode) {
        p.constraint_mode = mode == 0 ? ConstraintMode::kPaper : ConstraintMode::kCertified;
        std::vector<double> times;
        for (int rep = 0; rep < repetitions; ++rep) {
          r[mode] = solver->Solve(p);
          times.push_back(r[mode].solve_time_seconds * 1e3);
        }
        ms[mode] = Median(times);
      }
      if (!r[0].is_success() || !r[1].is_success()) {
        std::cerr << "curve " << c << " K " << K << ": " << r[0].message << " / " << r[1].message << "\n";
        continue;
      }
      const double inc = 100.0 * (r[1].total_time / r[0].total_time - 1.0);
      increases.push_back(inc);
      ratios.push_back(ms[1] / ms[0]);
      paper_acc.push_back(r[0].max_acceleration_ratio);
      cert_worst.push_back(std::max(r[1].max_acceleration_ratio, r[1].max_velocity_ratio));
      csv << c << "," << (quintic ? "quintic" : "cubic") << "," << K << "," << r[0].total_time << "," << r[1].total_time
          << "," << inc << "," << ms[0] << "," << ms[1] << "," << ms[1] / ms[0] << "," << r[0].max_acceleration_ratio
          << "," << r[1].max_acceleration_ratio << "," << r[1].max_velocity_ratio << "," << r[0].iterations << ","
          << r[1].iterations << "\n";
    }
    std::cout << "K=" << K << " (" << increases.size() << " curves): T increase median " << Median(increases)
              << "% max " << *std::max_element(increases.begin(), increases.end()) << "%; solve-time ratio median "
              << Median(ratios) << " max " << *std::max_element(ratios.begin(), ratios.end())
              << "; paper max |a|/amax median " << Median(paper_acc) << " max "
              << *std::max_element(paper_acc.begin(), paper_acc.end()) << "; certified worst ratio "
              << *std::max_element(cert_worst.begin(), cert_worst.end()) << "\n";
  }
  std::cout << "written: " << (std::filesystem::path(out_dir) / "certified_vs_paper.csv").string() << "\n";
  return 0;
}
