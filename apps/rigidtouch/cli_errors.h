// A malformed command line in the user's words: an unknown subcommand or flag with the closest
// valid one, a value that does not convert with the flag and the type it takes.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace rigidtouch::cli {

/// Levenshtein distance between `a` and `b` (insertions, deletions and substitutions).
int EditDistance(std::string_view a, std::string_view b);

/// The name of `names` closest to `word`, if it is close enough to be a typo of it (a distance of
/// at most 2, and less than half of the word's length); empty otherwise.
std::string Closest(std::string_view word, const std::vector<std::string>& names);

/// The subcommands named at the start of `argv` ("study simulate"), empty when argv[1] names none.
std::string SubcommandPath(const CLI::App& app, int argc, char** argv);

/// The message for a parse error of `app` on the command line `argv` (without the "rigidtouch:
/// error: " prefix): what was wrong, named as the user wrote it, with a suggestion where one fits.
std::string ExplainParseError(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv);

}  // namespace rigidtouch::cli
