#pragma once

// Runs the built `timeopt` executable (TIMEOPT_CLI_PATH, set by CMake for every test target) in a
// shell and captures its standard output and exit code. Shared by the CLI tests of all modules.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace timeopt::testing_support {

struct CliRun {
  int exit_code = -1;  // -1 when the process could not be started or did not exit normally
  std::string output;  // what the command wrote to the captured stream(s)
};

// `redirect` is appended to the command line: the default merges stderr into the output;
// "2>FILE" keeps stdout alone and sends stderr to FILE.
inline CliRun RunCli(const std::string& args, const std::string& redirect = "2>&1") {
  const std::string command = std::string(TIMEOPT_CLI_PATH) + " " + args + " " + redirect;
  CliRun run;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    run.output = "popen failed";
    return run;
  }
  std::array<char, 4096> buffer{};
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) run.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

}  // namespace timeopt::testing_support
