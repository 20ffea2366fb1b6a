#pragma once

// Library-internal JSON and CSV helpers shared by the io readers and writers (curves, problems,
// planner configurations, samples). Every error is std::invalid_argument naming the field.

#include <array>
#include <cstddef>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include "timeopt/core/enum_strings.h"
#include "timeopt/core/vehicle_limits.h"
#include "timeopt/io/curve_io.h"

namespace timeopt::internal {

// Largest JSON text read (64 MiB): parsing it takes ~1 GB.
inline constexpr size_t kMaxJsonBytes = size_t{64} << 20;

// Parses JSON text; throws std::invalid_argument "<context>: malformed JSON: ..." on syntax errors,
// and "<context>: N bytes of JSON, above the ..." for text above kMaxJsonBytes.
nlohmann::json ParseJsonText(const std::string& text, const std::string& context);

// The curve object of the contract; errors name "<context>.pieces[i].x" and so on.
CurveFile CurveFromJson(const nlohmann::json& j, const std::string& context);

// A finite number at j; throws naming `field` otherwise.
double FiniteNumber(const nlohmann::json& j, const std::string& field);
// An array of finite numbers of the given size (any size when expected_size < 0).
std::vector<double> FiniteArray(const nlohmann::json& j, const std::string& field, int expected_size = -1);

// Throws "<where>.<key>: unknown key" for a key of the object j that is not in `known` (a typo must
// not fall back silently to a default). `where` may be empty.
void RejectUnknownKeys(const nlohmann::json& j, const std::set<std::string>& known, const std::string& where);
// Throws "<field>: expected an object" unless j is one.
void RequireObject(const nlohmann::json& j, const std::string& field);
// A scalar (the same on every axis) or an array of 3 finite numbers.
Eigen::Vector3d PerAxis(const nlohmann::json& j, const std::string& field);
// The vehicle limits of a "limits" object (where: its field name, e.g. "limits"), laid over
// *limits: a key present sets its limit, a key absent leaves it. null is "none": no per-axis limit
// (infinity on every axis), no jerk limit, no quadrotor limit; for gravity, unchanged. Unknown keys
// are refused. The one reader of limits for problem files, planner configs and Python's keywords.
void ReadLimits(const nlohmann::json& j, const std::string& where, VehicleLimits* limits);
// The keys ReadLimits reads and LimitsJson writes: every field of VehicleLimits.
inline constexpr std::array<const char*, 10> kLimitKeys = {
    "max_velocity", "max_acceleration",
    "max_jerk",     "max_acceleration_change",
    "max_speed",    "max_acceleration_norm",
    "max_thrust",   "min_thrust",
    "max_tilt",     "gravity",
};
// The limits as a "limits" object that ReadLimits reads back to the same values: per-axis limits
// as arrays (null when infinite on every axis), the jerk limit and the optional ones as values or
// null, gravity. (A per-axis limit infinite on some axes only has no JSON form: such an axis is
// written as null, which ReadLimits refuses, naming the key.)
nlohmann::json LimitsJson(const VehicleLimits& limits);
// An array of 3 finite numbers.
Eigen::Vector3d Vector3(const nlohmann::json& j, const std::string& field);
// A number with an integer value in [lowest, highest] (30 and 30.0 both read as 30).
long long IntegerInRange(const nlohmann::json& j, const std::string& field, long long lowest, long long highest);

// The enumerator named by the string at j (FromString of its module); throws naming the field
// and the allowed names otherwise.
template <typename Enum, std::size_t N>
Enum EnumField(const nlohmann::json& j, const std::string& field, const std::array<Enum, N>& all) {
  Enum value = all[0];
  if (!j.is_string() || !EnumFromString(j.get<std::string>(), all, &value)) {
    throw std::invalid_argument(field + ": expected " + EnumChoices(all) + ", got " + j.dump());
  }
  return value;
}

// The comma-separated numbers of one CSV row (blanks around fields ignored); throws
// std::invalid_argument "<where>: 'field' is not a number" (or "is not finite").
std::vector<double> CsvNumbers(const std::string& row, const std::string& where);

}  // namespace timeopt::internal
