#pragma once

// Subcommands of the `timeopt` command-line tool. Each Register* adds its subcommand to the app and
// sets `run` to the function that executes it after parsing; the function returns the exit code.
// Exit codes: 0 success, 2 invalid input or unreadable file, 3 infeasible, 1 anything else.

#include <functional>

#include <CLI/CLI.hpp>

namespace timeopt::cli {

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitInvalidInput = 2;
constexpr int kExitInfeasible = 3;

using Runner = std::function<int()>;

void RegisterCurveCommand(CLI::App& app, Runner& run);
void RegisterTemporalCommand(CLI::App& app, Runner& run);
void RegisterWaypointsCommand(CLI::App& app, Runner& run);
void RegisterMapCommand(CLI::App& app, Runner& run);
void RegisterPlanCommand(CLI::App& app, Runner& run);
void RegisterConicCommand(CLI::App& app, Runner& run);
void RegisterSimulateCommand(CLI::App& app, Runner& run);

}  // namespace timeopt::cli
