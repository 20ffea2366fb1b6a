#pragma once

// Minimal line plots written as PNG with cairo: stacked panels sharing the x axis, each with
// series, optional horizontal limit lines, ticks, labels and a legend. Used by the CLI and the
// experiments to show profiles (e.g. the paper's Fig. 3b).

#include <array>
#include <string>
#include <vector>

namespace timeopt {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;  // same size
  std::array<double, 3> rgb = {0.1, 0.3, 0.8};
  bool dashed = false;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  bool log_y = false;  // logarithmic y axis (values <= 0 are skipped)
  bool log_x = false;  // logarithmic x axis (values <= 0 are skipped)
};

// Writes the panels stacked vertically into a PNG. Throws std::invalid_argument for mismatched
// series sizes or no panel, timeopt::FileError when the file cannot be written.
void WritePlotPng(const std::vector<PlotPanel>& panels, const std::string& path, int width = 1000,
                  int panel_height = 280);

}  // namespace timeopt
