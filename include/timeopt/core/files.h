#pragma once

// Whole-file reads and writes for the modules that take files (io, map, viz) and the CLI. Each
// failure is a timeopt::FileError naming the path; bad content is for the caller to report.

#include <string>

#include "timeopt/core/errors.h"

namespace timeopt {

// Whole file as a string; throws FileError naming the path when it cannot be read.
std::string ReadTextFile(const std::string& path);
// Throws FileError naming the path when it cannot be written.
void WriteTextFile(const std::string& path, const std::string& text);
// Creates the folder that `file` would be written in, with its parents, when it does not exist yet
// (nothing for a bare file name). Throws FileError naming the folder when it cannot be created.
void EnsureParentDirectory(const std::string& file);

}  // namespace timeopt
