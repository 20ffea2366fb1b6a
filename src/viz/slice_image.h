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

#include "timeopt/core/errors.h"
#include "timeopt/map/esdf.h"

namespace timeopt::internal {

using Rgb = std::array<double, 3>;

// Piecewise-linear colour map through five equally spaced stops; t is clamped to [0, 1] (NaN, from
// inf / inf on a map of absurd resolution, counts as 0: it used to index the stops out of range).
inline Rgb InterpolateStops(const double (&stops)[5][3], double t) {
  if (std::isnan(t)) t = 0.0;
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
  // Pixels around the map: tick labels and axis names left of and below it, the colour bar and
  // up to two caption lines below those.
  static constexpr int kLeft = 52, kTop = 12, kRight = 16, kAxisBand = 34, kBarHeight = 76;

  // Throws std::invalid_argument when `height` is outside the field's z range or the image
  // cannot be created.
  SliceImage(const Esdf& esdf, double height, int pixels_per_voxel, int max_image_size, int min_width)
      : nx_(esdf.box().size.x()),
        ny_(esdf.box().size.y()),
        resolution_(esdf.resolution()),
        x0_(esdf.box().min.x() * esdf.resolution()),
        y0_(esdf.box().min.y() * esdf.resolution()) {
    const Eigen::AlignedBox3d metric = esdf.box().Metric(esdf.resolution());
    if (!std::isfinite(height) || height < metric.min().z() || height > metric.max().z()) {
      char message[160];
      std::snprintf(message, sizeof(message), "slice height %g is outside the map's z range [%g, %g]", height,
                    metric.min().z(), metric.max().z());
      throw std::invalid_argument(message);
    }
    ppv_ = std::max(1, std::min(pixels_per_voxel, max_image_size / std::max(nx_, ny_)));
    map_height_ = ny_ * ppv_;
    width_ = std::max(nx_ * ppv_, min_width);
    surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, kLeft + width_ + kRight,
                                              kTop + map_height_ + kAxisBand + kBarHeight));
    if (cairo_surface_status(surface_.get()) != CAIRO_STATUS_SUCCESS) {
      throw std::invalid_argument("cannot create an image of that size");
    }
    context_.reset(cairo_create(surface_.get()));
    cairo_set_source_rgb(context_.get(), 1, 1, 1);
    cairo_paint(context_.get());
    // From here on (0, 0) is the map's top-left corner: callers draw in map pixels.
    cairo_translate(context_.get(), kLeft, kTop);
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
  void DrawColourBar(const std::function<Rgb(double)>& colour, const std::string& low, const std::string& high,
                     const std::string& caption) const {
    cairo_t* c = context_.get();
    const int bar_x = 0, bar_y = map_height_ + kAxisBand + 6, bar_w = std::min(width_, 300);
    const int bar_h = 12;
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
    // The caption: one line, or two separated by '\n'.
    const size_t split = caption.find('\n');
    cairo_move_to(c, bar_x, bar_y + bar_h + 30);
    cairo_show_text(c, caption.substr(0, split).c_str());
    if (split != std::string::npos) {
      cairo_move_to(c, bar_x, bar_y + bar_h + 45);
      cairo_show_text(c, caption.substr(split + 1).c_str());
    }
  }

  // A frame around the map with metre ticks on x (below) and y (left), at a step of 1, 2 or 5
  // times a power of ten chosen for about six ticks along the longer side.
  void DrawAxes() const {
    cairo_t* c = context_.get();
    const double w = nx_ * ppv_, h = map_height_;
    const double px_per_metre = ppv_ / resolution_;
    const double span = std::max(nx_, ny_) * resolution_;
    const double raw = span / 6.0, decade = std::pow(10.0, std::floor(std::log10(raw)));
    const double step = raw <= decade       ? decade
                        : raw <= 2 * decade ? 2 * decade
                        : raw <= 5 * decade ? 5 * decade
                                            : 10 * decade;
    cairo_set_source_rgb(c, 0, 0, 0);
    cairo_set_line_width(c, 1.0);
    cairo_rectangle(c, 0.5, 0.5, w - 1, h - 1);
    cairo_stroke(c);
    cairo_select_font_face(c, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(c, 10);
    char label[32];
    cairo_text_extents_t extents;
    for (int axis = 0; axis < 2; ++axis) {
      const double origin = axis == 0 ? x0_ : y0_;
      const double length = (axis == 0 ? nx_ : ny_) * resolution_;
      for (double v = std::ceil(origin / step - 1e-9) * step; v <= origin + length + 1e-9 * step; v += step) {
        const double offset = (v - origin) * px_per_metre;
        std::snprintf(label, sizeof(label), "%g", std::abs(v) < 1e-9 * step ? 0.0 : v);
        cairo_text_extents(c, label, &extents);
        if (axis == 0) {
          cairo_move_to(c, offset, h);
          cairo_line_to(c, offset, h + 5);
          cairo_stroke(c);
          cairo_move_to(c, offset - extents.x_advance / 2, h + 16);
        } else {
          cairo_move_to(c, 0, h - offset);
          cairo_line_to(c, -5, h - offset);
          cairo_stroke(c);
          cairo_move_to(c, -8 - extents.x_advance, h - offset + 3.5);
        }
        cairo_show_text(c, label);
      }
    }
    cairo_set_font_size(c, 11);
    cairo_text_extents(c, "x [m]", &extents);
    cairo_move_to(c, w / 2 - extents.x_advance / 2, h + 30);
    cairo_show_text(c, "x [m]");
    cairo_save(c);
    cairo_move_to(c, -kLeft + 13, h / 2 + 12);
    cairo_rotate(c, -M_PI / 2);
    cairo_show_text(c, "y [m]");
    cairo_restore(c);
  }

  // Draws the axes (DrawAxes), then writes the PNG. Throws timeopt::FileError naming the path when
  // it cannot be written.
  void WritePng(const std::string& path) const {
    DrawAxes();
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
  double resolution_, x0_, y0_;  // metres per voxel; the metric x and y of the box's corner
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
