#include "json_internal.h"

#include <cmath>

namespace timeopt::internal {

void RejectUnknownKeys(const nlohmann::json& j, const std::set<std::string>& known,
                       const std::string& where) {
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

Eigen::Vector3d Vector3(const nlohmann::json& j, const std::string& field) {
  const std::vector<double> v = FiniteArray(j, field, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

long long IntegerInRange(const nlohmann::json& j, const std::string& field, long long lowest,
                         long long highest) {
  const auto fail = [&] {
    return std::invalid_argument(field + ": expected an integer in " + std::to_string(lowest) +
                                 ".." + std::to_string(highest) + ", got " + j.dump());
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
