#include "timeopt/core/files.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

namespace timeopt {

std::string ReadTextFile(const std::string& path) {
  // A directory opens as a stream on Linux and then fails with a bare "basic_filebuf::underflow".
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FileError("'" + path + "' is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot open '" + path + "' for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw FileError("error while reading '" + path + "'");
  return ss.str();
}

void WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError("cannot open '" + path + "' for writing");
  out << text;
  out.flush();
  if (!out) throw FileError("error while writing '" + path + "'");
}

void EnsureParentDirectory(const std::string& file) {
  const std::filesystem::path parent = std::filesystem::path(file).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec) throw FileError("cannot create directory '" + parent.string() + "': " + ec.message());
}

}  // namespace timeopt
