// Temporal stage benchmarks (issues 4 and 19): SOCP vs Ipopt over m in {5, 10, 20} pieces and K in
// {30, 50, 100} cells per piece (and m = 10, K = 200), the conic solver alone on the same problems,
// rho, lambda_a, the planner's case, and SOCP time against the number of cells N = m K from 100 to
// 20,000 with its log-log slope. Curves: natural cubic splines through a seeded random walk,
// vmax = 3 m/s, amax = 2 m/s^2 per axis, rest to rest, rho = 0, paper constraints; BM_SocpRho and
// BM_IpoptRho the same at m = 10, K = 50 with rho = 0.1 and 1.
// Run: ./build/temporal_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// `temporal_benchmark --export-cbf DIR` instead writes the SOCPs of m = 10, K = 50 (rho = 0, 0.1 and
// 1) as CBF files for another conic solver (benchmarks/ecos/compare_ecos.sh) and exits.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "timeopt/conic/cbf.h"
#include "timeopt/curve/interpolation.h"
#include "timeopt/temporal/temporal_socp.h"
#include "timeopt/temporal/temporal_solver.h"

namespace {

using namespace timeopt;

TemporalProblem MakeProblem(int pieces, int K, ConstraintMode mode = ConstraintMode::kPaper, double rho = 0.0) {
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> u(-4.0, 4.0);
  Waypoints w(3, pieces + 1);
  w.col(0).setZero();
  for (int i = 1; i <= pieces; ++i) w.col(i) = w.col(i - 1) + Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
  TemporalProblem p;
  p.curve = NaturalCubicSpline(w);
  p.limits.max_velocity.setConstant(3.0);
  p.limits.max_acceleration.setConstant(2.0);
  p.cells_per_piece = K;
  p.constraint_mode = mode;
  p.rho = rho;
  return p;
}

// Solves `p` with one solver per benchmark (its workspace reused across repetitions) and reports
// the result's figures as counters (and the jerk-limited mode's, when it has a jerk limit):
// build_ms and solver_ms (of the last repetition), iterations, us_per_iteration, structured
// (1 when the SOCP backend's structured path answered), rows_per_cell and scp (convex solves).
void RunSolver(benchmark::State& state, TemporalSolver& solver, const TemporalProblem& p) {
  TemporalResult r;
  for (auto _ : state) {
    r = solver.Solve(p);
    // ClobberMemory, not DoNotOptimize(r.total_time): the latter's "+m,r" constraint on a double
    // member corrupted the value with GCC 12 and Google Benchmark 1.7.1.
    benchmark::ClobberMemory();
  }
  if (!r.is_success()) state.SkipWithError(r.message.c_str());
  state.counters["duration_s"] = benchmark::Counter(r.total_time);
  state.counters["iterations"] = r.iterations;
  state.counters["cells"] = static_cast<double>(state.range(0) * state.range(1));
  state.counters["solver_ms"] = r.solve_time_seconds * 1e3;
  state.counters["build_ms"] = r.build_time_seconds * 1e3;
  state.counters["max_acc_ratio"] = r.max_acceleration_ratio;
  state.counters["us_per_iteration"] = r.iterations > 0 ? 1e6 * r.solve_time_seconds / r.iterations : 0.0;
  state.counters["structured"] = r.method == "structured" ? 1.0 : 0.0;
  // Inequality rows of the last convex solve per cell (the jerk-limited mode's working set).
  state.counters["rows_per_cell"] = static_cast<double>(r.rows) / static_cast<double>(state.range(0) * state.range(1));
  if (p.limits.max_jerk) {
    state.counters["scp"] = r.scp_iterations;
    state.counters["max_jerk_ratio"] = r.max_jerk_ratio;
  }
}

void RunProblem(benchmark::State& state, TemporalBackend backend, const TemporalProblem& p) {
  auto solver = MakeTemporalSolver(backend);
  RunSolver(state, *solver, p);
}

void Run(benchmark::State& state, TemporalBackend backend, ConstraintMode mode, double rho = 0.0) {
  RunProblem(state, backend,
             MakeProblem(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), mode, rho));
}

void BM_Socp(benchmark::State& s) { Run(s, TemporalBackend::kSocp, ConstraintMode::kPaper); }
void BM_Ipopt(benchmark::State& s) { Run(s, TemporalBackend::kIpopt, ConstraintMode::kPaper); }
void BM_SocpCertified(benchmark::State& s) { Run(s, TemporalBackend::kSocp, ConstraintMode::kCertified); }

void Grid(benchmark::internal::Benchmark* b) {
  for (int m : {5, 10, 20})
    for (int K : {30, 50, 100}) b->Args({m, K});
  b->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_Socp)->Apply(Grid)->Args({10, 200});
BENCHMARK(BM_SocpCertified)->Apply(Grid)->Args({10, 200});
BENCHMARK(BM_Ipopt)->Apply(Grid);

// The same problems with the conic solver alone (SocpTemporalOptions::structured = false): the
// structured path's gain in the same run. Third argument: 0 paper rows, 1 certified.
void BM_SocpConicOnly(benchmark::State& state) {
  SocpTemporalOptions options;
  options.structured = false;
  auto solver = MakeSocpTemporalSolver(options);
  RunSolver(state, *solver,
            MakeProblem(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                        state.range(2) == 1 ? ConstraintMode::kCertified : ConstraintMode::kPaper));
}
BENCHMARK(BM_SocpConicOnly)
    ->Args({10, 50, 0})
    ->Args({10, 50, 1})
    ->Args({10, 200, 0})
    ->Args({10, 200, 1})
    ->Unit(benchmark::kMillisecond);

// lambda_a (max_acceleration_change = 0.2 m/s^2 per cell): rows over three grid values, which the
// structured path does not take; the conic solver answers.
void BM_SocpLambda(benchmark::State& state) {
  TemporalProblem p = MakeProblem(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  p.limits.max_acceleration_change = 0.2;
  RunProblem(state, TemporalBackend::kSocp, p);
}
BENCHMARK(BM_SocpLambda)->Args({10, 50})->Unit(benchmark::kMillisecond);

// The planner's temporal case: certified rows, K = 20 (PlannerConfig's defaults), on m = 10 and 27
// pieces (the forest plan has 27).
void BM_SocpPlannerCase(benchmark::State& state) { Run(state, TemporalBackend::kSocp, ConstraintMode::kCertified); }
BENCHMARK(BM_SocpPlannerCase)->Args({10, 20})->Args({27, 20})->Unit(benchmark::kMillisecond);

// rho > 0 (the one large rotated cone of eq. 50): m = 10, K = 50, rho = 0.1 * the third argument.
// The jerk-limited mode (limits.max_jerk = 10 m/s^3, 5 x amax) on the same curves: every convex
// solve of the sequential convex programme (and the certified guess), in solver_ms and build_ms;
// compare with BM_Socp and BM_SocpCertified at the same m and K. scp counts the convex solves.
void BM_SocpJerkLimited(benchmark::State& state) {
  TemporalProblem p = MakeProblem(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  p.limits.max_jerk = Eigen::Vector3d::Constant(10.0);
  RunProblem(state, TemporalBackend::kSocp, p);
}
BENCHMARK(BM_SocpJerkLimited)
    ->Args({10, 50})
    ->Args({20, 50})
    ->Args({10, 200})
    ->Args({5, 30})
    ->Unit(benchmark::kMillisecond);

// The quadrotor's own limits (issue 20) on the same curves, no per-axis limits: max_speed 3,
// thrust in [g - 3, g + 3], tilt 0.5 rad. Third argument: 0 paper rows, 1 certified (cones on every
// Bernstein control point). Compare the two, and with BM_Socp (the structured path does not take
// cones: the conic solver answers).
void BM_SocpQuadrotor(benchmark::State& state) {
  TemporalProblem p = MakeProblem(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                                  state.range(2) == 1 ? ConstraintMode::kCertified : ConstraintMode::kPaper);
  p.limits.max_velocity.setConstant(std::numeric_limits<double>::infinity());
  p.limits.max_acceleration.setConstant(std::numeric_limits<double>::infinity());
  p.limits.max_speed = 3.0;
  p.limits.max_thrust = 9.81 + 3.0;
  p.limits.min_thrust = 9.81 - 3.0;
  p.limits.max_tilt = 0.5;
  RunProblem(state, TemporalBackend::kSocp, p);
}
BENCHMARK(BM_SocpQuadrotor)->Args({10, 50, 0})->Args({10, 50, 1})->Unit(benchmark::kMillisecond);

// Issue 21: a start too fast to brake for the curves ahead (m = 10, K = 50, start at 2.9 m/s along
// the first tangent, amax 0.3 m/s^2 per axis). Argument 0: the infeasible solve with its diagnosis;
// 1: with relax_boundary (the closest start, then the solve). Compare with the same problem
// started at 40% of the relaxed speed, feasible (argument 2).
void BM_SocpInfeasibleStart(benchmark::State& state) {
  TemporalProblem p = MakeProblem(10, 50);
  p.limits.max_acceleration.setConstant(0.3);
  const Eigen::Vector3d t = p.curve.Evaluate(0, 0.0, 1).normalized();
  p.boundary.start_velocity = 2.9 * t;
  if (state.range(0) == 1) p.relax_boundary = true;
  if (state.range(0) == 2) {
    p.relax_boundary = true;
    const TemporalResult relaxed = MakeSocpTemporalSolver()->Solve(p);
    p.relax_boundary = false;
    p.boundary.start_velocity = 0.4 * relaxed.boundary_relaxation->start_speed * t;
  }
  auto solver = MakeSocpTemporalSolver();
  TemporalResult r;
  for (auto _ : state) {
    r = solver->Solve(p);
    benchmark::ClobberMemory();
  }
  state.counters["iterations"] = r.iterations;
  state.counters["infeasible"] = r.status == TemporalStatus::kInfeasible ? 1.0 : 0.0;
  state.counters["relaxed"] = r.boundary_relaxation ? 1.0 : 0.0;
}
BENCHMARK(BM_SocpInfeasibleStart)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_SocpRho(benchmark::State& s) {
  Run(s, TemporalBackend::kSocp, ConstraintMode::kPaper, 0.1 * static_cast<double>(s.range(2)));
}
void BM_IpoptRho(benchmark::State& s) {
  Run(s, TemporalBackend::kIpopt, ConstraintMode::kPaper, 0.1 * static_cast<double>(s.range(2)));
}
BENCHMARK(BM_SocpRho)->Args({10, 50, 1})->Args({10, 50, 10})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_IpoptRho)->Args({10, 50, 1})->Args({10, 50, 10})->Unit(benchmark::kMillisecond);

// Scaling in N = m K with K = 50 fixed (m = 2 .. 400).
void BM_SocpScaling(benchmark::State& s) { Run(s, TemporalBackend::kSocp, ConstraintMode::kPaper); }
BENCHMARK(BM_SocpScaling)
    ->Args({2, 50})
    ->Args({5, 50})
    ->Args({20, 50})
    ->Args({50, 50})
    ->Args({100, 50})
    ->Args({200, 50})
    ->Args({400, 50})
    ->Unit(benchmark::kMillisecond);

// Collects the scaling runs to print the log-log slope of time against N after the table.
class SlopeReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.benchmark_name().rfind("BM_SocpScaling", 0) == 0 && !r.error_occurred &&
          (r.run_type == Run::RT_Iteration ? r.repetitions <= 1 : r.aggregate_name == "median")) {
        const auto it = r.counters.find("cells");
        if (it != r.counters.end()) times_[it->second.value] = r.GetAdjustedRealTime();
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    if (times_.size() < 2) return;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double n = static_cast<double>(times_.size());
    for (const auto& [cells, t] : times_) {
      const double x = std::log(cells), y = std::log(t);
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
    }
    const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    GetOutputStream() << "log-log slope of SOCP time against cells (" << times_.begin()->first << " .. "
                      << times_.rbegin()->first << "): " << slope << "\n";
  }

 private:
  std::map<double, double> times_;
};

// Writes the SOCPs that BM_Socp/10/50 and BM_SocpRho solve.
int ExportCbf(const std::string& dir) {
  for (const double rho : {0.0, 0.1, 1.0}) {
    const std::string path = dir + "/temporal_m10_K50_rho" + (rho == 0.0 ? "0" : rho == 0.1 ? "0.1" : "1") + ".cbf";
    std::ofstream out(path);
    if (out) conic::WriteCbf(BuildTemporalSocp(MakeProblem(10, 50, ConstraintMode::kPaper, rho)), out);
    if (!out) {
      std::cerr << "temporal_benchmark: cannot write " << path << "\n";
      return 1;
    }
    std::cout << path << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "--export-cbf") == 0) return ExportCbf(argv[2]);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  SlopeReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
