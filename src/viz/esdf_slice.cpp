#include "timeopt/viz/esdf_slice.h"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include "slice_image.h"

namespace timeopt {
namespace {

// A perceptually ordered dark-to-bright colour map (viridis, sampled at five stops).
internal::Rgb ColourMap(double t) {
  static constexpr double kStops[5][3] = {{0.267, 0.005, 0.329},
                                          {0.231, 0.322, 0.545},
                                          {0.129, 0.569, 0.549},
                                          {0.369, 0.788, 0.384},
                                          {0.993, 0.906, 0.144}};
  return internal::InterpolateStops(kStops, t);
}

}  // namespace

void WriteEsdfSlicePng(const Esdf& esdf, double height, const std::string& path, const SliceImageOptions& options) {
  if (options.pixels_per_voxel < 1) throw std::invalid_argument("pixels_per_voxel must be >= 1");
  if (options.max_image_size < 16) throw std::invalid_argument("max_image_size must be >= 16");
  if (!(options.max_distance >= 0.0) || !std::isfinite(options.max_distance)) {
    throw std::invalid_argument("max_distance must be >= 0 (0: automatic)");
  }
  const internal::SliceImage image(esdf, height, options.pixels_per_voxel, options.max_image_size, 320);
  const int nx = esdf.box().size.x(), ny = esdf.box().size.y();
  const double r = esdf.resolution();

  // Sample at voxel centres of the slice (x fastest, y upwards).
  std::vector<double> values(static_cast<size_t>(nx) * ny);
  double largest = 0.0;
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const Eigen::Vector3d p((esdf.box().min.x() + x + 0.5) * r, (esdf.box().min.y() + y + 0.5) * r, height);
      const double d = esdf.Distance(p);
      values[static_cast<size_t>(y) * nx + x] = d;
      largest = std::max(largest, d);
    }
  }
  const double scale = options.max_distance > 0.0 ? options.max_distance : std::max(largest, r);

  image.FillVoxels([&](int x, int y) {
    const double d = values[static_cast<size_t>(y) * nx + x];
    return d < 0.0 ? internal::Rgb{0.0, 0.0, 0.0} : ColourMap(d / scale);  // black: obstacle
  });
  char caption[160];
  std::snprintf(caption, sizeof(caption), "signed distance at z = %.2f m; black: obstacle; %g m voxels", height, r);
  image.DrawColourBar(ColourMap, "0 m", internal::FormatValue(scale, "m"), caption);
  image.WritePng(path);
}

}  // namespace timeopt
