// The progress of long subcommands on stderr, and their stop on SIGINT / SIGTERM (command.h).
#include <unistd.h>

#include <iostream>
#include <memory>
#include <string>

#include "command.h"
#include "loop/stop_signal.h"

namespace rigidtouch::cli {

std::unique_ptr<Progress> StartProgress(std::string task, bool quiet) {
  const std::atomic<bool>& stop = loop::InstallStopSignalHandlers();
  Progress::Options options;
  options.enabled = !quiet;
  options.terminal = ::isatty(STDERR_FILENO) == 1;
  return std::make_unique<Progress>(std::cerr, std::move(task), options, &stop,
                                    &loop::StopSignalNumber());
}

void AddQuietFlag(CLI::App& app, bool& quiet) {
  app.add_flag("--quiet", quiet,
               "print no progress on stderr (by default a line every 2 s once the work has run "
               "2 s; a bar on a terminal)");
}

}  // namespace rigidtouch::cli
