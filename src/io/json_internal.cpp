#include "json_internal.h"

#include <cmath>
#include <limits>
#include <optional>

namespace timeopt::internal {

void RejectUnknownKeys(const nlohmann::json& j, const std::set<std::string>& known, const std::string& where) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!known.count(it.key())) {
      throw std::invalid_argument(where + (where.empty() ? "" : ".") + it.key() + ": unknown key");
    }
  }
}

void RequireObject(const nlohmann::json& j, const std::string& field) {
  if (!j.is_object()) throw std::invalid_argument(field + ": expected an object");
}

Eigen::Vector3d PerAxis(const nlohmann::json& j, const std::string& field) {
  if (j.is_number()) return Eigen::Vector3d::Constant(FiniteNumber(j, field));
  return Vector3(j, field);
}

void ReadLimits(const nlohmann::json& j, const std::string& where, VehicleLimits* limits) {
  RequireObject(j, where);
  RejectUnknownKeys(j, std::set<std::string>(kLimitKeys.begin(), kLimitKeys.end()), where);
  constexpr double kNone = std::numeric_limits<double>::infinity();
  const auto per_axis = [&](const char* key, Eigen::Vector3d* field) {
    if (!j.contains(key)) return;
    const nlohmann::json& v = j.at(key);
    *field = v.is_null() ? Eigen::Vector3d::Constant(kNone) : PerAxis(v, where + "." + key);
  };
  const auto optional = [&](const char* key, std::optional<double>* field) {
    if (!j.contains(key)) return;
    const nlohmann::json& v = j.at(key);
    if (v.is_null())
      field->reset();
    else
      *field = FiniteNumber(v, where + "." + key);
  };
  per_axis("max_velocity", &limits->max_velocity);
  per_axis("max_acceleration", &limits->max_acceleration);
  if (j.contains("max_jerk")) {
    // null: no jerk limit (the paper's profile, whose acceleration steps between cells).
    const nlohmann::json& v = j.at("max_jerk");
    if (v.is_null())
      limits->max_jerk.reset();
    else
      limits->max_jerk = PerAxis(v, where + ".max_jerk");
  }
  optional("max_acceleration_change", &limits->max_acceleration_change);
  optional("max_speed", &limits->max_speed);
  optional("max_acceleration_norm", &limits->max_acceleration_norm);
  optional("max_thrust", &limits->max_thrust);
  optional("min_thrust", &limits->min_thrust);
  optional("max_tilt", &limits->max_tilt);
  if (j.contains("gravity") && !j.at("gravity").is_null())
    limits->gravity = FiniteNumber(j.at("gravity"), where + ".gravity");
}

nlohmann::json LimitsJson(const VehicleLimits& l) {
  const auto per_axis = [](const Eigen::Vector3d& v) {
    return v.array().isInf().all() ? nlohmann::json(nullptr) : nlohmann::json::array({v.x(), v.y(), v.z()});
  };
  const auto optional = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["max_velocity"] = per_axis(l.max_velocity);
  j["max_acceleration"] = per_axis(l.max_acceleration);
  j["max_jerk"] =
      l.max_jerk ? nlohmann::json::array({l.max_jerk->x(), l.max_jerk->y(), l.max_jerk->z()}) : nlohmann::json(nullptr);
  j["max_acceleration_change"] = optional(l.max_acceleration_change);
  j["max_speed"] = optional(l.max_speed);
  j["max_acceleration_norm"] = optional(l.max_acceleration_norm);
  j["max_thrust"] = optional(l.max_thrust);
  j["min_thrust"] = optional(l.min_thrust);
  j["max_tilt"] = optional(l.max_tilt);
  j["gravity"] = l.gravity;
  return j;
}

Eigen::Vector3d Vector3(const nlohmann::json& j, const std::string& field) {
  const std::vector<double> v = FiniteArray(j, field, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

long long IntegerInRange(const nlohmann::json& j, const std::string& field, long long lowest, long long highest) {
  const auto fail = [&] {
    return std::invalid_argument(field + ": expected an integer in " + std::to_string(lowest) + ".." +
                                 std::to_string(highest) + ", got " + j.dump());
  };
  if (j.is_number_integer()) {
    // Unsigned values above the signed range are out of range too.
    if (j.is_number_unsigned() && j.get<unsigned long long>() > static_cast<unsigned long long>(highest)) {
      throw fail();
    }
    const long long value = j.get<long long>();
    if (value < lowest || value > highest) throw fail();
    return value;
  }
  if (j.is_number_float()) {
    const double value = j.get<double>();
    if (!(value >= static_cast<double>(lowest) && value <= static_cast<double>(highest)) ||
        value != std::floor(value)) {
      throw fail();
    }
    return static_cast<long long>(value);
  }
  throw fail();
}

}  // namespace timeopt::internal
