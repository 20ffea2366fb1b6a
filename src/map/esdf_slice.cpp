#include "timeopt/map/esdf_slice.h"

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include "timeopt/io/errors.h"

namespace timeopt {
namespace {

// A perceptually ordered dark-to-bright colour map (viridis, sampled at five stops).
std::array<double, 3> ColourMap(double t) {
  static constexpr double kStops[5][3] = {{0.267, 0.005, 0.329},
                                          {0.231, 0.322, 0.545},
                                          {0.129, 0.569, 0.549},
                                          {0.369, 0.788, 0.384},
                                          {0.993, 0.906, 0.144}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(static_cast<int>(t), 3);
  const double f = t - i;
  std::array<double, 3> rgb;
  for (int c = 0; c < 3; ++c) rgb[c] = kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c]);
  return rgb;
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};

}  // namespace

void WriteEsdfSlicePng(const Esdf& esdf, double height, const std::string& path,
                       const SliceImageOptions& options) {
  if (options.pixels_per_voxel < 1) throw std::invalid_argument("pixels_per_voxel must be >= 1");
  if (options.max_image_size < 16) throw std::invalid_argument("max_image_size must be >= 16");
  if (!(options.max_distance >= 0.0) || !std::isfinite(options.max_distance)) {
    throw std::invalid_argument("max_distance must be >= 0 (0: automatic)");
  }
  const Eigen::AlignedBox3d metric = esdf.box().Metric(esdf.resolution());
  if (!std::isfinite(height) || height < metric.min().z() || height > metric.max().z()) {
    char message[160];
    std::snprintf(message, sizeof(message), "slice height %g is outside the map's z range [%g, %g]",
                  height, metric.min().z(), metric.max().z());
    throw std::invalid_argument(message);
  }
  const int nx = esdf.box().size.x(), ny = esdf.box().size.y();
  const int ppv =
      std::max(1, std::min(options.pixels_per_voxel, options.max_image_size / std::max(nx, ny)));
  const double r = esdf.resolution();

  // Sample at voxel centres of the slice (x fastest, y upwards).
  std::vector<double> values(static_cast<size_t>(nx) * ny);
  double largest = 0.0;
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const Eigen::Vector3d p((esdf.box().min.x() + x + 0.5) * r, (esdf.box().min.y() + y + 0.5) * r,
                              height);
      const double d = esdf.Distance(p);
      values[static_cast<size_t>(y) * nx + x] = d;
      largest = std::max(largest, d);
    }
  }
  const double scale = options.max_distance > 0.0 ? options.max_distance : std::max(largest, r);

  const int map_w = nx * ppv, map_h = ny * ppv;
  const int bar_h = 62;
  const int width = std::max(map_w, 320), image_h = map_h + bar_h;
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, image_h));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::invalid_argument("cannot create an image of that size");
  }
  std::unique_ptr<cairo_t, ContextDeleter> cr(cairo_create(surface.get()));
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  cairo_set_antialias(cr.get(), CAIRO_ANTIALIAS_NONE);
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const double d = values[static_cast<size_t>(y) * nx + x];
      if (d < 0.0) {
        cairo_set_source_rgb(cr.get(), 0.0, 0.0, 0.0);  // obstacle
      } else {
        const auto rgb = ColourMap(d / scale);
        cairo_set_source_rgb(cr.get(), rgb[0], rgb[1], rgb[2]);
      }
      cairo_rectangle(cr.get(), x * ppv, (ny - 1 - y) * ppv, ppv, ppv);
      cairo_fill(cr.get());
    }
  }
  // Colour bar with labels.
  const int bar_x = 10, bar_y = map_h + 8, bar_w = std::min(width - 20, 300), bar_hh = 12;
  for (int i = 0; i < bar_w; ++i) {
    const auto rgb = ColourMap(static_cast<double>(i) / (bar_w - 1));
    cairo_set_source_rgb(cr.get(), rgb[0], rgb[1], rgb[2]);
    cairo_rectangle(cr.get(), bar_x + i, bar_y, 1, bar_hh);
    cairo_fill(cr.get());
  }
  cairo_set_antialias(cr.get(), CAIRO_ANTIALIAS_DEFAULT);
  cairo_set_source_rgb(cr.get(), 0, 0, 0);
  cairo_select_font_face(cr.get(), "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr.get(), 11);
  char label[160];
  cairo_move_to(cr.get(), bar_x, bar_y + bar_hh + 14);
  cairo_show_text(cr.get(), "0 m");
  std::snprintf(label, sizeof(label), "%.2f m", scale);
  cairo_text_extents_t extents;
  cairo_text_extents(cr.get(), label, &extents);
  cairo_move_to(cr.get(), bar_x + bar_w - extents.x_advance, bar_y + bar_hh + 14);
  cairo_show_text(cr.get(), label);
  std::snprintf(label, sizeof(label), "signed distance at z = %.2f m; black: obstacle; %g m voxels",
                height, r);
  cairo_move_to(cr.get(), bar_x, bar_y + bar_hh + 32);
  cairo_show_text(cr.get(), label);

  cairo_surface_flush(surface.get());
  const cairo_status_t status = cairo_surface_write_to_png(surface.get(), path.c_str());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw FileError("cannot write PNG '" + path + "': " + cairo_status_to_string(status));
  }
}

}  // namespace timeopt
