// The ESDF against OctoMap's own distance map, DynamicEDTOctomap (libdynamicedt3d), on a real
// scan: ../shared/maps/geb079.bt (skipped when that folder is absent).

#include <dynamicEDT3D/dynamicEDTOctomap.h>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "timeopt/map/esdf.h"
#include "timeopt/map/occupancy_map.h"

namespace timeopt {
namespace {

TEST(DynamicEdtComparisonTest, Geb079AgreesWithinOneVoxel) {
  const std::string path = std::string(TIMEOPT_SHARED_DIR) + "/maps/geb079.bt";
  if (!std::filesystem::exists(path)) {
    GTEST_SKIP() << "skipped: " << path << " not found (the shared maps folder beside the repository is absent)";
  }
  const OccupancyMap map = OccupancyMap::Load(path, UnknownSpace::kFree);
  const Esdf esdf = Esdf::FromMap(map);
  const double r = esdf.resolution();

  octomap::OcTree tree(path);
  const Eigen::AlignedBox3d domain = esdf.domain();  // first and last voxel centres
  const octomap::point3d lo(static_cast<float>(domain.min().x()), static_cast<float>(domain.min().y()),
                            static_cast<float>(domain.min().z()));
  const octomap::point3d hi(static_cast<float>(domain.max().x()), static_cast<float>(domain.max().y()),
                            static_cast<float>(domain.max().z()));
  // A maximum distance beyond the box diagonal: DynamicEDTOctomap then computes the whole
  // unbounded field, like ours. Unknown counts as free on both sides.
  const float max_distance = static_cast<float>((domain.max() - domain.min()).norm() + 1.0);
  DynamicEDTOctomap edt(max_distance, &tree, lo, hi, false);
  edt.update(true);

  const VoxelBox box = esdf.box();
  int64_t free_voxels = 0, occupied_voxels = 0, exact = 0;
  double worst = 0.0;
  for (int z = box.min.z(); z < box.end().z(); ++z) {
    for (int y = box.min.y(); y < box.end().y(); ++y) {
      for (int x = box.min.x(); x < box.end().x(); ++x) {
        const Eigen::Vector3i index(x, y, z);
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(x + 32768),
                                     static_cast<octomap::key_type>(y + 32768),
                                     static_cast<octomap::key_type>(z + 32768));
        const double theirs = edt.getDistance(key);  // centre to nearest occupied centre, m
        ASSERT_GE(theirs, 0.0) << "voxel outside DynamicEDTOctomap's box: " << index.transpose();
        const double ours = esdf.VoxelDistance(index);
        if (ours < 0.0) {
          ++occupied_voxels;
          // Both must call this voxel an obstacle.
          ASSERT_EQ(theirs, 0.0) << index.transpose();
          continue;
        }
        ++free_voxels;
        // Ours is measured to the obstacle's face (centre distance minus r/2).
        const double difference = std::abs(ours + 0.5 * r - theirs);
        worst = std::max(worst, difference);
        // Float storage on both sides: a few 1e-6 m. Beyond that, DynamicEDT3D's propagation is
        // not exact everywhere; the issue asks for agreement within one voxel.
        if (difference < 1e-5) ++exact;
        ASSERT_LE(difference, r) << "voxel " << index.transpose() << ": ours " << ours << " + r/2, DynamicEDTOctomap "
                                 << theirs;
      }
    }
  }
  EXPECT_GT(occupied_voxels, 0);
  EXPECT_GT(free_voxels, 0);
  RecordProperty("free_voxels", std::to_string(free_voxels));
  RecordProperty("exact_fraction", std::to_string(static_cast<double>(exact) / free_voxels));
  RecordProperty("worst_difference_m", std::to_string(worst));
  // Beyond the one-voxel bound: all but a handful of voxels agree to float precision
  // (measured: 99.9998%, worst 0.0031 m at r = 0.08 m); a tenth of a voxel and 99.9% leave room
  // for DynamicEDT3D's inexact propagation while catching any systematic offset or wrong sign.
  EXPECT_GT(static_cast<double>(exact) / free_voxels, 0.999);
  EXPECT_LT(worst, 0.1 * r);
  std::printf("geb079: %lld free voxels, %.4f%% equal to DynamicEDTOctomap, worst %.4f m\n",
              static_cast<long long>(free_voxels), 100.0 * exact / free_voxels, worst);
}

}  // namespace
}  // namespace timeopt
