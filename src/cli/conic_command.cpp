// `timeopt conic PROBLEM.cbf [--output RESULT.json] [--repeat N]`: solves a conic problem in the
// Conic Benchmark Format with our interior-point solver and writes a JSON result. With --repeat the
// problem is solved N times (re-solves reuse the symbolic analysis, as in re-planning) and
// solve_time_ms is the median, which is what a benchmark against another solver should compare.

#include <algorithm>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "timeopt/conic/cbf.h"
#include "timeopt/conic/solver.h"
#include "timeopt/io/curve_io.h"

namespace timeopt::cli {
namespace {

struct ConicArgs {
  std::string problem;
  std::string output;
  int repeat = 1;
};

int RunConic(const ConicArgs& args) {
  std::istringstream text(ReadTextFile(args.problem));
  const conic::CbfModel model = conic::ReadCbf(text);

  conic::Solver solver;
  conic::Result result;
  std::vector<double> times;
  for (int r = 0; r < args.repeat; ++r) {
    result = solver.Solve(model.problem);
    times.push_back(result.solve_time_seconds);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());

  nlohmann::ordered_json json;
  json["status"] = conic::ToString(result.status);
  json["message"] = result.message;
  // Only an optimal solve has an objective value; otherwise x is a certificate or an unconverged
  // iterate.
  if (result.is_success()) json["objective"] = model.FileObjective(result.primal_objective);
  else json["objective"] = nullptr;
  json["iterations"] = result.iterations;
  json["solve_time_ms"] = times[times.size() / 2] * 1e3;
  json["repeat"] = args.repeat;
  json["reduced_accuracy"] = result.reduced_accuracy;
  json["primal_residual"] = result.primal_residual;
  json["dual_residual"] = result.dual_residual;
  json["gap"] = result.gap;
  json["kkt_method"] = conic::ToString(result.kkt_method);
  json["num_variables"] = model.problem.num_variables();
  json["num_equalities"] = model.problem.num_equalities();
  json["num_cone_rows"] = model.problem.num_cone_rows();
  json["x"] = std::vector<double>(result.x.data(), result.x.data() + result.x.size());
  const std::string out = json.dump(2) + "\n";
  if (args.output.empty()) std::cout << out;
  else WriteTextFile(args.output, out);

  switch (result.status) {
    case conic::Status::kOptimal:
      return kExitOk;
    case conic::Status::kPrimalInfeasible:
      std::cerr << "timeopt: infeasible: " << result.message << "\n";
      return kExitInfeasible;
    default:
      std::cerr << "timeopt: " << conic::ToString(result.status) << ": " << result.message << "\n";
      return kExitFailure;
  }
}

}  // namespace

void RegisterConicCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<ConicArgs>();
  CLI::App* sub = app.add_subcommand(
      "conic", "Solve a conic problem (CBF file: linear, second-order and rotated cones) with our "
               "interior-point solver");
  sub->add_option("PROBLEM", args->problem, "Problem in the Conic Benchmark Format (.cbf)")->required();
  sub->add_option("-o,--output", args->output, "Result JSON file (default: stdout)");
  sub->add_option("--repeat", args->repeat, "Solve N times and report the median solve time")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  sub->callback([args, &run] { run = [args] { return RunConic(*args); }; });
}

}  // namespace timeopt::cli
