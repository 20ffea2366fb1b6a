// The `timeopt` command-line tool: parses arguments, dispatches to a subcommand and maps errors to
// exit codes with a one-line message on stderr.

#include <iostream>
#include <new>
#include <stdexcept>

#include "commands.h"
#include "timeopt/core/errors.h"
#include "timeopt/version.h"

int main(int argc, char** argv) {
  using namespace timeopt::cli;
  CLI::App app{
      "timeopt: minimum-time quadrotor trajectories (spatial-temporal decoupling, Gao et al. "
      "IROS 2018)"};
  app.set_version_flag("--version", std::string("timeopt ") + TIMEOPT_VERSION_STRING);
  app.require_subcommand(1);
  Runner run;
  RegisterCurveCommand(app, run);
  RegisterTemporalCommand(app, run);
  RegisterWaypointsCommand(app, run);
  RegisterMapCommand(app, run);
  RegisterPlanCommand(app, run);
  RegisterConicCommand(app, run);
  RegisterSimulateCommand(app, run);
  RegisterExportCommand(app, run);
  RegisterViewCommand(app, run);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "timeopt: " << e.what() << " (see --help)\n";
    return kExitInvalidInput;
  }

  try {
    return run ? run() : kExitFailure;
  } catch (const timeopt::FileError& e) {
    std::cerr << "timeopt: " << e.what() << "\n";
    return kExitInvalidInput;
  } catch (const std::invalid_argument& e) {
    std::cerr << "timeopt: invalid input: " << e.what() << "\n";
    return kExitInvalidInput;
  } catch (const std::bad_alloc&) {
    // An input too large for this machine's memory (the library caps the sizes it knows of).
    std::cerr << "timeopt: invalid input: out of memory: the input is too large\n";
    return kExitInvalidInput;
  } catch (const std::exception& e) {
    std::cerr << "timeopt: error: " << e.what() << "\n";
    return kExitFailure;
  }
}
