// What it costs to make a time-optimal profile trackable: for a few curves and the acceleration-change
// bound lambda_a of the temporal problem (paper eqs. 44-49) from none to 0.02 m/s^2 per cell, the
// minimum time T and how the default jerk-input quadrotor of sim/ (tracking bandwidth 10 rad/s,
// 1 kHz, starting at rest) flies the result: its largest |v|/vmax and |a|/amax. Without lambda_a the
// reference acceleration jumps between cells and the vehicle overshoots by 0.206 x the jump.
// Writes tracking_vs_lambda.csv and tracking_vs_lambda.png (x axis log10 lambda_a).
// Usage: experiment_tracking_vs_lambda [--out DIR] [--waypoints FILE.csv] [-K K]

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"
#include "timeopt/viz/plot.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"

namespace {

using namespace timeopt;

struct NamedCurve {
  std::string name;
  PiecewiseCurve curve;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Minimum time and simulated tracking against the acceleration-change bound lambda_a"};
  std::string out_dir = "results/experiments";
  std::string waypoints_path = "examples/waypoints.csv";
  int K = 50;
  app.add_option("--out", out_dir, "Output directory")->capture_default_str();
  app.add_option("--waypoints", waypoints_path, "Waypoints CSV for the minimum-jerk curve")->capture_default_str();
  app.add_option("-K", K, "Cells per piece")->check(CLI::Range(1, 1000))->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::vector<NamedCurve> curves;
  Waypoints line(3, 2);
  line << 0, 10, 0, 0, 0, 0;
  curves.push_back({"line_10m", NaturalCubicSpline(line)});
  try {
    curves.push_back({"waypoints_minjerk", MinimumJerkSpline(ReadWaypointsCsv(waypoints_path))});
  } catch (const std::exception& e) {
    std::cerr << "skipping " << waypoints_path << ": " << e.what() << "\n";
  }
  for (int c = 0; c < 3; ++c) {
    std::mt19937 rng(2000 + c);
    std::uniform_real_distribution<double> u(-4.0, 4.0);
    Waypoints w(3, 8);
    w.col(0).setZero();
    for (int i = 1; i < 8; ++i) w.col(i) = w.col(i - 1) + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
    curves.push_back({"random_minjerk_" + std::to_string(c), MinimumJerkSpline(w)});
  }
  const std::vector<std::optional<double>> lambdas = {std::nullopt, 2.0, 1.0, 0.5, 0.2, 0.1, 0.05, 0.02};

  std::filesystem::create_directories(out_dir);
  const std::filesystem::path csv_path = std::filesystem::path(out_dir) / "tracking_vs_lambda.csv";
  std::ofstream csv(csv_path);
  const QuadrotorSim sim;
  csv << "# vmax 2 m/s, amax 2 m/s^2 per axis, rest to rest, K " << K
      << ", certified rows, SOCP; vehicle: jerk input, bandwidth " << sim.options().bandwidth << " rad/s, "
      << 1.0 / sim.options().time_step << " Hz, settle " << sim.options().settle_time << " s, from rest\n"
      << "curve,lambda_a,status,T,reference_max_acc_ratio,flown_max_vel_ratio,flown_max_acc_ratio,limits_hold\n";
  csv.precision(10);
  const auto solver = MakeSocpTemporalSolver();
  PlotPanel time_panel{"minimum time T", "log10 lambda_a (m/s^2 per cell)", "T (s)", {}};
  PlotPanel acc_panel{
      "flown max |a| / amax (dashed: without lambda_a)", "log10 lambda_a (m/s^2 per cell)", "ratio", {}};
  const std::array<std::array<double, 3>, 5> colors = {
      {{0.1, 0.3, 0.8}, {0.8, 0.2, 0.1}, {0.1, 0.6, 0.2}, {0.6, 0.3, 0.7}, {0.9, 0.6, 0.0}}};
  for (size_t c = 0; c < curves.size(); ++c) {
    PlotSeries t_series{curves[c].name, {}, {}, colors[c % colors.size()]};
    PlotSeries a_series = t_series;
    double unbounded_acc = 0.0;
    for (const auto& lambda : lambdas) {
      TemporalProblem p;
      p.curve = curves[c].curve;
      p.limits.max_velocity.setConstant(2.0);
      p.limits.max_acceleration.setConstant(2.0);
      p.limits.max_acceleration_change = lambda;
      p.cells_per_piece = K;
      p.constraint_mode = ConstraintMode::kCertified;
      const TemporalResult r = solver->Solve(p);
      csv << curves[c].name << ",";
      if (lambda)
        csv << *lambda;
      else
        csv << "none";
      csv << "," << ToString(r.status);
      if (!r.is_success()) {
        csv << ",,,,,\n";
        std::cerr << curves[c].name << " lambda " << (lambda ? *lambda : 0.0) << ": " << r.message << "\n";
        continue;
      }
      const FeasibilityReport f =
          sim.Fly(Trajectory(p.curve, r.profile), p.limits, p.boundary.start_velocity, p.boundary.start_acceleration);
      csv << "," << r.total_time << "," << r.max_acceleration_ratio << "," << f.max_velocity_ratio << ","
          << f.max_acceleration_ratio << "," << (f.feasible ? 1 : 0) << "\n";
      std::cout << curves[c].name << " lambda_a ";
      if (lambda)
        std::cout << *lambda;
      else
        std::cout << "none";
      std::cout << ": T " << r.total_time << " s, flown max |v|/vmax " << f.max_velocity_ratio << ", max |a|/amax "
                << f.max_acceleration_ratio << (f.feasible ? " (limits hold)" : "") << "\n";
      if (!lambda) {
        unbounded_acc = f.max_acceleration_ratio;
        continue;
      }
      t_series.x.push_back(std::log10(*lambda));
      t_series.y.push_back(r.total_time);
      a_series.x.push_back(std::log10(*lambda));
      a_series.y.push_back(f.max_acceleration_ratio);
    }
    if (!a_series.x.empty()) {
      PlotSeries flat{
          "", {a_series.x.front(), a_series.x.back()}, {unbounded_acc, unbounded_acc}, colors[c % colors.size()], true};
      acc_panel.series.push_back(flat);
    }
    time_panel.series.push_back(t_series);
    acc_panel.series.push_back(a_series);
  }
  PlotSeries one{
      "limit", {std::log10(lambdas.back().value()), std::log10(lambdas[1].value())}, {1.0, 1.0}, {0.0, 0.0, 0.0}, true};
  acc_panel.series.push_back(one);
  const std::filesystem::path png = std::filesystem::path(out_dir) / "tracking_vs_lambda.png";
  WritePlotPng({time_panel, acc_panel}, png.string());
  std::cout << "written: " << csv_path.string() << ", " << png.string() << "\n";
  return 0;
}
