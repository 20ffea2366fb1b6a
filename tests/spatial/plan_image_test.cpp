// WritePlanPng's options: a common speed scale and a title for pictures compared side by side
// (the convergence experiment's top views), and bad values refused.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "../common/fixtures.h"
#include "timeopt/map/esdf.h"
#include "timeopt/map/map_generators.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/trajectory/trajectory.h"
#include "timeopt/viz/plan_plot.h"

namespace timeopt {
namespace {

// True when the file starts with the PNG signature.
bool IsPng(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  in.read(head, 8);
  return in && std::string(head, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}

TEST(PlanImage, ASharedSpeedScaleAndATitleAreDrawnAndBadScalesRefused) {
  ForestOptions forest;
  forest.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(6, 6, 3));
  forest.density = 0.1;
  const Esdf esdf = Esdf::FromMap(OccupancyMap::FromGrid(GenerateForest(forest)));
  // A straight flight across the map, up to 1.4 m/s (b linear on 4 cells).
  const Trajectory trajectory(test_support::Segment(Eigen::Vector3d(0.5, 0.5, 1.5), Eigen::Vector3d(5.5, 5.5, 1.5)),
                              TemporalProfile({{0.0, 0.02, 0.04, 0.02, 0.0}}));
  const std::string dir = testing::TempDir() + "/plan_image_test";
  std::filesystem::create_directories(dir);
  PlanImageOptions options;
  options.speed_scale = 3.0;  // above the trajectory's own top speed: its colours stop short of red
  options.title = "with decoupling";
  options.slice_height = 1.5;
  ASSERT_NO_THROW(WritePlanPng(esdf, trajectory, dir + "/shared.png", options));
  EXPECT_TRUE(IsPng(dir + "/shared.png"));
  ASSERT_NO_THROW(WritePlanPng(esdf, trajectory, dir + "/own.png"));  // NaN: its own top speed
  EXPECT_TRUE(IsPng(dir + "/own.png"));
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity()}) {
    options.speed_scale = bad;
    EXPECT_THROW(WritePlanPng(esdf, trajectory, dir + "/bad.png", options), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace timeopt
