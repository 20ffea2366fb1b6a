// `timeopt curve WAYPOINTS.csv [--kind cubic|minjerk] -o CURVE.json`

#include <iomanip>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/io/curve_io.h"

namespace timeopt::cli {
namespace {

struct CurveArgs {
  std::string waypoints;
  std::string kind = "minjerk";
  std::string output;
  bool json = false;
};

int RunCurve(const CurveArgs& args) {
  int merged = 0;
  const Waypoints waypoints = ReadDistinctWaypoints(args.waypoints, &merged);
  const PiecewiseCurve curve = args.kind == "cubic" ? NaturalCubicSpline(waypoints) : MinimumJerkSpline(waypoints);
  WriteCurveJson(curve, args.output);

  const ContinuityReport report = curve.Continuity(4);
  const double length = curve.ArcLength(1e-9);
  if (args.json) {
    nlohmann::ordered_json j = {{"kind", args.kind},          {"waypoints", waypoints.cols()},
                                {"merged_waypoints", merged}, {"pieces", curve.num_pieces()},
                                {"length", length},           {"continuity", report.jump},
                                {"output", args.output}};
    std::cout << j.dump(2) << "\n";
    return kExitOk;
  }
  std::cout << "curve: " << args.kind << " through " << waypoints.cols() << " waypoints" << DroppedWaypointsNote(merged)
            << "\n"
            << "pieces: " << curve.num_pieces() << "\n"
            << std::setprecision(9) << "length: " << length << " m\n"
            << "continuity (largest jump at the joints):\n";
  for (size_t d = 0; d < report.jump.size(); ++d) {
    std::cout << "  derivative " << d << ": " << std::setprecision(3) << std::scientific << report.jump[d]
              << std::defaultfloat << "\n";
  }
  std::cout << "written: " << args.output << "\n";
  return kExitOk;
}

}  // namespace

void RegisterCurveCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<CurveArgs>();
  CLI::App* sub =
      app.add_subcommand("curve", "Fit a curve through waypoints (x,y,z CSV rows) with unit piece durations in s");
  sub->add_option("WAYPOINTS", args->waypoints, "Waypoint CSV file, one x,y,z row per waypoint")->required();
  sub->add_option("--kind", args->kind, "cubic: C2 natural cubic; minjerk: minimum-jerk quintic, rest to rest")
      ->check(CLI::IsMember({"cubic", "minjerk"}))
      ->capture_default_str();
  sub->add_option("-o,--output", args->output, "Output curve JSON file")->required();
  sub->add_flag("--json", args->json,
                "Print the summary as JSON (kind, waypoints, pieces, length in m, continuity: the largest jump of "
                "derivatives 0-4 at the joints, output)");
  sub->callback([args, &run] { run = [args] { return RunCurve(*args); }; });
}

}  // namespace timeopt::cli
