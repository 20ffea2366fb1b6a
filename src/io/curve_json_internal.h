#pragma once

// Library-internal JSON helpers shared by the readers of curve and problem files.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "timeopt/io/curve_io.h"

namespace timeopt::internal {

// Parses JSON text; throws std::invalid_argument "<context>: malformed JSON: ..." on syntax errors.
nlohmann::json ParseJsonText(const std::string& text, const std::string& context);

// The curve object of the contract; errors name "<context>.pieces[i].x" and so on.
CurveFile CurveFromJson(const nlohmann::json& j, const std::string& context);

// A finite number at j; throws naming `field` otherwise.
double FiniteNumber(const nlohmann::json& j, const std::string& field);
// An array of finite numbers of the given size (any size when expected_size < 0).
std::vector<double> FiniteArray(const nlohmann::json& j, const std::string& field,
                                int expected_size = -1);

}  // namespace timeopt::internal
