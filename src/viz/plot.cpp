#include "timeopt/viz/plot.h"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "timeopt/core/errors.h"

namespace timeopt {
namespace {

// Tick step of about `target` ticks over span: 1, 2 or 5 times a power of ten.
double NiceStep(double span, int target) {
  const double raw = span / std::max(1, target);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

std::string Format(double v) {
  char buffer[32];
  if (std::abs(v) < 1e-12) v = 0.0;
  std::snprintf(buffer, sizeof(buffer), "%g", v);
  return buffer;
}

void Text(cairo_t* cr, double x, double y, const std::string& s, double align_x, double align_y,
          bool vertical = false) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_save(cr);
  cairo_translate(cr, x, y);
  if (vertical) cairo_rotate(cr, -M_PI / 2.0);
  cairo_move_to(cr, -e.width * align_x - e.x_bearing, e.height * align_y);
  cairo_show_text(cr, s.c_str());
  cairo_restore(cr);
}

}  // namespace

void WritePlotPng(const std::vector<PlotPanel>& panels, const std::string& path, int width, int panel_height) {
  if (panels.empty()) throw std::invalid_argument("WritePlotPng: no panel");
  if (width < 200 || panel_height < 100) throw std::invalid_argument("WritePlotPng: image too small");
  for (const auto& p : panels) {
    for (const auto& s : p.series) {
      if (s.x.size() != s.y.size()) {
        throw std::invalid_argument("WritePlotPng: series '" + s.label + "' has " + std::to_string(s.x.size()) +
                                    " x values and " + std::to_string(s.y.size()) + " y values");
      }
    }
  }
  const int height = panel_height * static_cast<int>(panels.size());
  cairo_surface_t* surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  cairo_t* cr = cairo_create(surface);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

  const double left = 80, right = 170, top = 34, bottom = 46;
  for (size_t pi = 0; pi < panels.size(); ++pi) {
    const PlotPanel& panel = panels[pi];
    const double y0 = static_cast<double>(pi) * panel_height;
    const double px0 = left, px1 = width - right, py0 = y0 + top, py1 = y0 + panel_height - bottom;

    const auto ty = [&](double v) { return panel.log_y ? std::log10(v) : v; };
    const auto tx = [&](double v) { return panel.log_x ? std::log10(v) : v; };
    const auto skipped = [&](double x, double y) {
      return !std::isfinite(x) || !std::isfinite(y) || (panel.log_y && y <= 0.0) || (panel.log_x && x <= 0.0);
    };
    double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin, ymin = xmin, ymax = -xmin;
    for (const auto& s : panel.series) {
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (skipped(s.x[i], s.y[i])) continue;
        xmin = std::min(xmin, tx(s.x[i]));
        xmax = std::max(xmax, tx(s.x[i]));
        ymin = std::min(ymin, ty(s.y[i]));
        ymax = std::max(ymax, ty(s.y[i]));
      }
    }
    if (!std::isfinite(xmin)) {
      xmin = 0;
      xmax = 1;
      ymin = 0;
      ymax = 1;
    }
    if (xmax - xmin <= 0) {
      xmin -= 0.5;
      xmax += 0.5;
    }
    if (ymax - ymin <= 0) {
      ymin -= 0.5;
      ymax += 0.5;
    }
    const double pad = 0.06 * (ymax - ymin);
    ymin -= pad;
    ymax += pad;
    const auto X = [&](double v) { return px0 + (tx(v) - xmin) / (xmax - xmin) * (px1 - px0); };
    const auto XT = [&](double t) { return px0 + (t - xmin) / (xmax - xmin) * (px1 - px0); };  // t: axis units
    const auto Y = [&](double v) { return py1 - (ty(v) - ymin) / (ymax - ymin) * (py1 - py0); };

    // grid and ticks
    cairo_set_font_size(cr, 12);
    cairo_set_line_width(cr, 1.0);
    // A logarithmic axis is ticked at whole decades, labelled with their values (0.1, 1, 10).
    const double xs = panel.log_x ? std::max(1.0, std::round(NiceStep(xmax - xmin, 8))) : NiceStep(xmax - xmin, 8);
    for (double v = std::ceil(xmin / xs) * xs; v <= xmax + 1e-9 * xs; v += xs) {
      cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
      cairo_move_to(cr, XT(v), py0);
      cairo_line_to(cr, XT(v), py1);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      Text(cr, XT(v), py1 + 6, Format(panel.log_x ? std::pow(10.0, v) : v), 0.5, 1.0);
    }
    const double ys = NiceStep(ymax - ymin, 5);
    for (double v = std::ceil(ymin / ys) * ys; v <= ymax + 1e-9 * ys; v += ys) {
      const double py = py1 - (v - ymin) / (ymax - ymin) * (py1 - py0);
      cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
      cairo_move_to(cr, px0, py);
      cairo_line_to(cr, px1, py);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      Text(cr, px0 - 6, py, panel.log_y ? "1e" + Format(v) : Format(v), 1.0, 0.5);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_rectangle(cr, px0, py0, px1 - px0, py1 - py0);
    cairo_stroke(cr);

    // series, clipped to the frame
    cairo_save(cr);
    cairo_rectangle(cr, px0, py0, px1 - px0, py1 - py0);
    cairo_clip(cr);
    for (const auto& s : panel.series) {
      cairo_set_source_rgb(cr, s.rgb[0], s.rgb[1], s.rgb[2]);
      cairo_set_line_width(cr, s.dashed ? 1.5 : 2.0);
      const double dash[] = {6.0, 4.0};
      cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0);
      bool pen = false;
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (skipped(s.x[i], s.y[i])) {
          pen = false;
          continue;
        }
        if (pen)
          cairo_line_to(cr, X(s.x[i]), Y(s.y[i]));
        else
          cairo_move_to(cr, X(s.x[i]), Y(s.y[i]));
        pen = true;
      }
      cairo_stroke(cr);
    }
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_restore(cr);

    // labels and legend
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 14);
    Text(cr, (px0 + px1) / 2, y0 + 10, panel.title, 0.5, 1.0);
    cairo_set_font_size(cr, 12);
    Text(cr, (px0 + px1) / 2, py1 + 26, panel.x_label, 0.5, 1.0);
    Text(cr, 18, (py0 + py1) / 2, panel.y_label, 0.5, 1.0, true);
    double ly = py0 + 8;
    for (const auto& s : panel.series) {
      if (s.label.empty()) continue;
      cairo_set_source_rgb(cr, s.rgb[0], s.rgb[1], s.rgb[2]);
      cairo_set_line_width(cr, 2.0);
      const double dash[] = {6.0, 4.0};
      cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0);
      cairo_move_to(cr, px1 + 12, ly);
      cairo_line_to(cr, px1 + 40, ly);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0);
      cairo_set_source_rgb(cr, 0, 0, 0);
      Text(cr, px1 + 46, ly, s.label, 0.0, 0.5);
      ly += 18;
    }
  }
  cairo_destroy(cr);
  const cairo_status_t status = cairo_surface_write_to_png(surface, path.c_str());
  cairo_surface_destroy(surface);
  if (status != CAIRO_STATUS_SUCCESS) {
    throw FileError("cannot write PNG '" + path + "': " + cairo_status_to_string(status));
  }
}

}  // namespace timeopt
