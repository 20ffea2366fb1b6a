// The paper's Sect. V-C flights, in simulation: a figure-eight loop through gates flown lap after
// lap with the limits raised step by step, and the paper's sharp turn (a fast straight run into a
// near-reverse turn). Each lap: the minimum-jerk curve through the gates (rest to rest, one lap),
// the time-optimal jerk-limited profile (certified rows, jerk 5 x the acceleration limit), and the
// simulated jerk-input quadrotor flying it from hover.
//
// Outputs in --out DIR: flight_loops.csv (course, limits, lap time, the flown largest |v|/vmax and
// |a|/amax, and whether the limits held within 1%), flight_loops.png (lap time and flown ratios
// against the limits), flight_paths.png (top-down paths of the fastest laps, coloured by speed).
// Usage: experiment_flight_loops --out DIR [--levels L ...]

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "timeopt/curve/interpolation.h"
#include "timeopt/sim/quadrotor_sim.h"
#include "timeopt/temporal/temporal_solver.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/viz/plot.h"

#include "sharp_turn.h"

namespace {

using namespace timeopt;

// Gates of a figure eight, 8 x 4 m at 1.5 m height, one lap from the centre back to it.
Waypoints FigureEight() {
  constexpr int kGates = 12;
  Waypoints w(3, kGates + 1);
  for (int k = 0; k <= kGates; ++k) {
    const double t = 2.0 * M_PI * k / kGates;
    w.col(k) = Eigen::Vector3d(4.0 * std::sin(t), 2.0 * std::sin(2.0 * t), 1.5 + 0.3 * std::sin(t));
  }
  return w;
}

using experiments::SharpTurn;

struct Lap {
  std::string course;
  double vmax = 0.0, amax = 0.0, jmax = 0.0;
  bool solved = false;
  double lap_time = 0.0;
  double flown_v = 0.0, flown_a = 0.0;
  bool held = false;
  std::vector<TrajectoryState> samples;
};

Lap Fly(const std::string& course, const Waypoints& gates, double level) {
  Lap lap;
  lap.course = course;
  lap.vmax = level;
  lap.amax = level;
  lap.jmax = 5.0 * level;
  TemporalProblem p;
  p.curve = MinimumJerkSpline(gates);
  p.limits.max_velocity.setConstant(lap.vmax);
  p.limits.max_acceleration.setConstant(lap.amax);
  p.limits.max_jerk = Eigen::Vector3d::Constant(lap.jmax);
  p.constraint_mode = ConstraintMode::kCertified;
  p.cells_per_piece = 30;
  const TemporalResult r = MakeSocpTemporalSolver()->Solve(p);
  if (!r.is_success()) {
    std::cerr << course << " at level " << level << ": " << r.message << "\n";
    return lap;
  }
  lap.solved = true;
  lap.lap_time = r.total_time;
  const Trajectory trajectory(p.curve, r.profile);
  QuadrotorSimOptions options;
  options.limit_tolerance = 0.01;  // the product's flight criterion for jerk-limited plans
  const FeasibilityReport flight =
      QuadrotorSim(options).Fly(trajectory, p.limits, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  lap.flown_v = flight.max_velocity_ratio;
  lap.flown_a = flight.max_acceleration_ratio;
  lap.held = flight.feasible;
  lap.samples = trajectory.Sample(200.0);
  return lap;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Flights with rising limits (paper Sect. V-C), in simulation"};
  std::string out = "results/experiments";
  std::vector<double> levels = {1.0, 2.0, 3.0, 4.0, 5.0};
  app.add_option("--out", out, "Output directory")->capture_default_str();
  app.add_option("--levels", levels, "Limits per lap: vmax = amax = level, jmax = 5 level")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(out);

  std::vector<Lap> laps;
  for (const auto& [name, gates] : {std::pair<std::string, Waypoints>{"figure_eight", FigureEight()},
                                    std::pair<std::string, Waypoints>{"sharp_turn", SharpTurn()}}) {
    for (double level : levels) {
      laps.push_back(Fly(name, gates, level));
      std::cerr << name << " level " << level << ": lap " << laps.back().lap_time << " s\n";
    }
  }

  std::ofstream csv(out + "/flight_loops.csv");
  csv << "course,max_velocity,max_acceleration,max_jerk,solved,lap_time,flown_velocity_ratio,"
         "flown_acceleration_ratio,limits_held\n";
  for (const Lap& l : laps) {
    csv << l.course << "," << l.vmax << "," << l.amax << "," << l.jmax << "," << (l.solved ? 1 : 0) << "," << l.lap_time
        << "," << l.flown_v << "," << l.flown_a << "," << (l.held ? 1 : 0) << "\n";
  }

  const std::array<double, 3> colors[2] = {{0.15, 0.35, 0.85}, {0.85, 0.25, 0.15}};
  PlotPanel time{"lap time against the limits (vmax = amax = level, jmax = 5 level)", "level", "lap time (s)", {}};
  PlotPanel ratios{
      "flown by the jerk-input quadrotor: largest |v|/vmax (solid), |a|/amax (dashed)", "level", "ratio", {}};
  const std::string courses[2] = {"figure_eight", "sharp_turn"};
  for (int c = 0; c < 2; ++c) {
    std::vector<double> x, t, v, a;
    for (const Lap& l : laps) {
      if (l.course != courses[c] || !l.solved) continue;
      x.push_back(l.vmax);
      t.push_back(l.lap_time);
      v.push_back(l.flown_v);
      a.push_back(l.flown_a);
    }
    time.series.push_back({courses[c], x, t, colors[c], false});
    ratios.series.push_back({courses[c], x, v, colors[c], false});
    ratios.series.push_back({"", x, a, colors[c], true});
  }
  WritePlotPng({time, ratios}, out + "/flight_loops.png");

  // Top-down paths of the fastest laps, coloured by speed (five bins from slow, blue, to fast, red).
  std::vector<PlotPanel> paths;
  for (const std::string& course : courses) {
    const Lap* fastest = nullptr;
    for (const Lap& l : laps) {
      if (l.course == course && l.solved && (!fastest || l.vmax > fastest->vmax)) fastest = &l;
    }
    if (!fastest) continue;
    PlotPanel panel;
    std::ostringstream title;
    title << course << " at level " << fastest->vmax << ": top-down path coloured by speed (blue slow, red fast)";
    panel.title = title.str();
    panel.x_label = "x (m)";
    panel.y_label = "y (m)";
    double top = 0.0;
    for (const TrajectoryState& s : fastest->samples) top = std::max(top, s.velocity.norm());
    for (size_t k = 0; k + 1 < fastest->samples.size(); ++k) {
      const TrajectoryState& s = fastest->samples[k];
      const TrajectoryState& e = fastest->samples[k + 1];
      const double f = top > 0.0 ? std::min(1.0, s.velocity.norm() / top) : 0.0;
      panel.series.push_back({"",
                              {s.position.x(), e.position.x()},
                              {s.position.y(), e.position.y()},
                              {0.1 + 0.8 * f, 0.2, 0.9 - 0.8 * f},
                              false});
    }
    paths.push_back(panel);
  }
  WritePlotPng(paths, out + "/flight_paths.png", 1000, 420);
  std::cout << "experiment_flight_loops: " << laps.size() << " laps, written to " << out << "\n";
  return 0;
}
