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
#include "timeopt/core/files.h"
#include "timeopt/io/conic_io.h"

namespace timeopt::cli {
namespace {

struct ConicArgs {
  std::string problem;
  std::string output;
  int repeat = 1;
  int64_t max_memory_mib = DefaultMemoryBudgetMiB();
};

// The solve's peak memory before fill-in, bytes: 64 MiB for the process, 400 bytes per variable,
// equality and cone row, 200 per non-zero of A and G (measured 2026-12-03: 320-375 bytes per
// variable and row on 2e6 of each without non-zeros, 1.28-1.50 GB; 183 per non-zero on a banded
// LP of 2e5 variables and 2e6 non-zeros, 517 MB). What the budget leaves goes to the sparse KKT
// factor's fill-in, which the solver counts before allocating it (SolverOptions::max_factor_bytes).
double ConicPeakBytes(const conic::Problem& p) {
  constexpr double kProcessBytes = 64.0 * (1 << 20), kRowBytes = 400.0, kNonZeroBytes = 200.0;
  const double rows = static_cast<double>(p.num_variables()) + p.num_equalities() + p.num_cone_rows();
  const double nonzeros = static_cast<double>(p.A.nonZeros()) + p.G.nonZeros();
  return kProcessBytes + kRowBytes * rows + kNonZeroBytes * nonzeros;
}

int RunConic(const ConicArgs& args) {
  std::istringstream text(ReadTextFile(args.problem));
  const conic::CbfModel model = conic::ReadCbf(text);
  const double peak = ConicPeakBytes(model.problem);
  if (peak > static_cast<double>(args.max_memory_mib) * (1 << 20)) {
    std::ostringstream m;
    m << "'" << args.problem << "': " << model.problem.num_variables() << " variables, "
      << model.problem.num_equalities() + model.problem.num_cone_rows() << " rows and "
      << model.problem.A.nonZeros() + model.problem.G.nonZeros() << " non-zeros need about "
      << static_cast<int64_t>(peak / (1 << 20)) << " MiB, above the memory budget of " << args.max_memory_mib
      << " MiB (a larger --max-memory)";
    throw std::invalid_argument(m.str());
  }

  conic::SolverOptions options;
  options.max_factor_bytes =
      std::max<int64_t>(1, static_cast<int64_t>(static_cast<double>(args.max_memory_mib) * (1 << 20) - peak));
  conic::Solver solver(options);
  conic::Result result;
  std::vector<double> times;
  for (int r = 0; r < args.repeat; ++r) {
    result = solver.Solve(model.problem);
    times.push_back(result.solve_time_seconds);
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());

  const double median = times[times.size() / 2];
  nlohmann::ordered_json json = nlohmann::ordered_json::parse(ConicResultToJson(model, result, median));
  json["repeat"] = args.repeat;
  const std::string out = json.dump(2) + "\n";
  if (args.output.empty())
    std::cout << out;
  else
    WriteTextFile(args.output, out);
  if (!result.is_success()) {
    std::cerr << "timeopt: " << conic::ToString(result.status) << ": " << result.message << "\n";
  }
  return ExitCodeFor(result.status);
}

}  // namespace

void RegisterConicCommand(CLI::App& app, Runner& run) {
  auto args = std::make_shared<ConicArgs>();
  CLI::App* sub =
      app.add_subcommand("conic",
                         "Solve a conic problem (CBF file: linear, second-order and rotated cones) with our "
                         "interior-point solver");
  sub->add_option("PROBLEM", args->problem, "Problem in the Conic Benchmark Format (.cbf)")->required();
  sub->add_option("-o,--output", args->output, "Result JSON file (default: stdout)");
  sub->add_option("--repeat", args->repeat, "Solve N times and report the median solve time")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  AddMemoryOption(sub, &args->max_memory_mib,
                  "Memory budget, MiB: a problem whose estimated peak (docs/sizes-and-errors.md) is above it "
                  "is refused before solving, and so is one whose KKT factor with its fill-in does not fit "
                  "in what is left; default: half of this machine's memory");
  sub->callback([args, &run] { run = [args] { return RunConic(*args); }; });
}

}  // namespace timeopt::cli
