#pragma once

// Shared by the IsValid() functions of the option structs (spatial, planner, temporal): records
// "<field>: expected <what>, got <value>" in *error (when not null) and returns false.

#include <sstream>
#include <string>

namespace timeopt::internal {

inline bool FailOption(std::string* error, const std::string& field, const std::string& expected, double got) {
  if (error != nullptr) {
    std::ostringstream s;
    s << field << ": expected " << expected << ", got " << got;
    *error = s.str();
  }
  return false;
}

}  // namespace timeopt::internal
