#pragma once

#include <stdexcept>
#include <string>

namespace timeopt {

// A file could not be opened, read or written. Bad *content* is std::invalid_argument instead.
class FileError : public std::runtime_error {
 public:
  explicit FileError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace timeopt
