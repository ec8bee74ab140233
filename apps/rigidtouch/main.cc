// rigidtouch command-line tool: `rigidtouch <subcommand> [options]`. Errors go to stderr with a
// non-zero exit; with --json a subcommand prints exactly one JSON object on stdout. Exit codes
// (README, "Exit codes"): 0 success, 2 bad input (a file, field, value or output path), 3 an
// internal error, 4 an output file could not be written (disk full, file size limit), 5 serve's
// device did not answer, 128 + the signal's number when SIGINT (130) or SIGTERM (143) stopped
// long work. A malformed command line is bad input too: status 2, the same prefix.
#include <algorithm>
#include <exception>
#include <iostream>
#include <string>

#include "base/progress.h"
#include "cli_errors.h"
#include "io/output_file.h"
#include "rigidtouch/command.h"
#include "rigidtouch/types.h"

namespace rigidtouch::cli {

std::vector<Command>& Commands() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace rigidtouch::cli

int main(int argc, char** argv) {
  CLI::App app{"rigidtouch: haptic rendering of rigid contact with impulse trains"};
  app.set_version_flag("--version", RIGIDTOUCH_VERSION);
  app.require_subcommand(1);
  // past `ulimit -f` a write then fails with EFBIG, which the writers report (exit 4)
  rigidtouch::io::IgnoreFileSizeSignal();
  // by name, so that help and errors list them alike whatever the link order
  auto& commands = rigidtouch::cli::Commands();
  std::sort(commands.begin(), commands.end(),
            [](const auto& a, const auto& b) { return a.name < b.name; });
  for (const auto& command : commands) command.add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::RuntimeError& e) {
    // a subcommand that printed its own message and chose its status (serve: 5)
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    // CLI11 would exit with its own code (above 100) and no prefix: one voice for every error
    const std::string message = rigidtouch::cli::ExplainParseError(app, e, argc, argv);
    const std::string path = rigidtouch::cli::SubcommandPath(app, argc, argv);
    std::cerr << "rigidtouch: error: " << message << "\n"
              << "Run `" << argv[0] << (path.empty() ? std::string() : " " + path)
              << " --help` for the " << (path.empty() ? "subcommands" : "options") << ".\n";
    return 2;
  } catch (const rigidtouch::io::OutputError& e) {
    std::cerr << "rigidtouch: error: " << e.what() << "\n";
    return 4;
  } catch (const rigidtouch::Error& e) {
    std::cerr << "rigidtouch: error: " << e.what() << "\n";
    return 2;
  } catch (const rigidtouch::Interrupted& e) {
    // SIGINT or SIGTERM during long work, which kept what it finished (the message says what)
    std::cerr << "rigidtouch: interrupted: " << e.what() << "\n";
    return 128 + e.signal();
  } catch (const std::exception& e) {
    std::cerr << "rigidtouch: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
