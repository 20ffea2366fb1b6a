#include "timeopt/map/occupancy_map.h"

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "timeopt/core/errors.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"

namespace timeopt {
namespace {

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "/map_test_" + name; }

std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary);
  file << bytes;
}

OccupancyGrid SmallBoxes(uint64_t seed) {
  RandomBoxesOptions options;
  options.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-0.8, -0.4, 0.0), Eigen::Vector3d(1.2, 1.0, 0.9));
  options.resolution = 0.1;
  options.count = 6;
  options.min_size = 0.2;
  options.max_size = 0.6;
  options.seed = seed;
  return GenerateRandomBoxes(options);
}

TEST(OccupancyMapTest, GridSaveLoadRoundTripKeepsEveryVoxel) {
  const OccupancyGrid grid = SmallBoxes(2);
  ASSERT_GT(grid.CountOccupied(), 0);
  const OccupancyMap map = OccupancyMap::FromGrid(grid);
  EXPECT_EQ(map.KnownBox().min, grid.box.min);
  EXPECT_EQ(map.KnownBox().size, grid.box.size);
  const std::string path = TempPath("roundtrip.bt");
  map.Save(path);
  const OccupancyMap loaded = OccupancyMap::Load(path);
  EXPECT_DOUBLE_EQ(loaded.resolution(), 0.1);
  EXPECT_EQ(loaded.NumNodes(), map.NumNodes());
  const OccupancyGrid back = loaded.Rasterize(grid.box);
  EXPECT_EQ(back.occupied, grid.occupied);
  // Volumes are sums of voxel cubes: exact up to the rounding of r^3 sums (1e-9 m^3).
  const double voxel = 0.1 * 0.1 * 0.1;
  EXPECT_NEAR(loaded.OccupiedVolume(), grid.CountOccupied() * voxel, 1e-9);
  EXPECT_NEAR(loaded.FreeVolume(), (grid.box.num_voxels() - grid.CountOccupied()) * voxel, 1e-9);
  // Point queries agree with the grid at voxel centres.
  for (int64_t i = 0; i < grid.box.num_voxels(); i += 7) {
    const Eigen::Vector3i local(static_cast<int>(i % grid.box.size.x()),
                                static_cast<int>((i / grid.box.size.x()) % grid.box.size.y()),
                                static_cast<int>(i / (int64_t{grid.box.size.x()} * grid.box.size.y())));
    const Eigen::Vector3i index = local + grid.box.min;
    EXPECT_EQ(loaded.IsOccupied(grid.Centre(index)), grid.At(index));
    EXPECT_EQ(loaded.State(grid.Centre(index)), grid.At(index) ? VoxelState::kOccupied : VoxelState::kFree);
  }
}

TEST(OccupancyMapTest, UnknownSpaceOptionDecidesUnobservedVoxels) {
  OccupancyMap map(0.1);
  map.SetOccupied(Eigen::Vector3d(0.05, 0.05, 0.05), true);
  map.SetOccupied(Eigen::Vector3d(0.15, 0.05, 0.05), false);
  VoxelBox box;
  box.min = Eigen::Vector3i(-1, 0, 0);
  box.size = Eigen::Vector3i(4, 1, 1);
  const Eigen::Vector3d unknown_point(0.35, 0.05, 0.05);
  EXPECT_EQ(map.State(unknown_point), VoxelState::kUnknown);
  EXPECT_FALSE(map.IsOccupied(unknown_point));
  EXPECT_EQ(map.Rasterize(box).occupied, (std::vector<uint8_t>{0, 1, 0, 0}));
  map.set_unknown_space(UnknownSpace::kOccupied);
  EXPECT_TRUE(map.IsOccupied(unknown_point));
  EXPECT_EQ(map.Rasterize(box).occupied, (std::vector<uint8_t>{1, 1, 0, 1}));
  // The ESDF follows the option: with unknown occupied, the free voxel is r/2 from both sides.
  const Esdf esdf(map.Rasterize(box));
  EXPECT_NEAR(esdf.VoxelDistance(Eigen::Vector3i(1, 0, 0)), 0.05, 1e-7);  // float storage
}

TEST(OccupancyMapTest, LoadsFullOtFilesOfOcTreeAndColorOcTree) {
  octomap::OcTree tree(0.05);
  octomap::ColorOcTree color_tree(0.05);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const octomap::point3d p(unit(rng), unit(rng), unit(rng));
    const bool occupied = i % 3 == 0;
    tree.updateNode(p, occupied);
    color_tree.updateNode(p, occupied)->setColor(255, 0, 0);
  }
  const std::string ot = TempPath("tree.ot"), color_ot = TempPath("color.ot");
  ASSERT_TRUE(tree.write(ot));
  ASSERT_TRUE(color_tree.write(color_ot));
  const OccupancyMap a = OccupancyMap::Load(ot);
  const OccupancyMap b = OccupancyMap::Load(color_ot);
  EXPECT_EQ(a.source_type(), "OcTree");
  EXPECT_EQ(b.source_type(), "ColorOcTree");
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const Eigen::Vector3d p(it.getX(), it.getY(), it.getZ());
    const VoxelState expected = tree.isNodeOccupied(*it) ? VoxelState::kOccupied : VoxelState::kFree;
    EXPECT_EQ(a.State(p), expected);
    EXPECT_EQ(b.State(p), expected);
  }
  // The same leaves summed in the same order: equal up to rounding of a sum of ~100 cubes.
  EXPECT_NEAR(a.OccupiedVolume(), b.OccupiedVolume(), 1e-12);
  EXPECT_GT(a.OccupiedVolume(), 0.0);
}

void ExpectInvalid(const std::string& path, const std::string& fragment) {
  try {
    OccupancyMap::Load(path);
    ADD_FAILURE() << "no exception for " << path;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(OccupancyMapTest, CorruptAndTruncatedFilesThrowNeverCrash) {
  EXPECT_THROW(OccupancyMap::Load(TempPath("does_not_exist.bt")), FileError);
  const std::string empty = TempPath("empty_file.bt");
  WriteBytes(empty, "");
  ExpectInvalid(empty, "empty");
  const std::string text = TempPath("text.bt");
  WriteBytes(text, "hello\nworld\n");
  ExpectInvalid(text, "not an OctoMap file");

  const std::string good = TempPath("good.bt");
  OccupancyMap::FromGrid(SmallBoxes(3)).Save(good);
  const std::string bytes = ReadBytes(good);
  const size_t data = bytes.find("data\n") + 5;
  ASSERT_LT(data, bytes.size());

  // Every truncation: a clear error, never a crash.
  const std::string cut = TempPath("cut.bt");
  for (size_t length = 0; length < bytes.size(); ++length) {
    WriteBytes(cut, bytes.substr(0, length));
    EXPECT_THROW(OccupancyMap::Load(cut), std::invalid_argument) << "length " << length;
  }
  ExpectInvalid(cut, "truncated");

  // Header lies about the size.
  std::string wrong_size = bytes;
  const size_t size_pos = wrong_size.find("size ");
  wrong_size.insert(size_pos + 5, "9");
  WriteBytes(cut, wrong_size);
  ExpectInvalid(cut, "header says");
  std::string no_res = bytes;
  no_res.replace(no_res.find("res "), 4, "rez ");
  WriteBytes(cut, no_res);
  ExpectInvalid(cut, "unknown header line");

  // Every data byte set to 0xff (all children inner nodes): deeper than 16 levels.
  std::string deep = bytes;
  for (size_t i = data; i < deep.size(); ++i) deep[i] = static_cast<char>(0xff);
  WriteBytes(cut, deep);
  EXPECT_THROW(OccupancyMap::Load(cut), std::invalid_argument);

  // Random byte corruptions: either a valid tree of the right size or an exception.
  std::mt19937_64 rng(12);
  std::uniform_int_distribution<size_t> position(data, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  int rejected = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string corrupt = bytes;
    for (int k = 0; k < 3; ++k) corrupt[position(rng)] = static_cast<char>(value(rng));
    WriteBytes(cut, corrupt);
    try {
      const OccupancyMap map = OccupancyMap::Load(cut);
      EXPECT_GT(map.NumNodes(), 0);
    } catch (const std::invalid_argument&) {
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 0);

  // A full-format file with an unsupported tree type.
  WriteBytes(cut, "# Octomap OcTree file\nid CountingOcTree\nsize 1\nres 0.1\ndata\n12345");
  ExpectInvalid(cut, "unsupported tree type");
}

TEST(OccupancyMapTest, EmptyMapAndZeroSizeBoxGiveClearErrors) {
  const std::string path = TempPath("empty_map.bt");
  OccupancyMap(0.1).Save(path);
  const OccupancyMap map = OccupancyMap::Load(path);
  EXPECT_TRUE(map.empty());
  EXPECT_TRUE(map.KnownBox().empty());
  EXPECT_EQ(map.OccupiedVolume(), 0.0);
  try {
    Esdf::FromMap(map);
    ADD_FAILURE() << "no exception for an empty map";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
  // No obstacle in the box (every voxel unknown, counted free): its faces bound the field, so a
  // voxel centre k voxels from the nearest face is (k - 1/2) voxels from the obstacles.
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  const Esdf bounded = Esdf::FromMap(map, box);
  const VoxelBox b = bounded.box();
  const Eigen::Vector3i centre = b.min + b.size / 2;
  const int k = std::min((centre - b.min).minCoeff(), (b.end() - Eigen::Vector3i::Ones() - centre).minCoeff());
  EXPECT_NEAR(bounded.VoxelDistance(centre), (k - 0.5) * bounded.resolution(), 1e-6);
  const OccupancyMap boxes = OccupancyMap::FromGrid(SmallBoxes(5));
  try {
    Esdf::FromMap(boxes, Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 1, 0)));
    ADD_FAILURE() << "no exception for a zero-size box";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zero"), std::string::npos) << e.what();
  }
  EXPECT_THROW(OccupancyMap(0.0), std::invalid_argument);
  EXPECT_THROW(map.Rasterize(VoxelBox()), std::invalid_argument);
  EXPECT_THROW(OccupancyMap(0.1).Save(TempPath("no_such_dir/x.bt")), FileError);
}

TEST(OccupancyMapTest, EsdfFromMapEqualsEsdfFromGrid) {
  const OccupancyGrid grid = SmallBoxes(6);
  const OccupancyMap map = OccupancyMap::FromGrid(grid);
  const Esdf from_map = Esdf::FromMap(map);
  const Esdf from_grid(grid);
  ASSERT_EQ(from_map.box().min, from_grid.box().min);
  ASSERT_EQ(from_map.box().size, from_grid.box().size);
  for (int x = grid.box.min.x(); x < grid.box.end().x(); ++x) {
    const Eigen::Vector3i index(x, grid.box.min.y() + 2, grid.box.min.z() + 3);
    EXPECT_EQ(from_map.VoxelDistance(index), from_grid.VoxelDistance(index));
  }
}

// The occupied voxels near a polyline, against brute force over every voxel of a small map: the
// same set (each once), and a radius whose neighbourhood alone passes the lookup cap is refused.
TEST(OccupancyMapTest, OccupiedVoxelsNearAPathMatchBruteForce) {
  OccupancyMap map(0.1);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> cell(0, 29);
  for (int n = 0; n < 400; ++n) {
    map.SetOccupied(Eigen::Vector3d((cell(rng) + 0.5) * 0.1, (cell(rng) + 0.5) * 0.1, (cell(rng) + 0.5) * 0.1), true);
  }
  std::vector<Eigen::Vector3d> path;
  for (int k = 0; k <= 50; ++k) path.emplace_back(0.3 + 0.048 * k, 1.5, 1.0 + 0.02 * k);
  const double radius = 0.6;
  const std::vector<Eigen::Vector3d> found = OccupiedVoxelsNear(map, path, radius, 100000);
  // Brute force: every occupied voxel whose centre is within the radius of the polyline (points
  // 0.05 m apart, finer than the helper's spacing) is found; the helper may add voxels up to its
  // stated allowance (the points' spacing and a voxel's half diagonal) beyond the radius.
  std::set<std::array<long, 3>> found_keys;
  for (const Eigen::Vector3d& c : found) {
    EXPECT_TRUE(map.IsOccupied(c));
    EXPECT_TRUE(
        found_keys
            .insert({std::lround(c.x() / 0.1 - 0.5), std::lround(c.y() / 0.1 - 0.5), std::lround(c.z() / 0.1 - 0.5)})
            .second)
        << "found twice";
  }
  int expected = 0;
  for (int x = 0; x < 30; ++x) {
    for (int y = 0; y < 30; ++y) {
      for (int z = 0; z < 30; ++z) {
        const Eigen::Vector3d c((x + 0.5) * 0.1, (y + 0.5) * 0.1, (z + 0.5) * 0.1);
        if (!map.IsOccupied(c)) continue;
        double nearest = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector3d& p : path) nearest = std::min(nearest, (c - p).norm());
        if (nearest <= radius) {
          ++expected;
          EXPECT_TRUE(found_keys.count({x, y, z})) << x << " " << y << " " << z;
        }
        if (found_keys.count({x, y, z})) {
          EXPECT_LE(nearest, radius + 0.25 * radius + 0.087 + 1e-9);
        }
      }
    }
  }
  EXPECT_GT(expected, 10);
  EXPECT_THROW(OccupiedVoxelsNear(map, path, 1000.0, 100000), std::invalid_argument);
  EXPECT_THROW(OccupiedVoxelsNear(map, path, -1.0, 100000), std::invalid_argument);
  EXPECT_THROW(OccupiedVoxelsNear(map, path, radius, 3), std::invalid_argument);  // more occupied than allowed
}

}  // namespace
}  // namespace timeopt
