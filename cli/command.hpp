#pragma once
// A subcommand as main.cpp sees it. Each <command>.hpp declares a function
// add_<command>_command(CLI::App&) that declares the subcommand and its flags
// and returns a Command, so main registers a command in one line and never
// needs to know its flags.

#include <CLI/CLI.hpp>

#include <functional>

namespace shatter::cli {

/// A subcommand declared on the app: `app->parsed()` says whether the command
/// line named it, and `run` runs it with the flags CLI11 parsed into it. `run`
/// returns the exit code of a success (ExitCode::ok) and reports any failure by
/// throwing, for errors.hpp's failure_of to map.
struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

}  // namespace shatter::cli
