#pragma once

// Curve and waypoint files (described in docs/formats.md).
//
// Curve JSON: {"pieces": [{"x": [c0, c1, ...], "y": [...], "z": [...]}, ...],
//              "durations": [h0, h1, ...]}   ("durations" optional)
// Coefficients are ascending powers. Without "durations" piece i is a polynomial in s in [0, 1];
// with them it is a polynomial in its own parameter tau in [0, h_i] (what time-parameterized
// planners output) and is rescaled on reading to s = tau / h_i, so that every PiecewiseCurve in
// the library is in unit pieces. The durations are reported back in `CurveFile::durations`.
//
// Waypoint CSV: one "x,y,z" row per waypoint, an optional header line "x,y,z", blank lines and
// lines starting with '#' ignored.
//
// Errors: malformed content throws std::invalid_argument with a message naming the offending
// field or line ("curve.pieces[2].y: expected 4 coefficients like x, got 3"); a file that cannot
// be opened or written throws timeopt::FileError.

#include <optional>
#include <string>
#include <vector>

#include "timeopt/curve/interpolation.h"
#include "timeopt/curve/piecewise_curve.h"
#include "timeopt/core/errors.h"
#include "timeopt/core/files.h"

namespace timeopt {

struct CurveFile {
  PiecewiseCurve curve;                          // unit pieces (rescaled if durations were given)
  std::optional<std::vector<double>> durations;  // the given durations h_i, seconds or any unit
};

// Parses the curve object of the contract from JSON text; `context` prefixes error messages
// (e.g. "curve" inside a problem file).
CurveFile ParseCurveJson(const std::string& json_text, const std::string& context = "curve");
CurveFile ReadCurveJson(const std::string& path);

// JSON text of the curve (unit pieces, no durations).
std::string CurveToJson(const PiecewiseCurve& curve, int indent = 2);
void WriteCurveJson(const PiecewiseCurve& curve, const std::string& path);

// Rows x,y,z (an optional "x,y,z" header, '#' comments and blank lines skipped); at least 2 and at
// most 1e6 waypoints. Throws std::invalid_argument naming `source` and the line.
Waypoints ParseWaypointsCsv(const std::string& csv_text, const std::string& source = "waypoints");
Waypoints ReadWaypointsCsv(const std::string& path);

}  // namespace timeopt
