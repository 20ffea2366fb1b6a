// Runs the real `timeopt` executable and checks exit codes, messages and outputs.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../common/run_cli.h"

#include "timeopt/io/curve_io.h"
#include "timeopt/core/errors.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;

using testing_support::CliRun;
using testing_support::RunCli;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("timeopt_cli_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const std::string& text) const { std::ofstream(Path(name)) << text; }
  std::filesystem::path dir_;
};

TEST_F(CliTest, HelpAndVersion) {
  const CliRun help = RunCli("curve --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_THAT(help.output, HasSubstr("--kind"));
  const CliRun version = RunCli("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_THAT(version.output, HasSubstr("timeopt 0."));
}

TEST_F(CliTest, CurveFitsAndWritesJson) {
  Write("w.csv", "x,y,z\n0,0,0\n1,0,0\n1,1,0\n2,1,1\n");
  for (const std::string kind : {"cubic", "minjerk"}) {
    const CliRun r = RunCli("curve " + Path("w.csv") + " --kind " + kind + " -o " + Path("c.json"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("pieces: 3"));
    EXPECT_THAT(r.output, HasSubstr("length: "));
    EXPECT_THAT(r.output, HasSubstr("derivative 2: "));
    const CurveFile f = ReadCurveJson(Path("c.json"));
    ASSERT_EQ(f.curve.num_pieces(), 3);
    // The written curve passes through the last waypoint (JSON keeps full precision).
    EXPECT_LT((f.curve.Evaluate(2, 1.0) - Eigen::Vector3d(2, 1, 1)).norm(), 1e-12);
  }
}

TEST_F(CliTest, BadInputExitsWithTwoAndOneLine) {
  Write("bad.csv", "0,0,0\n1,x,0\n");
  CliRun r = RunCli("curve " + Path("bad.csv") + " -o " + Path("c.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("line 2"));
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;

  r = RunCli("curve " + Path("missing.csv") + " -o " + Path("c.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("missing.csv"));

  r = RunCli("curve " + Path("bad.csv") + " --kind septic -o " + Path("c.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--kind"));

  r = RunCli("");
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace timeopt

namespace timeopt {
namespace {

TEST_F(CliTest, TemporalSolvesTheContractExample) {
  for (const std::string solver : {"socp", "ipopt"}) {
    const CliRun r =
        RunCli("temporal " + std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json --solver " + solver +
               " --output " + Path("r.json") + " --samples " + Path("s.csv") + " --rate 10 --plot " + Path("p.png"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string json = ReadTextFile(Path("r.json"));
    EXPECT_THAT(json, HasSubstr("\"status\": \"optimal\""));
    EXPECT_THAT(json, HasSubstr("\"solver\": \"" + solver + "\""));
    EXPECT_THAT(json, HasSubstr("\"total_time\": 7.0")) << json;          // closed form L/v + v/a = 7
    EXPECT_THAT(json, HasSubstr("\"reduced_accuracy\": false")) << json;  // the line solves to full accuracy
    const std::string csv = ReadTextFile(Path("s.csv"));
    EXPECT_EQ(csv.rfind("t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz\n", 0), 0u);
    // 7 s at 10 Hz: t = 0.0 .. 6.9 plus the final state at 7.0.
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 71);
    EXPECT_GT(std::filesystem::file_size(Path("p.png")), 1000u);
  }
}

TEST_F(CliTest, TemporalExitCodes) {
  Write("fast.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0},
    "boundary": {"start_velocity": [5, 0, 0]}, "discretization": {"K": 10}})");
  CliRun r = RunCli("temporal " + Path("fast.json") + " -o " + Path("r.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_THAT(ReadTextFile(Path("r.json")), HasSubstr("\"status\": \"infeasible\""));

  Write("bad.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": -2.0, "max_acceleration": 1.0}})");
  r = RunCli("temporal " + Path("bad.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("limits.max_velocity"));

  Write("typo.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0}, "rhoo": 1})");
  r = RunCli("temporal " + Path("typo.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("rhoo: unknown key"));

  r = RunCli("temporal " + Path("nothing.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("nothing.json"));
}

// The top-level number `key` of a JSON text (NaN when absent or not a number); nested blocks such
// as "flight" are read with JsonNumberIn.
double JsonNumberIn(const std::string& json, const std::string& block, const std::string& key) {
  const nlohmann::json j = nlohmann::json::parse(json, nullptr, false);
  const nlohmann::json* at = &j;
  if (!block.empty()) {
    if (!j.is_object() || !j.contains(block)) return std::nan("");
    at = &j[block];
  }
  if (!at->is_object() || !at->contains(key) || !(*at)[key].is_number()) return std::nan("");
  return (*at)[key].get<double>();
}
double JsonNumber(const std::string& json, const std::string& key) { return JsonNumberIn(json, "", key); }

// examples/line_problem.json is a 10 m line, vmax 2, amax 1, rest to rest: T = L/v + v/a = 7 s in
// closed form, and with rho = 0 the SOCP's optimal value is T. The exported file, read back and
// solved by `timeopt conic`, must give it; 1e-7 is the solver's 1e-8 tolerances with room for T ~ 7.
TEST_F(CliTest, RequestsThatCannotBeMetAreRefusedBeforeAnyOutput) {
  // 7 s at 1e8 Hz is 7e8 samples, above the cap of 1e8: one line and exit 2, and no result on
  // stdout (it was printed first, then the samples failed).
  const std::string line = std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json";
  CliRun r = RunCli("temporal " + line + " --samples " + Path("s.csv") + " --rate 1e8", "2>" + Path("err.txt"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "");
  EXPECT_THAT(ReadTextFile(Path("err.txt")), HasSubstr("more than 1e8 samples"));
  EXPECT_FALSE(std::filesystem::exists(Path("s.csv")));
  // A memory budget below the solve's estimated peak (64 MiB for the process alone): refused first.
  r = RunCli("temporal " + line + " --max-memory 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("above the memory budget of 1 MiB"));
  // simulate solves the same problem first, under the same budget, before it flies anything.
  r = RunCli("simulate " + line + " --max-memory 1 -o " + Path("sim.json"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("above the memory budget of 1 MiB"));
  EXPECT_FALSE(std::filesystem::exists(Path("sim.json")));
  // --ipopt-seconds: Ipopt's CPU cap; 0 turns the socp solver's fallback off, and is no cap for Ipopt.
  r = RunCli("temporal " + line + " --ipopt-seconds 0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunCli("temporal " + line + " --solver ipopt --ipopt-seconds 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("max_solve_time_seconds"));
  // And for a conic problem: min x s.t. x >= 1 needs 64 MiB for the process alone.
  Write("tiny.cbf",
        "VER\n3\nOBJSENSE\nMIN\nVAR\n1 1\nF 1\nCON\n1 1\nL+ 1\nOBJACOORD\n1\n0 1\nACOORD\n1\n0 0 1\nBCOORD\n1\n0 -1\n");
  r = RunCli("conic " + Path("tiny.cbf") + " --max-memory 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("above the memory budget of 1 MiB"));
  r = RunCli("conic " + Path("tiny.cbf"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // The same plan with start == goal: a message that says so, not the temporal stage's "zero length".
  r = RunCli("plan --start 1,1,1.5 --goal 1,1,1.5 -q");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("start and goal are the same point"));
}

TEST_F(CliTest, AVerySlowPlanEndsWithinItsSampleCaps) {
  // Limits of 1e-6 make the default plan last about 2.2e7 s: the plan's quality scan (10 ms steps)
  // and its picture (100 Hz) asked for 2e9 samples and never ended. Now the CSV is thinned to at
  // most 1e6 rows (the rate in output_rate_hz), and the flight check, above its 1e8 steps, says so.
  const CliRun r = RunCli("plan --max-velocity 1e-6 --max-acceleration 1e-6 --max-jerk 1e-6 -o " + Path("slow.csv") +
                              " --plot " + Path("slow.png"),
                          "2>" + Path("err.txt"));
  ASSERT_EQ(r.exit_code, 0) << ReadTextFile(Path("err.txt"));
  const nlohmann::json summary = nlohmann::json::parse(r.output);
  const double T = summary["total_time"].get<double>();
  EXPECT_GT(T, 1e7);
  const double rate = summary["output_rate_hz"].get<double>();
  EXPECT_NEAR(rate * T, 1e6, 1.0);
  EXPECT_THAT(summary["flight"]["error"].get<std::string>(), HasSubstr("1e8 steps"));
  const std::string csv = ReadTextFile(Path("slow.csv"));
  EXPECT_LE(std::count(csv.begin(), csv.end(), '\n'), 1000002);
}

TEST_F(CliTest, AnObstacleFreeMapIsPlannedInsideItsBox) {
  // A 10 x 10 x 3 m map without a tree: the distance field's box faces bound it, so the plan
  // succeeds, with a margin far larger than the map clipped to it, and keeps the robot radius
  // (0.3 m) plus its margin from the box's walls.
  CliRun r = RunCli("map generate forest --density 0 --bounds 0 0 0 10 10 3 -o " + Path("empty.bt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string extra : {"", " --whole-map", " --region-margin 1e9"}) {
    r = RunCli("plan --map " + Path("empty.bt") + " --start 1,1,1.5 --goal 9,9,1.5 -q -o " + Path("p.csv") + extra);
    EXPECT_EQ(r.exit_code, 0) << extra << ": " << r.output;
  }
  // A map whose resolution is absurd is refused when read, naming the range.
  r = RunCli("map generate forest --density 0 --resolution 1e300 --bounds 0 0 0 1e300 1e300 1e300 -o " +
             Path("huge.bt"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("[1e-6, 1e6]"));
}

TEST_F(CliTest, TemporalExportsItsSocpAndConicSolvesItToTheClosedForm) {
  CliRun r = RunCli("temporal " + std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json" + " --export-cbf " +
                    Path("line.cbf") + " -o " + Path("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(JsonNumber(ReadTextFile(Path("r.json")), "objective"), 7.0, 1e-7);
  r = RunCli("conic " + Path("line.cbf") + " --repeat 3 -o " + Path("c.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = ReadTextFile(Path("c.json"));
  EXPECT_THAT(json, HasSubstr("\"status\": \"optimal\""));
  EXPECT_NEAR(JsonNumber(json, "objective"), 7.0, 1e-7) << json;
  EXPECT_EQ(JsonNumber(json, "repeat"), 3.0);

  // A start speed above vmax: presolve decides it, so there is no SOCP to write; the result is still
  // written and the exit code is the solve's.
  Write("fast.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0},
    "boundary": {"start_velocity": [5, 0, 0]}, "discretization": {"K": 10}})");
  r = RunCli("temporal " + Path("fast.json") + " --export-cbf " + Path("fast.cbf") + " -o " + Path("f.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_THAT(r.output, HasSubstr("--export-cbf: nothing written: no SOCP to build: presolve proves"));
  EXPECT_THAT(ReadTextFile(Path("f.json")), HasSubstr("\"status\": \"infeasible\""));
  EXPECT_FALSE(std::filesystem::exists(Path("fast.cbf")));
}

TEST_F(CliTest, ConicExitCodes) {
  Write("bad.cbf", "VER\n3\nVAR\n2 1\nQ 3\n");
  CliRun r = RunCli("conic " + Path("bad.cbf"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("CBF line 5: VAR cones add up to 3, not 2"));

  // x >= 1 and -x >= 1.
  Write("infeasible.cbf", "VER\n3\nVAR\n1 1\nF 1\nCON\n2 1\nL+ 2\nACOORD\n2\n0 0 1\n1 0 -1\nBCOORD\n2\n0 -1\n1 -1\n");
  r = RunCli("conic " + Path("infeasible.cbf") + " -o " + Path("i.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const std::string json = ReadTextFile(Path("i.json"));
  EXPECT_THAT(json, HasSubstr("\"status\": \"primal_infeasible\""));
  EXPECT_THAT(json, HasSubstr("\"objective\": null"));

  r = RunCli("conic " + Path("missing.cbf"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("missing.cbf"));
}

// The contract line: its time-optimal acceleration jumps by amax where cruise ends, which a
// jerk-input vehicle overshoots (tests/sim has the closed forms); bounding the acceleration change
// per cell (lambda_a = 0.05 m/s^2) removes the overshoot at the price of a longer flight.
TEST_F(CliTest, SimulateReportsTheOvershootAndItsRemedy) {
  const std::string line = std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json";
  CliRun r = RunCli("simulate " + line + " -o " + Path("s.json") + " --states " + Path("s.csv"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("limit exceeded in simulation: |v_x| reaches 1.01"));
  std::string json = ReadTextFile(Path("s.json"));
  EXPECT_THAT(json, HasSubstr("\"feasible\": false"));
  // 1.206 in continuous time; 1.205-1.211 at 1 kHz depending on where a jump falls between updates.
  EXPECT_NEAR(JsonNumber(json, "max_acceleration_ratio"), 1.208, 0.005);
  const std::string csv = ReadTextFile(Path("s.csv"));
  EXPECT_EQ(csv.rfind("t,x,y,z,vx,vy,vz,ax,ay,az,jx,jy,jz,ex,ey,ez\n", 0), 0u);
  // A header, the start of every step and the final state.
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + JsonNumber(json, "steps") + 1);
  EXPECT_EQ(JsonNumber(json, "steps"), 8000);  // 7 s and 1 s of settling at 1 kHz

  Write("lambda.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0, "max_acceleration_change": 0.05},
    "discretization": {"K": 50}})");
  r = RunCli("simulate " + Path("lambda.json") + " -o " + Path("l.json"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  json = ReadTextFile(Path("l.json"));
  EXPECT_THAT(json, HasSubstr("\"feasible\": true"));
  EXPECT_GT(JsonNumber(json, "total_time"), 7.0);

  // With a jerk limit the acceleration is continuous: the vehicle follows within a fraction of a
  // percent, and the verdict allows 1% by default for such problems (reported as "tolerance"); a
  // strict verdict (--tolerance 0) still sees the controller's small lag (exit 1).
  Write("jerk.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0, "max_jerk": 2.0},
    "discretization": {"K": 50}})");
  r = RunCli("simulate " + Path("jerk.json") + " -o " + Path("j.json"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  json = ReadTextFile(Path("j.json"));
  EXPECT_EQ(JsonNumber(json, "tolerance"), 0.01);
  EXPECT_LE(JsonNumber(json, "max_acceleration_ratio"), 1.01);
  EXPECT_LE(JsonNumber(json, "max_velocity_ratio"), 1.01);
  r = RunCli("simulate " + Path("jerk.json") + " --tolerance 0 -o " + Path("j0.json"));
  EXPECT_EQ(JsonNumber(ReadTextFile(Path("j0.json")), "tolerance"), 0.0);
  EXPECT_EQ(r.exit_code, JsonNumber(ReadTextFile(Path("j0.json")), "max_acceleration_ratio") > 1.0 ? 1 : 0);

  // The same line written as 1 kHz samples and flown from them, as another planner's output would be:
  // the same overshoot (the vehicle starts on the first sample, already at amax).
  r = RunCli("temporal " + line + " -o " + Path("t.json") + " --samples " + Path("line.csv") + " --rate 1000");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCli("simulate --samples " + Path("line.csv") + " --max-velocity 2 --max-acceleration 1 -o " + Path("ss.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  json = ReadTextFile(Path("ss.json"));
  EXPECT_NEAR(JsonNumber(json, "max_acceleration_ratio"), 1.208, 0.005);
  EXPECT_GE(JsonNumber(json, "samples"), 7001);  // t = 0, 0.001, ... and the final state at T
  r = RunCli("simulate --samples " + Path("line.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--samples needs --max-velocity and --max-acceleration"));
  r = RunCli("simulate " + line + " --samples " + Path("line.csv") + " --max-velocity 2 --max-acceleration 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("give either PROBLEM.json or --samples"));

  // --max-jerk makes the contract line's own problem jerk-limited: the same vehicle then flies it
  // within 1% (exit 0), the plan being ~0.5 s longer than the paper's 7 s. With --samples it has no
  // problem to limit (exit 2, naming --vehicle-max-jerk), and a negative value is refused.
  r = RunCli("simulate " + line + " --max-jerk 2 -o " + Path("mj.json"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  json = ReadTextFile(Path("mj.json"));
  EXPECT_LE(JsonNumber(json, "max_acceleration_ratio"), 1.01);
  EXPECT_GT(JsonNumber(json, "total_time"), 7.0);
  EXPECT_EQ(JsonNumber(json, "tolerance"), 0.01);
  r = RunCli("simulate --samples " + Path("line.csv") + " --max-velocity 2 --max-acceleration 1 --max-jerk 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--vehicle-max-jerk"));
  r = RunCli("simulate " + line + " --max-jerk -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--max-jerk"));

  r = RunCli("simulate " + line + " --control-rate 50");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--control-rate must be at least 10 x --bandwidth"));
}

// `waypoints` with no flags times the curve as the planner would (certified rows, 2 m/s, 2 m/s^2,
// 10 m/s^3): the dense check of the result holds every limit to the solver's 1e-6, and the
// simulated jerk-input vehicle (an independent model: it integrates its own jerk commands) flies
// it within the product's 1% flight criterion, as result.json's flight block says.
TEST_F(CliTest, WaypointsDefaultsToAFlyableProfile) {
  const std::string waypoints = std::string(TIMEOPT_SOURCE_DIR) + "/examples/waypoints.csv";
  const CliRun r = RunCli("waypoints " + waypoints + " --out-dir " + Path("wd"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("certified constraints"));
  EXPECT_THAT(r.output, HasSubstr("max_jerk 10"));
  const std::string json = ReadTextFile(Path("wd/result.json"));
  EXPECT_LE(JsonNumber(json, "max_velocity_ratio"), 1.0 + 1e-6);
  EXPECT_LE(JsonNumber(json, "max_acceleration_ratio"), 1.0 + 1e-6);
  EXPECT_LE(JsonNumber(json, "max_jerk_ratio"), 1.0 + 1e-6);
  const nlohmann::json flight = nlohmann::json::parse(json)["flight"];
  EXPECT_TRUE(flight["feasible"].get<bool>()) << json;
  EXPECT_EQ(flight["tolerance"].get<double>(), 0.01);
  EXPECT_LE(JsonNumberIn(json, "flight", "max_velocity_ratio"), 1.01);
  EXPECT_LE(JsonNumberIn(json, "flight", "max_acceleration_ratio"), 1.01);
}

// A waypoint that repeats the one before (a CSV with the same point twice, or 1e-9 m apart) is
// dropped: the time is that of the same file without it (the same problem, so the same bits), where
// the vehicle had stopped at the repeat on a curve that looped back around it (3.82 s for 2.21 s).
TEST_F(CliTest, WaypointsDropsACoincidentWaypoint) {
  Write("dup.csv", "x,y,z\n0,0,0\n1,0,0\n1.000000001,0,0\n2,0,0\n");
  Write("plain.csv", "x,y,z\n0,0,0\n1,0,0\n2,0,0\n");
  const CliRun dup = RunCli("waypoints " + Path("dup.csv") + " --json --out-dir " + Path("wdup"), "2>/dev/null");
  const CliRun plain = RunCli("waypoints " + Path("plain.csv") + " --json --out-dir " + Path("wplain"), "2>/dev/null");
  ASSERT_EQ(dup.exit_code, 0) << dup.output;
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const nlohmann::json a = nlohmann::json::parse(dup.output), b = nlohmann::json::parse(plain.output);
  EXPECT_EQ(a["merged_waypoints"].get<int>(), 1);
  EXPECT_EQ(b["merged_waypoints"].get<int>(), 0);
  EXPECT_EQ(a["total_time"].get<double>(), b["total_time"].get<double>());
  EXPECT_EQ(a["piece_durations"].size(), 2u);
  const CliRun text = RunCli("curve " + Path("dup.csv") + " -o " + Path("dup_curve.json"));
  ASSERT_EQ(text.exit_code, 0) << text.output;
  EXPECT_THAT(text.output, HasSubstr("3 waypoints (1 more dropped: each coincided with the one before)"));
  Write("same.csv", "1,2,3\n1,2,3\n");
  const CliRun same = RunCli("waypoints " + Path("same.csv") + " --out-dir " + Path("wsame"));
  EXPECT_EQ(same.exit_code, 2);
  EXPECT_THAT(same.output, HasSubstr("all 2 waypoints coincide"));
}

// `plan --print-config` prints the library's defaults as a planner configuration; the shipped
// examples/planner_config.json is that text (so it cannot drift from the library), reading it back
// gives it again (a round trip through ParsePlannerConfigJson), and flags land in it.
TEST_F(CliTest, PlanPrintsItsCompleteConfiguration) {
  const std::string shipped = std::string(TIMEOPT_SOURCE_DIR) + "/examples/planner_config.json";
  CliRun r = RunCli("plan --print-config");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, ReadTextFile(shipped));
  r = RunCli("plan --config " + shipped + " --print-config");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, ReadTextFile(shipped));
  r = RunCli("plan --config " + shipped + " --max-jerk 0 --robot-radius 0.5 --print-config");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json config = nlohmann::json::parse(r.output);
  EXPECT_FALSE(config["limits"].contains("max_jerk") && !config["limits"]["max_jerk"].is_null()) << r.output;
  EXPECT_EQ(config["robot_radius"].get<double>(), 0.5);
}

// --verbose reports each stage on stderr as it ends, --quiet keeps stdout empty, and waypoints'
// --json prints its result.json (the same bytes as the file) instead of prose.
TEST_F(CliTest, ProgressQuietAndJsonOutput) {
  CliRun r = RunCli("plan -v -q -o " + Path("p.csv") + " --plot " + Path("p.png"), "2>" + Path("stderr.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "");
  const std::string stages = ReadTextFile(Path("stderr.txt"));
  for (const char* stage : {"map: ", "esdf: ", "search: ", "spatial: ", "check: ", "temporal: ", "flight: "}) {
    EXPECT_THAT(stages, HasSubstr(std::string("timeopt plan: ") + stage)) << stages;
  }
  const std::string waypoints = std::string(TIMEOPT_SOURCE_DIR) + "/examples/waypoints.csv";
  r = RunCli("waypoints " + waypoints + " --json --out-dir " + Path("wj"), "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, ReadTextFile(Path("wj/result.json")));
  EXPECT_TRUE(nlohmann::json::parse(r.output)["flight"]["feasible"].get<bool>());
  r = RunCli("waypoints " + waypoints + " -q --out-dir " + Path("wq3"), "2>/dev/null");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.output, "");
}

// Absurd spatial weights are invalid input naming the key (1e100 once made the optimizer return a
// curve that the clearance check sampled into gigabytes and a crash); at the cap the plan runs.
TEST_F(CliTest, AbsurdSpatialWeightsAreRefused) {
  for (const char* key : {"collision_weight", "smoothness_weight", "length_weight"}) {
    Write("w.json", std::string(R"({"spatial": {")") + key + R"(": 1e100}})");
    const CliRun r = RunCli("plan -q --config " + Path("w.json") + " -o " + Path("w.csv"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_THAT(r.output, HasSubstr(std::string("spatial.") + key + ": expected a number in [0, 1e9]"));
  }
  Write("w.json", R"({"spatial": {"collision_weight": 1e9}})");
  const CliRun r = RunCli("plan -q --config " + Path("w.json") + " -o " + Path("w.csv"));
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;  // a plan or a named failure, no crash
}

// `curve --json` and `map info --json` print their figures as JSON, the same as their prose: the
// shipped forest is 20 x 20 x 4 m at 0.1 m (maps/README.md), and a two-point curve is its chord.
TEST_F(CliTest, CurveAndMapInfoPrintJson) {
  Write("two.csv", "x,y,z\n0,0,0\n3,4,0\n");
  CliRun r = RunCli("curve " + Path("two.csv") + " -o " + Path("two.json") + " --json", "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["pieces"].get<int>(), 1);
  EXPECT_NEAR(j["length"].get<double>(), 5.0, 1e-9);
  EXPECT_EQ(j["continuity"].size(), 5u);
  r = RunCli("map info " + std::string(TIMEOPT_SOURCE_DIR) + "/maps/forest_20x20.bt --json", "2>/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["resolution"].get<double>(), 0.1);
  EXPECT_EQ(j["voxels"], nlohmann::json::parse("[200, 200, 40]"));
  EXPECT_NEAR(j["occupied_volume"].get<double>() + j["free_volume"].get<double>() + j["unknown_volume"].get<double>(),
              20.0 * 20.0 * 4.0, 1e-6);
}

// The quadrotor's limits from the command line: waypoints with --max-speed, --max-thrust,
// --min-thrust and --max-tilt (no per-axis limits then) holds them on the dense check (the result
// JSON's ratios, certified rows: within 1e-6); bad values are invalid input naming the option or
// the limit.
TEST_F(CliTest, QuadrotorLimitsOnTheCommandLine) {
  const std::string waypoints = std::string(TIMEOPT_SOURCE_DIR) + "/examples/waypoints.csv";
  CliRun r = RunCli("waypoints " + waypoints +
                    " --max-speed 2.5 --max-thrust 12 --min-thrust 8 --max-tilt 0.4 "
                    "-K 30 --constraint-mode certified --out-dir " +
                    Path("wq"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("max_speed 2.5 m/s"));
  const std::string json = ReadTextFile(Path("wq/result.json"));
  for (const char* key : {"max_speed_ratio", "max_thrust_ratio", "min_thrust_ratio", "max_tilt_ratio"}) {
    EXPECT_LE(JsonNumber(json, key), 1.0 + 1e-6) << key;
    EXPECT_GT(JsonNumber(json, key), 0.5) << key;
  }
  r = RunCli("waypoints " + waypoints + " --max-speed -1 --out-dir " + Path("wq2"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("--max-speed"));
  const std::string line = std::string(TIMEOPT_SOURCE_DIR) + "/examples/line_problem.json";
  r = RunCli("simulate " + line + " --max-tilt 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("limits.max_tilt"));
  // A limit the boundary already breaks: a hover cannot hold min_thrust above g.
  r = RunCli("simulate " + line + " --min-thrust 10.5");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_THAT(r.output, HasSubstr("limits.min_thrust"));
}

// An infeasible start (3 m/s on the contract line, vmax 2): exit 3 with the cause in the result
// JSON; with --relax-boundary exit 0, the start lowered to 2 m/s and the answer for it.
TEST_F(CliTest, InfeasibleStartIsNamedAndRelaxed) {
  Write("fast.json", R"({"curve": {"pieces": [{"x": [0, 10], "y": [0, 0], "z": [0, 0]}]},
    "limits": {"max_velocity": 2.0, "max_acceleration": 1.0},
    "boundary": {"start_velocity": [3, 0, 0]}, "discretization": {"K": 20}})");
  CliRun r = RunCli("temporal " + Path("fast.json") + " -o " + Path("f.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  std::string json = ReadTextFile(Path("f.json"));
  EXPECT_THAT(json, HasSubstr("\"cause\": \"boundary_speed\""));
  r = RunCli("temporal " + Path("fast.json") + " --relax-boundary -o " + Path("r.json"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  json = ReadTextFile(Path("r.json"));
  EXPECT_NEAR(JsonNumberIn(json, "boundary_relaxation", "start_speed"), 2.0, 1e-9);
  EXPECT_NEAR(JsonNumberIn(json, "boundary_relaxation", "start_violation"), 1.0, 1e-9);
  EXPECT_NEAR(JsonNumber(json, "total_time"), 6.0, 1e-6);
}

// A directory where a file is expected: exit 2 naming it (it was exit 1 with
// "basic_filebuf::underflow" for maps and "malformed JSON" for problems).
TEST_F(CliTest, ADirectoryAsInputIsNamed) {
  const std::string dir = Path("");
  for (const std::string& command : {"temporal " + dir, "map info " + dir, "plan --config " + dir}) {
    const CliRun r = RunCli(command);
    EXPECT_EQ(r.exit_code, 2) << command << ": " << r.output;
    EXPECT_THAT(r.output, HasSubstr("is a directory")) << command;
  }
}

}  // namespace
}  // namespace timeopt
