#pragma once

// An occupancy map: an octomap::OcTree behind a small interface (pimpl, so users of this header
// need no OctoMap headers).
//
// Files: OctoMap's binary `.bt` (occupied / free per leaf) and full `.ot` files of type OcTree or
// ColorOcTree (a ColorOcTree loads as occupancy, its colours dropped). The file content is
// validated before OctoMap parses it (header, node stream shape, depth at most 16, node count
// equal to the header's `size`), so a truncated or corrupt file gives an exception, never a
// crash. Saving writes `.bt`.
//
// Voxels never observed are unknown; `UnknownSpace` decides whether they count as free or
// occupied wherever the map is turned into occupancy (IsOccupied, Rasterize, the ESDF).

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "timeopt/map/voxel_grid.h"

namespace timeopt {

enum class UnknownSpace {
  kFree,      // unobserved voxels are free (optimistic: what exploration planners use)
  kOccupied,  // unobserved voxels are obstacles (conservative)
};

// Every enumerator, in declaration order (for FromString, and for listing the choices).
inline constexpr std::array<UnknownSpace, 2> kUnknownSpaces = {
    UnknownSpace::kFree,
    UnknownSpace::kOccupied,
};
const char* ToString(UnknownSpace unknown);  // "free", "occupied"
// The enumerator named `text` (as ToString writes it) into *unknown; false when none is.
bool FromString(const std::string& text, UnknownSpace* unknown);

enum class VoxelState { kUnknown, kFree, kOccupied };

class OccupancyMap {
 public:
  // An empty map (every voxel unknown). Throws std::invalid_argument for a resolution (metres)
  // outside [1e-6, 1e6] (Load refuses such files too).
  explicit OccupancyMap(double resolution, UnknownSpace unknown = UnknownSpace::kFree);
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;
  OccupancyMap(const OccupancyMap&);
  OccupancyMap& operator=(const OccupancyMap&);

  // Reads a `.bt` or `.ot` file (the format is recognized by its first line, not its name).
  // Throws timeopt::FileError when the file cannot be opened, std::invalid_argument naming the
  // problem when its content is not a valid OcTree / ColorOcTree file.
  static OccupancyMap Load(const std::string& path, UnknownSpace unknown = UnknownSpace::kFree);

  // The map with exactly the occupied / free voxels of `grid` (every voxel of the grid becomes
  // known; the tree is pruned). Throws std::invalid_argument for an invalid grid.
  static OccupancyMap FromGrid(const OccupancyGrid& grid, UnknownSpace unknown = UnknownSpace::kFree);

  // Writes the map as an OctoMap binary `.bt` file. Throws timeopt::FileError on failure.
  void Save(const std::string& path) const;

  double resolution() const;
  UnknownSpace unknown_space() const { return unknown_; }
  void set_unknown_space(UnknownSpace unknown) { unknown_ = unknown; }

  // True when no voxel is known.
  bool empty() const;
  // The smallest voxel box holding every known voxel; empty box when the map is empty.
  VoxelBox KnownBox() const;
  // KnownBox() in metres (voxel corners). Empty (default) box when the map is empty.
  Eigen::AlignedBox3d Bounds() const;

  // State of the voxel containing `point` (metres); kUnknown outside OctoMap's key range.
  VoxelState State(const Eigen::Vector3d& point) const;
  // Occupancy of the voxel containing `point`, unknown space resolved by unknown_space().
  bool IsOccupied(const Eigen::Vector3d& point) const;

  // Volumes of the occupied and free known voxels, cubic metres.
  double OccupiedVolume() const;
  double FreeVolume() const;
  // Number of leaves and of all nodes of the tree.
  int64_t NumLeaves() const;
  int64_t NumNodes() const;
  // The OctoMap tree type the file held ("OcTree" or "ColorOcTree"; "OcTree" for built maps).
  const std::string& source_type() const { return source_type_; }

  // Dense occupancy of every voxel in `box`, unknown voxels resolved by unknown_space(). Throws
  // std::invalid_argument for an empty box.
  OccupancyGrid Rasterize(const VoxelBox& box) const;

  // Sets one voxel (containing `point`) to occupied or free. Throws std::invalid_argument when the
  // point is outside OctoMap's key range.
  void SetOccupied(const Eigen::Vector3d& point, bool occupied);

 private:
  struct Impl;
  OccupancyMap(std::unique_ptr<Impl> impl, UnknownSpace unknown, std::string source_type);

  std::unique_ptr<Impl> impl_;
  UnknownSpace unknown_ = UnknownSpace::kFree;
  std::string source_type_ = "OcTree";

  friend class OccupancyMapInternal;
};

// The centres of the occupied voxels of `map` (unknown space resolved by its unknown_space())
// within `radius` metres of the polyline through `points` (checked at points at most half a voxel
// or a quarter of the radius apart), each once, in the order found. Throws std::invalid_argument
// for a radius that is not a finite number >= 0, when more than max_voxels of them are occupied,
// or when more than kMaxVoxelLookups voxels would be looked at (lower the radius; refused at once
// when one point's neighbourhood alone is larger). Looking at 4e6 voxels takes a few seconds and
// about 200 MB; the cap allows a 2 m radius along about 300 m of path at 0.1 m voxels.
inline constexpr size_t kMaxVoxelLookups = 4000000;
std::vector<Eigen::Vector3d> OccupiedVoxelsNear(const OccupancyMap& map, const std::vector<Eigen::Vector3d>& points,
                                                double radius, size_t max_voxels);

}  // namespace timeopt
