#pragma once

// A dense signed Euclidean distance field (ESDF) over a box of voxels.
//
// Values at voxel centres (exact, no approximation beyond the voxel model):
//   free voxel c:      d(c) =  min_{o occupied} |c - o| - r/2
//   occupied voxel c:  d(c) = -(min_{f free}   |c - f| - r/2)
// with r the resolution and the minima over voxel centres inside the box. The half voxel puts the
// zero level set on the faces between free and occupied voxels: a free voxel next to an obstacle
// has +r/2, the obstacle voxel -r/2, and the field is exactly the distance to a planar wall of
// voxels measured perpendicular to it. Each minimum is computed by the exact, linear-time
// separable squared distance transform of Felzenszwalb and Huttenlocher ("Distance Transforms of
// Sampled Functions", Theory of Computing 8, 2012): one 1-D lower-envelope pass per axis, once
// with the occupied voxels as sites and once with the free ones.
//
// Between voxel centres the field is the trilinear interpolant of the centre values; the gradient
// is the analytic gradient of that interpolant: the value is continuous everywhere, the gradient
// is smooth inside each cell of eight centres and may jump across cell faces. Values are stored
// as float (relative rounding 6e-8, i.e. below a micrometre for distances under 10 m).
//
// Build cost: linear in the voxels (two transforms of three passes each), 9 bytes per voxel at
// the peak (occupancy, a 32-bit work array, the field).
//
// Outside the interpolation domain D = [first centre, last centre] (the box shrunk by half a
// voxel on every side) the query point p is clamped to q = clamp(p, D) and
//   d(p) = d(q) + |p - q|,   grad d(p) = (components of grad d(q) along axes where p is inside D)
//                                        + (p - q) / |p - q|,
// i.e. everything outside the box is treated as free space without new obstacles. The function
// stays continuous and finite everywhere; Contains() tells whether a point is inside D. A
// non-finite coordinate gives a non-finite result (never an out-of-range read).
//
// Storage: one float per voxel, row-major with x fastest (VoxelBox layout). Queries take no lock
// and do not allocate; an Esdf is immutable after construction and safe to query from threads.

#include <cstddef>
#include <cstdint>
#include <new>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "timeopt/map/distance_field.h"
#include "timeopt/map/occupancy_map.h"
#include "timeopt/map/voxel_grid.h"

namespace timeopt {
namespace internal {

// Storage for large dense arrays: blocks of 2 MiB and more are 2 MiB aligned and, on Linux,
// advised to use transparent huge pages (a 32 MB field otherwise costs 8000 page faults, about a
// tenth of the build time). Smaller blocks use operator new.
void* AllocateLarge(std::size_t bytes);
void DeallocateLarge(void* pointer, std::size_t bytes) noexcept;

template <typename T>
struct LargeAllocator {
  using value_type = T;
  LargeAllocator() = default;
  template <typename U>
  LargeAllocator(const LargeAllocator<U>&) {}  // NOLINT(runtime/explicit)
  T* allocate(std::size_t n) { return static_cast<T*>(AllocateLarge(n * sizeof(T))); }
  // Value-less construction default-initializes (no zero fill of arrays that are overwritten).
  template <typename U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  void deallocate(T* p, std::size_t n) noexcept { DeallocateLarge(p, n * sizeof(T)); }
  template <typename U>
  bool operator==(const LargeAllocator<U>&) const {
    return true;
  }
  template <typename U>
  bool operator!=(const LargeAllocator<U>&) const {
    return false;
  }
};

}  // namespace internal

class Esdf final : public DistanceField {
 public:
  // Builds the field from a dense grid. Throws std::invalid_argument for an invalid grid, and
  // when the grid has no occupied voxel (the distance would be unbounded) or no free voxel.
  explicit Esdf(const OccupancyGrid& grid);

  // Peak memory of building the field over `voxels`: kPeakBytesPerVoxel per voxel (the
  // rasterized occupancy, a 32-bit work array and the float field).
  static constexpr int64_t kPeakBytesPerVoxel = 9;
  static int64_t PeakBytes(const VoxelBox& voxels) { return voxels.num_voxels() * kPeakBytesPerVoxel; }

  // Builds the field over `box` (metres, snapped outwards to the voxel lattice) or, without a
  // box, over the map's known box; unknown voxels count as the map's unknown_space() says. A box
  // without an occupied voxel gets occupied faces: its walls bound the distance (otherwise
  // unbounded), so an obstacle-free map keeps a vehicle inside the mapped volume.
  // max_bytes > 0 is a memory budget: a field whose PeakBytes exceed it is refused before any
  // allocation (std::invalid_argument with both figures). Throws std::invalid_argument for an
  // empty map without a box, a box of zero size, and the cases of the grid constructor.
  static Esdf FromMap(const OccupancyMap& map, const std::optional<Eigen::AlignedBox3d>& box = std::nullopt,
                      int64_t max_bytes = 0);

  // The field over a region of interest of a large map: `region` (metres, snapped outwards to the
  // lattice) clipped to the map's known box. Where the region cuts the map, its outermost voxel
  // layer counts as occupied, so the field never exceeds the full map's field (obstacles beyond a
  // cut are at least as far as the cut) and equals it wherever the nearest obstacle is closer than
  // the cut; a planner that keeps its clearance in this field keeps it in the whole map. A region
  // far larger than the map is the map. Without an occupied voxel, as FromMap. Memory
  // and time scale with the region, not the map. Throws std::invalid_argument for an empty map,
  // a region that does not overlap the known box or has zero size, and the cases of the grid
  // constructor; max_bytes as for FromMap.
  static Esdf FromMapRegion(const OccupancyMap& map, const Eigen::AlignedBox3d& region, int64_t max_bytes = 0);

  double Distance(const Eigen::Vector3d& point) const override;
  double DistanceAndGradient(const Eigen::Vector3d& point, Eigen::Vector3d* gradient) const override;

  // Batched queries (see DistanceField::Distances), inlined per point: no virtual call inside.
  void Distances(const Eigen::Matrix3Xd& points, Eigen::VectorXd* distances,
                 Eigen::Matrix3Xd* gradients) const override;

  // The value stored at the centre of voxel `index` (world voxel index, inside box()).
  double VoxelDistance(const Eigen::Vector3i& index) const;

  // True when `point` is inside the interpolation domain (no outside extension applied).
  bool Contains(const Eigen::Vector3d& point) const;

  double resolution() const { return resolution_; }
  const VoxelBox& box() const { return box_; }
  // The interpolation domain D (first to last voxel centre), metres.
  Eigen::AlignedBox3d domain() const;
  // Bytes held by the distance values.
  int64_t memory_bytes() const { return static_cast<int64_t>(values_.size() * sizeof(float)); }

 private:
  template <bool kWithGradient>
  double Evaluate(const Eigen::Vector3d& point, Eigen::Vector3d* gradient) const;

  double resolution_ = 0.0;
  double inverse_resolution_ = 0.0;
  VoxelBox box_;
  Eigen::Vector3d first_centre_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_centre_ = Eigen::Vector3d::Zero();
  Eigen::Vector3i max_cell_ = Eigen::Vector3i::Zero();                        // largest lower cell corner per axis
  Eigen::Matrix<int64_t, 3, 1> step_ = Eigen::Matrix<int64_t, 3, 1>::Zero();  // 0 on flat axes
  std::vector<float, internal::LargeAllocator<float>> values_;
};

}  // namespace timeopt
