#pragma once

// Library-internal JSON and CSV helpers shared by the readers of curve, problem and sample files.

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

// The comma-separated numbers of one CSV row (blanks around fields ignored); throws
// std::invalid_argument "<where>: 'field' is not a number" (or "is not finite").
std::vector<double> CsvNumbers(const std::string& row, const std::string& where);

}  // namespace timeopt::internal
