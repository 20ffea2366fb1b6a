#include "timeopt/spatial/plan_plot.h"

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

// Speed colours from slow (blue) over green and yellow to fast (red).
std::array<double, 3> SpeedColour(double t) {
  static constexpr double kStops[5][3] = {
      {0.13, 0.25, 0.85}, {0.0, 0.7, 0.9}, {0.2, 0.8, 0.2}, {0.98, 0.8, 0.1}, {0.85, 0.1, 0.1}};
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

void WritePlanPng(const Esdf& esdf, const Trajectory& trajectory, const std::string& path,
                  const PlanImageOptions& options) {
  if (options.pixels_per_voxel < 1) throw std::invalid_argument("pixels_per_voxel must be >= 1");
  if (options.max_image_size < 64) throw std::invalid_argument("max_image_size must be >= 64");
  if (!(options.sample_rate_hz > 0.0) || !std::isfinite(options.sample_rate_hz)) {
    throw std::invalid_argument("sample_rate_hz must be a positive number");
  }
  const std::vector<TrajectoryState> samples = trajectory.Sample(options.sample_rate_hz);
  double height = options.slice_height;
  if (std::isnan(height)) {
    height = 0.0;
    for (const TrajectoryState& s : samples) height += s.position.z();
    height /= static_cast<double>(samples.size());
  }
  const double r = esdf.resolution();
  const Eigen::AlignedBox3d metric = esdf.box().Metric(r);
  if (!std::isfinite(height) || height < metric.min().z() || height > metric.max().z()) {
    char message[160];
    std::snprintf(message, sizeof(message), "slice height %g is outside the map's z range [%g, %g]",
                  height, metric.min().z(), metric.max().z());
    throw std::invalid_argument(message);
  }
  const int nx = esdf.box().size.x(), ny = esdf.box().size.y();
  const int ppv =
      std::max(1, std::min(options.pixels_per_voxel, options.max_image_size / std::max(nx, ny)));
  const int map_w = nx * ppv, map_h = ny * ppv, bar_h = 62;
  const int width = std::max(map_w, 360), image_h = map_h + bar_h;
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface(
      cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, image_h));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS) {
    throw std::invalid_argument("cannot create an image of that size");
  }
  std::unique_ptr<cairo_t, ContextDeleter> cr(cairo_create(surface.get()));
  cairo_t* c = cr.get();
  cairo_set_source_rgb(c, 1, 1, 1);
  cairo_paint(c);

  // Map slice: obstacles black, free space from grey (at the surface) to white (>= 2 m away).
  cairo_set_antialias(c, CAIRO_ANTIALIAS_NONE);
  for (int y = 0; y < ny; ++y) {
    for (int x = 0; x < nx; ++x) {
      const Eigen::Vector3d p((esdf.box().min.x() + x + 0.5) * r, (esdf.box().min.y() + y + 0.5) * r,
                              height);
      const double d = esdf.Distance(p);
      const double shade = d < 0.0 ? 0.0 : 0.6 + 0.4 * std::min(d / 2.0, 1.0);
      cairo_set_source_rgb(c, shade, shade, shade);
      cairo_rectangle(c, x * ppv, (ny - 1 - y) * ppv, ppv, ppv);
      cairo_fill(c);
    }
  }
  cairo_set_antialias(c, CAIRO_ANTIALIAS_DEFAULT);
  const double x0 = esdf.box().min.x() * r, y0 = esdf.box().min.y() * r;
  auto px = [&](const Eigen::Vector3d& p) { return (p.x() - x0) / r * ppv; };
  auto py = [&](const Eigen::Vector3d& p) { return map_h - (p.y() - y0) / r * ppv; };

  double vmax = 0.0;
  for (const TrajectoryState& s : samples) vmax = std::max(vmax, s.velocity.norm());
  const double vscale = vmax > 0.0 ? vmax : 1.0;
  cairo_set_line_width(c, std::max(2.0, 0.6 * ppv));
  cairo_set_line_cap(c, CAIRO_LINE_CAP_ROUND);
  for (size_t k = 1; k < samples.size(); ++k) {
    const double speed = 0.5 * (samples[k - 1].velocity.norm() + samples[k].velocity.norm());
    const auto rgb = SpeedColour(speed / vscale);
    cairo_set_source_rgb(c, rgb[0], rgb[1], rgb[2]);
    cairo_move_to(c, px(samples[k - 1].position), py(samples[k - 1].position));
    cairo_line_to(c, px(samples[k].position), py(samples[k].position));
    cairo_stroke(c);
  }
  for (int end = 0; end < 2; ++end) {
    const Eigen::Vector3d& p = end == 0 ? samples.front().position : samples.back().position;
    cairo_set_source_rgb(c, end == 0 ? 0.1 : 0.8, end == 0 ? 0.6 : 0.1, end == 0 ? 0.1 : 0.6);
    cairo_arc(c, px(p), py(p), std::max(4.0, 1.5 * ppv), 0, 2 * M_PI);
    cairo_fill(c);
  }

  // Speed colour bar and caption.
  const int bar_x = 10, bar_y = map_h + 8, bar_w = std::min(width - 20, 300), bar_hh = 12;
  for (int i = 0; i < bar_w; ++i) {
    const auto rgb = SpeedColour(static_cast<double>(i) / (bar_w - 1));
    cairo_set_source_rgb(c, rgb[0], rgb[1], rgb[2]);
    cairo_rectangle(c, bar_x + i, bar_y, 1, bar_hh);
    cairo_fill(c);
  }
  cairo_set_source_rgb(c, 0, 0, 0);
  cairo_select_font_face(c, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(c, 11);
  char label[200];
  cairo_move_to(c, bar_x, bar_y + bar_hh + 14);
  cairo_show_text(c, "0 m/s");
  std::snprintf(label, sizeof(label), "%.2f m/s", vmax);
  cairo_text_extents_t extents;
  cairo_text_extents(c, label, &extents);
  cairo_move_to(c, bar_x + bar_w - extents.x_advance, bar_y + bar_hh + 14);
  cairo_show_text(c, label);
  std::snprintf(label, sizeof(label),
                "speed along the trajectory (T = %.2f s); map slice at z = %.2f m, black: obstacle; "
                "green: start, purple: goal",
                trajectory.duration(), height);
  cairo_move_to(c, bar_x, bar_y + bar_hh + 32);
  cairo_show_text(c, label);

  cairo_surface_flush(surface.get());
  const cairo_status_t status = cairo_surface_write_to_png(surface.get(), path.c_str());
  if (status != CAIRO_STATUS_SUCCESS) {
    throw FileError("cannot write PNG '" + path + "': " + cairo_status_to_string(status));
  }
}

}  // namespace timeopt
