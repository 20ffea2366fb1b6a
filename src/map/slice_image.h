#pragma once

// Library-internal pieces shared by the PNG pictures drawn over a horizontal ESDF slice
// (`timeopt map slice` and the planner's trajectory plot): the image of the slice's voxel grid,
// colour maps given by five stops, the colour bar with its labels, and writing the PNG.

#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "timeopt/io/errors.h"
#include "timeopt/map/esdf.h"

namespace timeopt::internal {

using Rgb = std::array<double, 3>;

// Piecewise-linear colour map through five equally spaced stops; t is clamped to [0, 1].
inline Rgb InterpolateStops(const double (&stops)[5][3], double t) {
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(static_cast<int>(t), 3);
  const double f = t - i;
  Rgb rgb;
  for (int c = 0; c < 3; ++c) rgb[c] = stops[i][c] + f * (stops[i + 1][c] - stops[i][c]);
  return rgb;
}

// A white RGB image over the slice: one square of `pixels_per_voxel` pixels per voxel (reduced so
// that the map fits in `max_image_size` pixels), with room for a colour bar below it.
class SliceImage {
 public:
  static constexpr int kBarHeight = 62;  // pixels below the map for the bar and its caption

  // Throws std::invalid_argument when `height` is outside the field's z range or the image
  // cannot be created.
  SliceImage(const Esdf& esdf, double height, int pixels_per_voxel, int max_image_size,
             int min_width)
      : nx_(esdf.box().size.x()), ny_(esdf.box().size.y()) {
    const Eigen::AlignedBox3d metric = esdf.box().Metric(esdf.resolution());
    if (!std::isfinite(height) || height < metric.min().z() || height > metric.max().z()) {
      char message[160];
      std::snprintf(message, sizeof(message),
                    "slice height %g is outside the map's z range [%g, %g]", height,
                    metric.min().z(), metric.max().z());
      throw std::invalid_argument(message);
    }
    ppv_ = std::max(1, std::min(pixels_per_voxel, max_image_size / std::max(nx_, ny_)));
    map_height_ = ny_ * ppv_;
    width_ = std::max(nx_ * ppv_, min_width);
    surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, width_, map_height_ + kBarHeight));
    if (cairo_surface_status(surface_.get()) != CAIRO_STATUS_SUCCESS) {
      throw std::invalid_argument("cannot create an image of that size");
    }
    context_.reset(cairo_create(surface_.get()));
    cairo_set_source_rgb(context_.get(), 1, 1, 1);
    cairo_paint(context_.get());
  }

  cairo_t* context() const { return context_.get(); }
  int pixels_per_voxel() const { return ppv_; }
  int map_height() const { return map_height_; }
  int width() const { return width_; }

  // Fills every voxel square of the slice with colour(x, y) (voxel indices in the field's box,
  // y upwards), without anti-aliasing so neighbouring squares do not bleed.
  void FillVoxels(const std::function<Rgb(int, int)>& colour) const {
    cairo_t* c = context_.get();
    cairo_set_antialias(c, CAIRO_ANTIALIAS_NONE);
    for (int y = 0; y < ny_; ++y) {
      for (int x = 0; x < nx_; ++x) {
        const Rgb rgb = colour(x, y);
        cairo_set_source_rgb(c, rgb[0], rgb[1], rgb[2]);
        cairo_rectangle(c, x * ppv_, (ny_ - 1 - y) * ppv_, ppv_, ppv_);
        cairo_fill(c);
      }
    }
    cairo_set_antialias(c, CAIRO_ANTIALIAS_DEFAULT);
  }

  // The colour bar under the map with `low`/`high` labels at its ends and a caption line.
  void DrawColourBar(const std::function<Rgb(double)>& colour, const std::string& low,
                     const std::string& high, const std::string& caption) const {
    cairo_t* c = context_.get();
    const int bar_x = 10, bar_y = map_height_ + 8, bar_w = std::min(width_ - 20, 300), bar_h = 12;
    for (int i = 0; i < bar_w; ++i) {
      const Rgb rgb = colour(static_cast<double>(i) / (bar_w - 1));
      cairo_set_source_rgb(c, rgb[0], rgb[1], rgb[2]);
      cairo_rectangle(c, bar_x + i, bar_y, 1, bar_h);
      cairo_fill(c);
    }
    cairo_set_source_rgb(c, 0, 0, 0);
    cairo_select_font_face(c, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(c, 11);
    cairo_move_to(c, bar_x, bar_y + bar_h + 14);
    cairo_show_text(c, low.c_str());
    cairo_text_extents_t extents;
    cairo_text_extents(c, high.c_str(), &extents);
    cairo_move_to(c, bar_x + bar_w - extents.x_advance, bar_y + bar_h + 14);
    cairo_show_text(c, high.c_str());
    cairo_move_to(c, bar_x, bar_y + bar_h + 32);
    cairo_show_text(c, caption.c_str());
  }

  // Throws timeopt::FileError naming the path when the PNG cannot be written.
  void WritePng(const std::string& path) const {
    cairo_surface_flush(surface_.get());
    const cairo_status_t status = cairo_surface_write_to_png(surface_.get(), path.c_str());
    if (status != CAIRO_STATUS_SUCCESS) {
      throw FileError("cannot write PNG '" + path + "': " + cairo_status_to_string(status));
    }
  }

 private:
  struct SurfaceDeleter {
    void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
  };
  struct ContextDeleter {
    void operator()(cairo_t* c) const { cairo_destroy(c); }
  };
  int nx_, ny_;
  int ppv_ = 1, map_height_ = 0, width_ = 0;
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface_;
  std::unique_ptr<cairo_t, ContextDeleter> context_;
};

// "%.2f<unit>" as a string, for bar labels.
inline std::string FormatValue(double value, const char* unit) {
  char label[64];
  std::snprintf(label, sizeof(label), "%.2f %s", value, unit);
  return label;
}

}  // namespace timeopt::internal
