// Subcommand registration: each apps/rigidtouch/<name>.cc registers itself with a static
// CommandRegistrar, so adding a subcommand touches only its own file.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

namespace rigidtouch::cli {

/// Adds a subcommand (options and callback) to the root application.
using CommandFactory = void (*)(CLI::App& root);

/// All registered subcommands, in registration order.
std::vector<CommandFactory>& Commands();

/// Registers a subcommand at static-initialisation time.
struct CommandRegistrar {
  explicit CommandRegistrar(CommandFactory factory) { Commands().push_back(factory); }
};

}  // namespace rigidtouch::cli
