// rigidtouch command-line tool: `rigidtouch <subcommand> [options]`. Errors go to stderr with a
// non-zero exit; with --json a subcommand prints exactly one JSON object on stdout.
#include <exception>
#include <iostream>

#include "rigidtouch/command.h"
#include "rigidtouch/types.h"

namespace rigidtouch::cli {

std::vector<CommandFactory>& Commands() {
  static std::vector<CommandFactory> commands;
  return commands;
}

}  // namespace rigidtouch::cli

int main(int argc, char** argv) {
  CLI::App app{"rigidtouch: haptic rendering of rigid contact with impulse trains"};
  app.set_version_flag("--version", RIGIDTOUCH_VERSION);
  app.require_subcommand(1);
  for (auto factory : rigidtouch::cli::Commands()) factory(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const rigidtouch::Error& e) {
    std::cerr << "rigidtouch: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rigidtouch: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
