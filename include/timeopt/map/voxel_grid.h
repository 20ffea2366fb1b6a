#pragma once

// Dense voxel boxes and occupancy grids, aligned with the OctoMap voxel lattice.
//
// Voxel index i (per axis) is the cube [i * resolution, (i + 1) * resolution): the same lattice
// as an octomap::OcTree of that resolution, whose key is i + 32768. Its centre is
// (i + 0.5) * resolution. Storage is row-major with x fastest: cell (x, y, z) of a box of size
// (nx, ny, nz) is element x + nx * (y + ny * z).

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace timeopt {

// An axis-aligned box of voxels: indices min(a) .. min(a) + size(a) - 1 on axis a.
struct VoxelBox {
  Eigen::Vector3i min = Eigen::Vector3i::Zero();
  Eigen::Vector3i size = Eigen::Vector3i::Zero();

  // Number of voxels (0 when any size is not positive).
  int64_t num_voxels() const;
  bool empty() const { return num_voxels() == 0; }
  // One past the last index on each axis.
  Eigen::Vector3i end() const { return min + size; }
  bool Contains(const Eigen::Vector3i& index) const;
  // The metric box covered by the voxels (corners, not centres).
  Eigen::AlignedBox3d Metric(double resolution) const;

  // The smallest voxel box covering the metric `box` at `resolution` (snapped outwards to the
  // lattice; a corner within 1e-9 voxel of a lattice plane counts as on it). Throws
  // std::invalid_argument when the box is empty, has zero extent on an axis or a
  // non-finite corner, or when the resolution is not positive, or when an index leaves the
  // OctoMap key range [-32768, 32767].
  static VoxelBox Covering(const Eigen::AlignedBox3d& box, double resolution);
};

// Largest dense grid: 1 byte of occupancy and 4 of distance per voxel, so 2e8 voxels are ~1 GB
// (plus the transform's per-plane scratch). The shared geb079 map is 3.6e6; a 40-byte .bt whose
// root is a leaf spans 2.8e14 and used to end as a bare bad_alloc.
inline constexpr int64_t kMaxGridVoxels = 200'000'000;

// Occupancy of every voxel in a box; values are exactly 0 (free) or 1 (occupied).
struct OccupancyGrid {
  double resolution = 0.0;  // edge length of a voxel, metres
  VoxelBox box;
  std::vector<uint8_t> occupied;  // box.num_voxels() values, row-major, x fastest

  // A grid of `box` at `resolution` with every voxel set to `value`. Throws
  // std::invalid_argument for an empty box, a non-positive resolution, or a box of more than 2e8
  // voxels (~1 GB with its distance field), before allocating.
  OccupancyGrid(double resolution, const VoxelBox& box, bool value = false);
  OccupancyGrid() = default;

  int64_t Linear(const Eigen::Vector3i& local) const {
    return local.x() +
           static_cast<int64_t>(box.size.x()) * (local.y() + static_cast<int64_t>(box.size.y()) * local.z());
  }
  // Occupancy of the voxel with world index `index` (must be inside the box).
  bool At(const Eigen::Vector3i& index) const { return occupied[Linear(index - box.min)] != 0; }
  void Set(const Eigen::Vector3i& index, bool value) { occupied[Linear(index - box.min)] = value ? 1 : 0; }
  // Centre of the voxel with world index `index`, metres.
  Eigen::Vector3d Centre(const Eigen::Vector3i& index) const {
    return (index.cast<double>().array() + 0.5).matrix() * resolution;
  }
  int64_t CountOccupied() const;

  // Throws std::invalid_argument when the sizes disagree, the resolution is not positive or a
  // value is neither 0 nor 1.
  void Validate() const;
};

}  // namespace timeopt
