#include "timeopt/viz/plan_plot.h"

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

// Speed colours from slow (blue) over green and yellow to fast (red).
internal::Rgb SpeedColour(double t) {
  static constexpr double kStops[5][3] = {
      {0.13, 0.25, 0.85}, {0.0, 0.7, 0.9}, {0.2, 0.8, 0.2}, {0.98, 0.8, 0.1}, {0.85, 0.1, 0.1}};
  return internal::InterpolateStops(kStops, t);
}

}  // namespace

void WritePlanPng(const Esdf& esdf, const Trajectory& trajectory, const std::string& path,
                  const PlanImageOptions& options) {
  if (options.pixels_per_voxel < 1) throw std::invalid_argument("pixels_per_voxel must be >= 1");
  if (options.max_image_size < 64) throw std::invalid_argument("max_image_size must be >= 64");
  if (!(options.sample_rate_hz > 0.0) || !std::isfinite(options.sample_rate_hz)) {
    throw std::invalid_argument("sample_rate_hz must be a positive number");
  }
  if (!std::isnan(options.speed_scale) && !(options.speed_scale > 0.0 && std::isfinite(options.speed_scale))) {
    throw std::invalid_argument("speed_scale must be a positive number (or NaN: the trajectory's top speed)");
  }
  // At most kMaxPlotSamples points, whatever the flight's length (a flight of 2e7 s at 100 Hz
  // asked for 2e9).
  constexpr double kMaxPlotSamples = 1e5;
  const std::vector<TrajectoryState> samples =
      trajectory.Sample(std::min(options.sample_rate_hz, kMaxPlotSamples / std::max(trajectory.duration(), 1e-300)));
  double height = options.slice_height;
  if (std::isnan(height)) {
    height = 0.0;
    for (const TrajectoryState& s : samples) height += s.position.z();
    height /= static_cast<double>(samples.size());
  }
  const double r = esdf.resolution();
  const internal::SliceImage image(esdf, height, options.pixels_per_voxel, options.max_image_size, 360);
  const int ppv = image.pixels_per_voxel(), map_h = image.map_height();
  cairo_t* c = image.context();

  // Map slice: obstacles black, free space from grey (at the surface) to white (>= 2 m away).
  image.FillVoxels([&](int x, int y) {
    const Eigen::Vector3d p((esdf.box().min.x() + x + 0.5) * r, (esdf.box().min.y() + y + 0.5) * r, height);
    const double d = esdf.Distance(p);
    const double shade = d < 0.0 ? 0.0 : 0.6 + 0.4 * std::min(d / 2.0, 1.0);
    return internal::Rgb{shade, shade, shade};
  });
  const double x0 = esdf.box().min.x() * r, y0 = esdf.box().min.y() * r;
  auto px = [&](const Eigen::Vector3d& p) { return (p.x() - x0) / r * ppv; };
  auto py = [&](const Eigen::Vector3d& p) { return map_h - (p.y() - y0) / r * ppv; };

  double vmax = 0.0;
  for (const TrajectoryState& s : samples) vmax = std::max(vmax, s.velocity.norm());
  if (!std::isnan(options.speed_scale)) vmax = options.speed_scale;
  const double vscale = vmax > 0.0 ? vmax : 1.0;
  cairo_set_line_width(c, std::max(2.0, 0.6 * ppv));
  cairo_set_line_cap(c, CAIRO_LINE_CAP_ROUND);
  for (size_t k = 1; k < samples.size(); ++k) {
    const double speed = 0.5 * (samples[k - 1].velocity.norm() + samples[k].velocity.norm());
    const auto rgb = SpeedColour(std::min(speed / vscale, 1.0));
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
  char caption[200];
  std::snprintf(caption, sizeof(caption),
                "speed along the trajectory (T = %.2f s); green: start, purple: goal\n"
                "map slice at z = %.2f m: black obstacle; grey to white: distance to it, 0 to 2 m",
                trajectory.duration(), height);
  const std::string text = options.title.empty() ? std::string(caption) : options.title + ": " + caption;
  image.DrawColourBar(SpeedColour, "0 m/s", internal::FormatValue(vmax, "m/s"), text);
  image.WritePng(path);
}

}  // namespace timeopt
