#include "timeopt/map/voxel_grid.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace timeopt {
namespace {

// OctoMap keys are 16 bit with the origin at 32768, so world voxel indices span this range.
constexpr int kMinIndex = -32768;
constexpr int kMaxIndex = 32767;

}  // namespace

int64_t VoxelBox::num_voxels() const {
  if ((size.array() <= 0).any()) return 0;
  return static_cast<int64_t>(size.x()) * size.y() * size.z();
}

bool VoxelBox::Contains(const Eigen::Vector3i& index) const {
  return (index.array() >= min.array()).all() && (index.array() < end().array()).all();
}

Eigen::AlignedBox3d VoxelBox::Metric(double resolution) const {
  return Eigen::AlignedBox3d(min.cast<double>() * resolution, end().cast<double>() * resolution);
}

VoxelBox VoxelBox::Covering(const Eigen::AlignedBox3d& box, double resolution) {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("resolution must be positive and finite");
  }
  if (!box.min().allFinite() || !box.max().allFinite()) {
    throw std::invalid_argument("box corners must be finite");
  }
  if ((box.max().array() <= box.min().array()).any()) {
    std::ostringstream message;
    message << "box has zero or negative size: min (" << box.min().transpose() << "), max (" << box.max().transpose()
            << "); every axis needs max > min";
    throw std::invalid_argument(message.str());
  }
  // A corner within kSnap voxels of a lattice plane counts as on it, so that e.g. 0.3 / 0.1
  // (= 2.9999999999999996) does not add a voxel.
  constexpr double kSnap = 1e-9;
  const Eigen::Vector3d lo = ((box.min() / resolution).array() + kSnap).floor();
  const Eigen::Vector3d hi = ((box.max() / resolution).array() - kSnap).ceil();
  if ((lo.array() < kMinIndex).any() || (hi.array() - 1 > kMaxIndex).any()) {
    throw std::invalid_argument("box leaves the OctoMap key range (|coordinate| <= 32768 voxels)");
  }
  VoxelBox result;
  result.min = lo.cast<int>();
  result.size = (hi - lo).cast<int>();
  return result;
}

OccupancyGrid::OccupancyGrid(double resolution_in, const VoxelBox& box_in, bool value)
    : resolution(resolution_in), box(box_in) {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("grid resolution must be positive and finite");
  }
  if (box.empty()) throw std::invalid_argument("grid box is empty (a size is not positive)");
  if (box.num_voxels() > kMaxGridVoxels) {
    std::ostringstream message;
    message << "grid of " << box.size.x() << " x " << box.size.y() << " x " << box.size.z() << " = " << box.num_voxels()
            << " voxels is above the " << kMaxGridVoxels
            << " supported (~5 bytes each with its distance field); use a smaller region or a coarser "
               "resolution";
    throw std::invalid_argument(message.str());
  }
  occupied.assign(static_cast<size_t>(box.num_voxels()), value ? 1 : 0);
}

int64_t OccupancyGrid::CountOccupied() const {
  // Sums in 32-bit chunks (vectorizable) of at most 2^24 values each.
  int64_t count = 0;
  const size_t n = occupied.size();
  for (size_t begin = 0; begin < n; begin += (size_t{1} << 24)) {
    const size_t end = std::min(n, begin + (size_t{1} << 24));
    uint32_t chunk = 0;
    for (size_t i = begin; i < end; ++i) chunk += occupied[i];
    count += chunk;
  }
  return count;
}

void OccupancyGrid::Validate() const {
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    throw std::invalid_argument("grid resolution must be positive and finite");
  }
  if (box.empty()) throw std::invalid_argument("grid box is empty (a size is not positive)");
  if (static_cast<int64_t>(occupied.size()) != box.num_voxels()) {
    std::ostringstream message;
    message << "grid holds " << occupied.size() << " values, expected " << box.num_voxels();
    throw std::invalid_argument(message.str());
  }
  uint8_t high_bits = 0;  // an OR over all values vectorizes; a throwing loop would not
  for (uint8_t v : occupied) high_bits |= static_cast<uint8_t>(v & 0xFEu);
  if (high_bits != 0) throw std::invalid_argument("grid occupancy values must be 0 or 1");
}

}  // namespace timeopt
