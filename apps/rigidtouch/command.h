// Subcommand registration: each apps/rigidtouch/<name>.cc registers itself with a static
// CommandRegistrar, so adding a subcommand touches only its own file.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "base/progress.h"

namespace rigidtouch::cli {

/// Adds a subcommand (options and callback) to the root application.
using CommandFactory = void (*)(CLI::App& root);

/// A subcommand's name and the factory that adds it.
struct Command {
  std::string_view name;
  CommandFactory add;
};

/// All registered subcommands, in registration order (static initialisation: the order of the
/// files in the link, which a unity build changes; the tool adds them sorted by name).
std::vector<Command>& Commands();

/// Exit status of `serve` and `view` when the device never answered (docs/device-protocol.md,
/// Watchdogs); 2 is any other error (bad parameter, e.g. a stiffness the device cannot display).
inline constexpr int kExitNoDevice = 5;

/// `--connect replay:LOG`: a recorded session's handle motion as the device.
inline constexpr std::string_view kReplayPrefix = "replay:";

/// Progress of a long subcommand's work on stderr: a bar when stderr is a terminal, a line at most
/// every 2 s otherwise, nothing in the first 2 s and nothing with `quiet` (--quiet). Installs the
/// SIGINT and SIGTERM handlers whose request the work checks: it stops cleanly, keeping what it
/// finished, and throws Interrupted, which the tool reports with exit status 128 + the signal.
std::unique_ptr<Progress> StartProgress(std::string task, bool quiet);

/// Adds `--quiet` (no progress on stderr) to a long subcommand.
void AddQuietFlag(CLI::App& app, bool& quiet);

/// Registers a subcommand at static-initialisation time.
struct CommandRegistrar {
  CommandRegistrar(std::string_view name, CommandFactory factory) {
    Commands().push_back({name, factory});
  }
};

}  // namespace rigidtouch::cli
