#include "timeopt/io/curve_io.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "json_internal.h"

namespace timeopt {
namespace internal {

nlohmann::json ParseJsonText(const std::string& text, const std::string& context) {
  // The parsed tree takes ~16 bytes of memory per byte of text (a 130 MB problem reached 2.1 GB),
  // and a parse that runs out of memory cannot be unwound (the library's tree destructor allocates,
  // so the process aborts). The largest problem the cell cap admits, 2e6 cells at K = 50 (4e4
  // quintic pieces), is ~15 MB of text.
  if (text.size() > kMaxJsonBytes) {
    throw std::invalid_argument(context + ": " + std::to_string(text.size()) + " bytes of JSON, above the " +
                                std::to_string(kMaxJsonBytes) + " supported");
  }
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(context + ": malformed JSON: " + e.what());
  }
}

double FiniteNumber(const nlohmann::json& j, const std::string& field) {
  if (!j.is_number()) {
    throw std::invalid_argument(field + ": expected a number, got " + std::string(j.type_name()));
  }
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw std::invalid_argument(field + ": expected a finite number");
  return v;
}

std::vector<double> CsvNumbers(const std::string& row, const std::string& where) {
  std::vector<double> values;
  std::stringstream fields(row);
  std::string field;
  while (std::getline(fields, field, ',')) {
    const auto first = field.find_first_not_of(" \t");
    const auto last = field.find_last_not_of(" \t");
    field = first == std::string::npos ? std::string() : field.substr(first, last - first + 1);
    // strtod, not stod: stod rejects subnormal values (ERANGE on underflow).
    char* end = nullptr;
    const double v = std::strtod(field.c_str(), &end);
    if (field.empty() || *end != '\0') throw std::invalid_argument(where + ": '" + field + "' is not a number");
    if (!std::isfinite(v)) throw std::invalid_argument(where + ": '" + field + "' is not finite");
    values.push_back(v);
  }
  return values;
}

std::vector<double> FiniteArray(const nlohmann::json& j, const std::string& field, int expected_size) {
  if (!j.is_array()) {
    throw std::invalid_argument(field + ": expected an array, got " + std::string(j.type_name()));
  }
  if (expected_size >= 0 && static_cast<int>(j.size()) != expected_size) {
    throw std::invalid_argument(field + ": expected " + std::to_string(expected_size) + " numbers, got " +
                                std::to_string(j.size()));
  }
  std::vector<double> out;
  out.reserve(j.size());
  for (size_t i = 0; i < j.size(); ++i) {
    out.push_back(FiniteNumber(j[i], field + "[" + std::to_string(i) + "]"));
  }
  return out;
}

CurveFile CurveFromJson(const nlohmann::json& j, const std::string& context) {
  if (!j.is_object()) throw std::invalid_argument(context + ": expected an object");
  if (!j.contains("pieces")) throw std::invalid_argument(context + ".pieces: missing");
  const auto& pieces_json = j.at("pieces");
  if (!pieces_json.is_array()) throw std::invalid_argument(context + ".pieces: expected an array");
  if (pieces_json.empty()) {
    throw std::invalid_argument(context + ".pieces: expected at least 1 piece, got 0");
  }
  std::optional<std::vector<double>> durations;
  if (j.contains("durations")) {
    durations = FiniteArray(j.at("durations"), context + ".durations", static_cast<int>(pieces_json.size()));
    for (size_t i = 0; i < durations->size(); ++i) {
      if (!((*durations)[i] > 0.0)) {
        throw std::invalid_argument(context + ".durations[" + std::to_string(i) + "]: expected a positive duration");
      }
    }
  }
  std::vector<PolynomialPiece> pieces;
  pieces.reserve(pieces_json.size());
  for (size_t i = 0; i < pieces_json.size(); ++i) {
    const std::string name = context + ".pieces[" + std::to_string(i) + "]";
    const auto& pj = pieces_json[i];
    if (!pj.is_object()) throw std::invalid_argument(name + ": expected an object");
    std::vector<double> axes[3];
    const char* axis_names[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      if (!pj.contains(axis_names[a])) {
        throw std::invalid_argument(name + "." + axis_names[a] + ": missing");
      }
      axes[a] = FiniteArray(pj.at(axis_names[a]), name + "." + axis_names[a]);
    }
    // An axis may give fewer coefficients than another (a constant axis as [c]): the missing
    // higher-order coefficients are zero.
    size_t size = 0;
    for (int a = 0; a < 3; ++a) {
      if (axes[a].empty()) {
        throw std::invalid_argument(name + "." + axis_names[a] + ": expected at least 1 coefficient");
      }
      size = std::max(size, axes[a].size());
    }
    PolynomialPiece::Coefficients c = PolynomialPiece::Coefficients::Zero(3, static_cast<Eigen::Index>(size));
    for (int a = 0; a < 3; ++a) {
      for (size_t k = 0; k < axes[a].size(); ++k) c(a, static_cast<Eigen::Index>(k)) = axes[a][k];
    }
    PolynomialPiece piece(std::move(c));
    if (durations) piece = piece.Reparameterized((*durations)[i]);
    pieces.push_back(std::move(piece));
  }
  return CurveFile{PiecewiseCurve(std::move(pieces)), durations};
}

}  // namespace internal

CurveFile ParseCurveJson(const std::string& json_text, const std::string& context) {
  return internal::CurveFromJson(internal::ParseJsonText(json_text, context), context);
}

CurveFile ReadCurveJson(const std::string& path) { return ParseCurveJson(ReadTextFile(path), path); }

std::string CurveToJson(const PiecewiseCurve& curve, int indent) {
  nlohmann::json pieces = nlohmann::json::array();
  for (const auto& p : curve.pieces()) {
    nlohmann::json pj;
    const char* axis_names[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      std::vector<double> row(p.coefficients().cols());
      for (int k = 0; k < p.coefficients().cols(); ++k) row[k] = p.coefficients()(a, k);
      pj[axis_names[a]] = row;
    }
    pieces.push_back(pj);
  }
  nlohmann::json j;
  j["pieces"] = pieces;
  return j.dump(indent) + "\n";
}

void WriteCurveJson(const PiecewiseCurve& curve, const std::string& path) { WriteTextFile(path, CurveToJson(curve)); }

// Largest number of waypoints read: 1e6 (a curve through them takes a few hundred MB; a temporal
// problem on it meets the 2e6-cell cap first at K >= 2).
constexpr size_t kMaxWaypoints = 1'000'000;

Waypoints ParseWaypointsCsv(const std::string& csv_text, const std::string& source) {
  std::istringstream in(csv_text);
  std::string line;
  std::vector<Eigen::Vector3d> points;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    std::string trimmed = line.substr(first);
    if (points.empty() && (trimmed.rfind("x", 0) == 0)) {
      std::string compact;
      for (char ch : trimmed)
        if (ch != ' ' && ch != '\t') compact += ch;
      if (compact == "x,y,z") continue;
    }
    const std::string where = source + " line " + std::to_string(line_number);
    const std::vector<double> values = internal::CsvNumbers(trimmed, where);
    if (values.size() != 3) {
      throw std::invalid_argument(where + ": expected 3 values x,y,z, got " + std::to_string(values.size()));
    }
    if (points.size() >= kMaxWaypoints) {
      throw std::invalid_argument(where + ": more than " + std::to_string(kMaxWaypoints) +
                                  " waypoints, above the supported number");
    }
    points.emplace_back(values[0], values[1], values[2]);
  }
  if (points.size() < 2) {
    throw std::invalid_argument(source + ": expected at least 2 waypoints, got " + std::to_string(points.size()));
  }
  Waypoints w(3, static_cast<Eigen::Index>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) w.col(static_cast<Eigen::Index>(i)) = points[i];
  return w;
}

Waypoints ReadWaypointsCsv(const std::string& path) { return ParseWaypointsCsv(ReadTextFile(path), path); }

}  // namespace timeopt
