// `timeopt map info|generate|slice` through the real executable, and the committed default maps.

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../common/run_cli.h"

#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt {
namespace {

using ::testing::HasSubstr;

using testing_support::CliRun;
using testing_support::RunCli;

class MapCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(TIMEOPT_CLI_PATH)) {
      GTEST_SKIP() << "skipped: the timeopt executable is not built (" << TIMEOPT_CLI_PATH << ")";
    }
    // One folder per process: ctest runs each test in its own process, two at a time under -j2.
    dir_ = std::filesystem::path(::testing::TempDir()) / ("map_command_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(MapCommandTest, GenerateInfoAndSliceASharpTurn) {
  const std::string map = Path("turn.bt");
  const CliRun generate = RunCli("map generate sharp-turn --resolution 0.2 --leg-length 4 -o " + map);
  ASSERT_EQ(generate.exit_code, 0) << generate.output;
  EXPECT_THAT(generate.output, HasSubstr("written: " + map));

  // The file holds what the library generates for the same options.
  SharpTurnOptions options;
  options.resolution = 0.2;
  options.leg_length = 4;
  const OccupancyGrid expected = GenerateSharpTurn(options);
  const OccupancyMap loaded = OccupancyMap::Load(map);
  EXPECT_EQ(loaded.Rasterize(expected.box).occupied, expected.occupied);

  const CliRun info = RunCli("map info " + map);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_THAT(info.output, HasSubstr("resolution: 0.2 m"));
  EXPECT_THAT(info.output, HasSubstr("occupied volume:"));
  EXPECT_THAT(info.output, HasSubstr("bounds: [0, "));

  const std::string png = Path("turn.png");
  const CliRun slice = RunCli("map slice " + map + " --z 1.5 -o " + png);
  ASSERT_EQ(slice.exit_code, 0) << slice.output;
  std::ifstream file(png, std::ios::binary);
  std::array<char, 8> signature{};
  file.read(signature.data(), signature.size());
  EXPECT_EQ(std::string(signature.data() + 1, 3), "PNG");
}

TEST_F(MapCommandTest, GenerateForestAndBoxesWithBounds) {
  const CliRun forest =
      RunCli("map generate forest --bounds 0 0 0 4 3 1 --density 0.5 --seed 3 -o " + Path("forest.bt"));
  ASSERT_EQ(forest.exit_code, 0) << forest.output;
  EXPECT_THAT(forest.output, HasSubstr("voxels: 12000"));  // 40 x 30 x 10
  const CliRun boxes = RunCli("map generate boxes --bounds 0 0 0 4 3 1 --count 3 --ground -o " + Path("boxes.bt"));
  ASSERT_EQ(boxes.exit_code, 0) << boxes.output;
  EXPECT_FALSE(OccupancyMap::Load(Path("boxes.bt")).empty());
}

TEST_F(MapCommandTest, InvalidInputExitsWithTwoAndOneLine) {
  const std::string corrupt = Path("corrupt.bt");
  std::ofstream(corrupt) << "# Octomap OcTree binary file\nid OcTree\nsize 5\nres 0.1\ndata\n\x03";
  for (const std::string& args :
       {"map info " + corrupt, "map info " + Path("missing.bt"), "map slice " + corrupt + " --z 1 -o " + Path("x.png"),
        "map generate forest --bounds 0 0 0 4 4 0 -o " + Path("flat.bt"),
        "map generate forest --radius-min 0.5 --radius-max 0.1 -o " + Path("r.bt"),
        "map generate boxes -o " + Path("wrong_extension.ot")}) {
    const CliRun run = RunCli(args);
    EXPECT_EQ(run.exit_code, 2) << args << "\n" << run.output;
    // One line: a single trailing newline.
    EXPECT_EQ(std::count(run.output.begin(), run.output.end(), '\n'), 1) << run.output;
  }
  // A 40-byte map whose root is a leaf spans the whole key range (2.8e14 voxels): its slice is
  // refused by the grid's size cap, naming it, not by running out of memory.
  const std::string leaf = Path("leaf_root.bt");
  std::ofstream(leaf, std::ios::binary) << "# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\ndata\n"
                                        << std::string(2, '\0');
  const CliRun leaf_slice = RunCli("map slice " + leaf + " --z 0 -o " + Path("leaf.png"));
  EXPECT_EQ(leaf_slice.exit_code, 2) << leaf_slice.output;
  EXPECT_THAT(leaf_slice.output, HasSubstr("voxels is above the 200000000 supported"));
  // A slice height outside the map.
  ASSERT_EQ(RunCli("map generate sharp-turn -o " + Path("t.bt")).exit_code, 0);
  const CliRun high = RunCli("map slice " + Path("t.bt") + " --z 50 -o " + Path("t.png"));
  EXPECT_EQ(high.exit_code, 2);
  EXPECT_THAT(high.output, HasSubstr("outside the map's z range"));
}

// The committed default maps load, have the bounds maps/README.md states, and give an ESDF.
TEST(DefaultMapsTest, CommittedMapsLoadWithTheDocumentedBounds) {
  struct Expected {
    const char* file;
    Eigen::Vector3d max;
  };
  for (const Expected& e : {Expected{"forest_20x20.bt", {20, 20, 4}}, Expected{"sharp_turn.bt", {10.2, 5, 3}},
                            Expected{"boxes_20x20.bt", {20, 20, 4}}}) {
    const std::string path = std::string(TIMEOPT_SOURCE_DIR) + "/maps/" + e.file;
    const OccupancyMap map = OccupancyMap::Load(path);
    EXPECT_DOUBLE_EQ(map.resolution(), 0.1) << e.file;
    // Bounds are voxel corners, multiples of 0.1 m: equal up to the rounding of k * 0.1.
    EXPECT_TRUE(map.Bounds().min().isZero(1e-9)) << e.file;
    EXPECT_TRUE(map.Bounds().max().isApprox(e.max, 1e-9)) << e.file;
    const Esdf esdf = Esdf::FromMap(map);
    EXPECT_EQ(esdf.box().num_voxels(), map.KnownBox().num_voxels());
  }
}

}  // namespace
}  // namespace timeopt
