#include "timeopt/map/map_generators.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace timeopt {
namespace {

void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument(message);
}

void ValidateBoundsAndResolution(const Eigen::AlignedBox3d& bounds, double resolution) {
  Require(std::isfinite(resolution) && resolution > 0.0, "resolution must be positive");
  Require(bounds.min().allFinite() && bounds.max().allFinite(), "bounds must be finite");
  Require((bounds.max().array() > bounds.min().array()).all(), "bounds must have max > min on every axis");
}

constexpr double kPi = 3.14159265358979323846;

// Distance from p to the segment [a, b] in the plane.
double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

// Calls visit(index, centre) for every voxel of the grid (world index, centre in metres).
template <typename Visit>
void ForEachVoxel(const OccupancyGrid& grid, Visit&& visit) {
  const Eigen::Vector3i end = grid.box.end();
  for (int z = grid.box.min.z(); z < end.z(); ++z) {
    for (int y = grid.box.min.y(); y < end.y(); ++y) {
      for (int x = grid.box.min.x(); x < end.x(); ++x) {
        const Eigen::Vector3i index(x, y, z);
        visit(index, grid.Centre(index));
      }
    }
  }
}

}  // namespace

// The most trees or boxes a generator places (see ForestOptions::Validate).
constexpr double kMaxGeneratedObstacles = 1e6;

void ForestOptions::Validate() const {
  ValidateBoundsAndResolution(bounds, resolution);
  Require(std::isfinite(density) && density >= 0.0, "forest density must be >= 0 (trees per m^2)");
  Require(std::isfinite(min_radius) && min_radius > 0.0, "forest min_radius must be positive");
  Require(std::isfinite(max_radius) && max_radius >= min_radius, "forest max_radius must be >= min_radius");
  // Each tree costs a pass over its voxel columns: a cap keeps absurd densities from running for
  // hours (1e6 trees: minutes at most; a 10 x 10 m forest at 1 tree/m^2 has 100).
  const Eigen::Vector3d size = bounds.sizes();
  Require(density * size.x() * size.y() <= kMaxGeneratedObstacles,
          "forest density gives more than 1e6 trees in the bounds");
}

void SharpTurnOptions::Validate() const {
  Require(std::isfinite(resolution) && resolution > 0.0, "resolution must be positive");
  Require(std::isfinite(corridor_width) && corridor_width >= 2 * resolution,
          "sharp-turn corridor_width must be at least two voxels");
  Require(std::isfinite(leg_length) && leg_length > 0.0, "sharp-turn leg_length must be positive");
  Require(std::isfinite(turn_angle_deg) && turn_angle_deg > 0.0 && turn_angle_deg <= 180.0,
          "sharp-turn turn_angle_deg must be in (0, 180]");
  Require(std::isfinite(height) && height >= resolution, "sharp-turn height must be at least one voxel");
  Require(std::isfinite(wall) && wall >= resolution, "sharp-turn wall must be at least one voxel");
}

Eigen::Matrix<double, 2, 3> SharpTurnOptions::Polyline() const {
  const double angle = turn_angle_deg * kPi / 180.0;
  Eigen::Matrix<double, 2, 3> points;
  points.col(0) = Eigen::Vector2d::Zero();
  points.col(1) = Eigen::Vector2d(leg_length, 0.0);
  points.col(2) = points.col(1) + leg_length * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  // Shift so that the solid margin starts at x = y = 0.
  const double margin = 0.5 * corridor_width + wall;
  const Eigen::Vector2d shift = Eigen::Vector2d::Constant(margin) - points.rowwise().minCoeff();
  points.colwise() += shift;
  return points;
}

Eigen::AlignedBox3d SharpTurnOptions::Bounds() const {
  const Eigen::Matrix<double, 2, 3> points = Polyline();
  const double margin = 0.5 * corridor_width + wall;
  const Eigen::Vector2d hi = points.rowwise().maxCoeff().array() + margin;
  return Eigen::AlignedBox3d(Eigen::Vector3d::Zero(), Eigen::Vector3d(hi.x(), hi.y(), height + 2.0 * wall));
}

void RandomBoxesOptions::Validate() const {
  ValidateBoundsAndResolution(bounds, resolution);
  Require(count >= 0 && count <= kMaxGeneratedObstacles, "boxes count must be in [0, 1e6]");
  Require(std::isfinite(min_size) && min_size > 0.0, "boxes min_size must be positive");
  Require(std::isfinite(max_size) && max_size >= min_size, "boxes max_size must be >= min_size");
}

OccupancyGrid GenerateForest(const ForestOptions& options) {
  options.Validate();
  OccupancyGrid grid(options.resolution, VoxelBox::Covering(options.bounds, options.resolution));
  std::mt19937_64 rng(options.seed);
  const Eigen::Vector3d lo = options.bounds.min(), hi = options.bounds.max();
  std::uniform_real_distribution<double> ux(lo.x(), hi.x()), uy(lo.y(), hi.y());
  std::uniform_real_distribution<double> ur(options.min_radius, options.max_radius);
  const double area = (hi.x() - lo.x()) * (hi.y() - lo.y());
  const auto trees = static_cast<int64_t>(std::llround(options.density * area));

  // Trees are vertical: mark one z layer, then copy it to every layer.
  const int nx = grid.box.size.x(), ny = grid.box.size.y(), nz = grid.box.size.z();
  const int64_t plane = static_cast<int64_t>(nx) * ny;
  const double r = options.resolution;
  for (int64_t t = 0; t < trees; ++t) {
    const Eigen::Vector2d centre(ux(rng), uy(rng));
    const double radius = ur(rng);
    const int x0 = std::max(grid.box.min.x(), static_cast<int>(std::floor((centre.x() - radius) / r)));
    const int x1 = std::min(grid.box.end().x() - 1, static_cast<int>(std::floor((centre.x() + radius) / r)));
    const int y0 = std::max(grid.box.min.y(), static_cast<int>(std::floor((centre.y() - radius) / r)));
    const int y1 = std::min(grid.box.end().y() - 1, static_cast<int>(std::floor((centre.y() + radius) / r)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d c((x + 0.5) * r, (y + 0.5) * r);
        if ((c - centre).squaredNorm() <= radius * radius) {
          grid.occupied[static_cast<size_t>((x - grid.box.min.x()) +
                                            static_cast<int64_t>(nx) * (y - grid.box.min.y()))] = 1;
        }
      }
    }
  }
  for (int z = 1; z < nz; ++z) {
    std::copy_n(grid.occupied.begin(), plane, grid.occupied.begin() + z * plane);
  }
  return grid;
}

OccupancyGrid GenerateSharpTurn(const SharpTurnOptions& options) {
  options.Validate();
  const Eigen::AlignedBox3d bounds = options.Bounds();
  OccupancyGrid grid(options.resolution, VoxelBox::Covering(bounds, options.resolution), true);
  const Eigen::Matrix<double, 2, 3> line = options.Polyline();
  const double half_width = 0.5 * options.corridor_width;
  const double floor = options.wall, ceiling = options.wall + options.height;
  ForEachVoxel(grid, [&](const Eigen::Vector3i& index, const Eigen::Vector3d& centre) {
    if (centre.z() < floor || centre.z() > ceiling) return;
    const Eigen::Vector2d p = centre.head<2>();
    const double distance =
        std::min(SegmentDistance(p, line.col(0), line.col(1)), SegmentDistance(p, line.col(1), line.col(2)));
    if (distance <= half_width) grid.Set(index, false);
  });
  return grid;
}

OccupancyGrid GenerateRandomBoxes(const RandomBoxesOptions& options) {
  options.Validate();
  OccupancyGrid grid(options.resolution, VoxelBox::Covering(options.bounds, options.resolution));
  std::mt19937_64 rng(options.seed);
  const Eigen::Vector3d lo = options.bounds.min(), hi = options.bounds.max();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> size(options.min_size, options.max_size);
  const double r = options.resolution;
  for (int b = 0; b < options.count; ++b) {
    Eigen::Vector3d centre, extent;
    for (int a = 0; a < 3; ++a) {
      centre(a) = lo(a) + unit(rng) * (hi(a) - lo(a));
      extent(a) = size(rng);
    }
    const Eigen::Vector3d box_lo = (centre - 0.5 * extent).cwiseMax(lo);
    const Eigen::Vector3d box_hi = (centre + 0.5 * extent).cwiseMin(hi);
    // Voxels whose centre lies in [box_lo, box_hi]: (i + 0.5) r in the interval.
    const Eigen::Vector3i first = ((box_lo / r).array() - 0.5).ceil().cast<int>().matrix().cwiseMax(grid.box.min);
    const Eigen::Vector3i last =
        ((box_hi / r).array() - 0.5).floor().cast<int>().matrix().cwiseMin(grid.box.end() - Eigen::Vector3i::Ones());
    for (int z = first.z(); z <= last.z(); ++z) {
      for (int y = first.y(); y <= last.y(); ++y) {
        for (int x = first.x(); x <= last.x(); ++x) grid.Set(Eigen::Vector3i(x, y, z), true);
      }
    }
  }
  if (options.ground) {
    const int64_t plane = static_cast<int64_t>(grid.box.size.x()) * grid.box.size.y();
    std::fill_n(grid.occupied.begin(), plane, uint8_t{1});
  }
  return grid;
}

}  // namespace timeopt
