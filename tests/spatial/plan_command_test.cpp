// `timeopt plan`: exit codes and messages for bad input, and a successful plan whose CSV and
// summary agree (run on a small generated map written to a temporary directory).

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../common/run_cli.h"

#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt {
namespace {

struct PlanRun {
  int exit_code = -1;
  std::string out;  // stdout only
  std::string err;  // stderr only
};

PlanRun RunPlan(const std::string& args, const std::string& dir) {
  const std::string err_file = dir + "/stderr.txt";
  const testing_support::CliRun cli = testing_support::RunCli("plan " + args, "2>" + err_file);
  PlanRun run;
  run.exit_code = cli.exit_code;
  run.out = cli.output;
  std::ifstream in(err_file);
  std::stringstream s;
  s << in.rdbuf();
  run.err = s.str();
  return run;
}

class PlanCommand : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs each test in its own process, two at a time under -j2.
    dir_ =
        (std::filesystem::temp_directory_path() / ("timeopt_plan_command_test_" + std::to_string(::getpid()))).string();
    std::filesystem::create_directories(dir_);
    ForestOptions forest;
    forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(8, 8, 3));
    forest.density = 0.1;
    forest.seed = 3;
    OccupancyGrid grid = GenerateForest(forest);
    // A solid box around (6, 6): the goal inside it is enclosed.
    for (int z = 0; z < 30; ++z) {
      for (int y = 54; y < 67; ++y) {
        for (int x = 54; x < 67; ++x) {
          const bool shell = z < 2 || z > 27 || y < 56 || y > 64 || x < 56 || x > 64;
          grid.Set(Eigen::Vector3i(x, y, z), shell);
        }
      }
    }
    // Keep the corners free for the start and the goal.
    for (int z = 0; z < 30; ++z) {
      for (int y = 0; y < 12; ++y) {
        for (int x = 0; x < 12; ++x) {
          grid.Set(Eigen::Vector3i(x, y, z), false);
          grid.Set(Eigen::Vector3i(79 - x, 79 - y, z), false);
        }
      }
    }
    OccupancyMap::FromGrid(grid).Save(dir_ + "/map.bt");
  }
  static std::string map() { return dir_ + "/map.bt"; }
  static std::string dir_;
};
std::string PlanCommand::dir_;

TEST_F(PlanCommand, PlansAndWritesTheSamplesAndTheSummary) {
  const std::string csv = dir_ + "/plan.csv", png = dir_ + "/plan.png";
  const PlanRun run =
      RunPlan("--map " + map() + " --start 0.6,0.6,1.5 --goal 7.4,7.4,1.5 --output " + csv + " --plot " + png, dir_);
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  EXPECT_EQ(summary["status"], "success");
  EXPECT_GE(summary["min_clearance"].get<double>(), 0.3);
  for (const char* stage : {"esdf", "search", "spatial", "check", "temporal", "plan_total"}) {
    EXPECT_TRUE(summary["time_ms"].contains(stage)) << stage;
  }
  // The CSV's last time is the trajectory's duration (samples at 100 Hz plus the end point).
  std::ifstream in(csv);
  std::string line, last;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("t,x,y,z,vx,vy,vz", 0), 0u) << line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line, ++rows;
  }
  const double total_time = summary["total_time"].get<double>();
  EXPECT_NEAR(std::stod(last.substr(0, last.find(','))), total_time, 1e-9);
  EXPECT_GE(rows, static_cast<int>(total_time * 100.0));
  EXPECT_TRUE(std::filesystem::exists(png));
}

TEST_F(PlanCommand, BadInputExitsWithTwoAndAOneLineMessage) {
  struct Case {
    std::string args, expected;
  };
  const std::string config = dir_ + "/bad_config.json";
  std::ofstream(config) << R"({"spatial": {"colision_weight": 3}})";
  const std::string negative = dir_ + "/negative_config.json";
  std::ofstream(negative) << R"({"limits": {"max_velocity": -1}})";
  const Case cases[] = {
      {"--map " + map() + " --start 5.5,6,1.5 --goal 7.4,7.4,1.5", "start_in_collision"},
      {"--map " + map() + " --start 0.6,0.6,1.5 --goal 30,1,1.5", "goal_outside_map"},
      {"--map " + map() + " --start 0.6,0.6 --goal 7.4,7.4,1.5", "--start: expected x,y,z"},
      {"--map " + map() + " --start 0.6,0.6,1.5 --goal 7.4,7.4,1.5 --config " + config,
       "config.spatial.colision_weight: unknown key"},
      {"--map " + map() + " --start 0.6,0.6,1.5 --goal 7.4,7.4,1.5 --config " + negative, "max_velocity"},
      {"--map " + dir_ + "/missing.bt --start 0.6,0.6,1.5 --goal 7.4,7.4,1.5", "missing.bt"},
      {"--map " + map() + " --goal 7.4,7.4,1.5", "--start and --goal are required"},
  };
  for (const Case& c : cases) {
    const PlanRun run = RunPlan(c.args, dir_);
    EXPECT_EQ(run.exit_code, 2) << c.args << "\n" << run.out << run.err;
    EXPECT_NE((run.out + run.err).find(c.expected), std::string::npos) << c.args << "\n" << run.err;
    EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  }
}

// The distance field over a region of interest (the start-goal box grown by --region-margin): a
// short plan in one corner of the map gives the same trajectory as the whole-map field, since
// nothing near its path differs (the region's field equals the map's away from its cuts; see
// EsdfTest.RegionOfInterestIsALowerBoundAndExactAwayFromItsCuts), over a fraction of the voxels.
TEST_F(PlanCommand, ARegionOfInterestPlansAsTheWholeMapOverFewerVoxels) {
  const std::string route = "--map " + map() + " --start 0.6,0.6,1.5 --goal 2.5,1.2,1.5";
  const PlanRun region = RunPlan(route + " --region-margin 1.5", dir_);
  const PlanRun whole = RunPlan(route + " --whole-map", dir_);
  ASSERT_EQ(region.exit_code, 0) << region.out << region.err;
  ASSERT_EQ(whole.exit_code, 0) << whole.out << whole.err;
  const nlohmann::json r = nlohmann::json::parse(region.out), w = nlohmann::json::parse(whole.out);
  EXPECT_EQ(r["total_time"].get<double>(), w["total_time"].get<double>());
  EXPECT_EQ(r["path_length"].get<double>(), w["path_length"].get<double>());
  // Region: x in [0, 4], y in [0, 2.7], z in [0, 3] (clipped to the map) against 8 x 8 x 3 m.
  EXPECT_EQ(r["esdf_box"]["voxels"].get<int64_t>(), 40 * 27 * 30);
  EXPECT_EQ(w["esdf_box"]["voxels"].get<int64_t>(), 80 * 80 * 30);
  // The memory budget (9 bytes per voxel at the peak): 1 MiB takes the region (0.28 MiB) and
  // refuses the whole map (1.65 MiB) with exit 2, naming both figures, before allocating.
  const PlanRun budget_region = RunPlan(route + " --region-margin 1.5 --max-memory 1", dir_);
  EXPECT_EQ(budget_region.exit_code, 0) << budget_region.err;
  const PlanRun budget_whole = RunPlan(route + " --whole-map --max-memory 1", dir_);
  EXPECT_EQ(budget_whole.exit_code, 2) << budget_whole.out << budget_whole.err;
  EXPECT_NE(budget_whole.err.find("needs 1.65 MiB at its peak, above the memory budget of 1.00 MiB"), std::string::npos)
      << budget_whole.err;
  // The margin must be positive.
  const PlanRun zero = RunPlan(route + " --region-margin 0", dir_);
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_NE(zero.err.find("--region-margin"), std::string::npos) << zero.err;
}

TEST_F(PlanCommand, EnclosedGoalIsUnreachableWithExitThree) {
  const PlanRun run = RunPlan("--map " + map() + " --start 0.6,0.6,1.5 --goal 6,6,1.5", dir_);
  EXPECT_EQ(run.exit_code, 3) << run.out << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["status"], "unreachable");
}

}  // namespace
}  // namespace timeopt
