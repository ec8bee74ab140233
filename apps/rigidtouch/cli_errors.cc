#include "cli_errors.h"

#include <algorithm>
#include <numeric>

namespace rigidtouch::cli {
namespace {

// the subcommands of `app`, by name
std::vector<std::string> SubcommandNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    names.push_back(sub->get_name());
  }
  return names;
}

// every long flag of `app` ("--name"), and --help
std::vector<std::string> FlagNames(const CLI::App& app) {
  std::vector<std::string> names = {"--help"};
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
  }
  return names;
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// what a value of CLI11's type name is, for people
std::string TypeInWords(const std::string& type) {
  if (type.find("FLOAT") != std::string::npos) return "a number";
  if (type.find("UINT") != std::string::npos) return "a whole number, 0 or more";
  if (type.find("INT") != std::string::npos) return "a whole number";
  return "a value of type " + type;
}

// "Could not convert: NAME = VALUES": the flag and the values as written, in the user's words
std::string ExplainConversion(const CLI::App& sub, const std::string& what) {
  const std::string tag = "Could not convert: ";
  if (what.rfind(tag, 0) != 0) return "";
  const std::size_t eq = what.find(" = ", tag.size());
  if (eq == std::string::npos) return "";
  const std::string name = what.substr(tag.size(), eq - tag.size());
  const std::string values = what.substr(eq + 3);
  const CLI::Option* option = sub.get_option_no_throw(name);
  if (option == nullptr) return "";
  std::string message = name + ": '" + values + "' is not " + TypeInWords(option->get_type_name());
  if (!option->get_description().empty()) message += " (" + option->get_description() + ")";
  return message;
}

}  // namespace

int EditDistance(std::string_view a, std::string_view b) {
  std::vector<int> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    int diagonal = row[0];
    row[0] = static_cast<int>(i);
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const int above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string Closest(std::string_view word, const std::vector<std::string>& names) {
  std::string best;
  int best_distance = 3;  // at most 2
  for (const std::string& name : names) {
    const int d = EditDistance(word, name);
    if (d < best_distance && 2 * d < static_cast<int>(word.size())) {
      best = name;
      best_distance = d;
    }
  }
  return best;
}

std::string SubcommandPath(const CLI::App& app, int argc, char** argv) {
  std::string path;
  const CLI::App* sub = &app;
  for (int i = 1; i < argc; ++i) {
    const std::vector<std::string> names = SubcommandNames(*sub);
    if (std::find(names.begin(), names.end(), argv[i]) == names.end()) break;
    sub = sub->get_subcommand(argv[i]);
    path += (path.empty() ? "" : " ") + std::string(argv[i]);
  }
  return path;
}

std::string ExplainParseError(const CLI::App& app, const CLI::ParseError& e, int argc,
                              char** argv) {
  const std::vector<std::string> subcommands = SubcommandNames(app);
  if (argc < 2 || argv[1][0] == '-') return e.what();
  const std::string word = argv[1];
  if (std::find(subcommands.begin(), subcommands.end(), word) == subcommands.end()) {
    const std::string near = Closest(word, subcommands);
    return "unknown subcommand '" + word + "'" +
           (near.empty() ? std::string() : " (did you mean '" + near + "'?)") +
           "; valid: " + JoinNames(subcommands);
  }
  // the innermost subcommand named (study simulate), and where its flags begin
  const CLI::App* sub = app.get_subcommand(word);
  std::string path = word;
  int first = 2;
  while (first < argc) {
    const std::vector<std::string> nested = SubcommandNames(*sub);
    if (std::find(nested.begin(), nested.end(), argv[first]) == nested.end()) break;
    sub = sub->get_subcommand(argv[first]);
    path += std::string(" ") + argv[first];
    ++first;
  }
  // the first flag the subcommand does not have (a typo), wherever CLI11's error came from
  const std::vector<std::string> flags = FlagNames(*sub);
  for (int i = first; i < argc; ++i) {
    const std::string token = argv[i];
    if (token == "--") break;
    if (token.rfind("--", 0) != 0) continue;
    const std::string flag = token.substr(0, token.find('='));
    if (std::find(flags.begin(), flags.end(), flag) != flags.end()) continue;
    const std::string near = Closest(flag, flags);
    return path + ": unknown flag " + flag +
           (near.empty() ? std::string() : "; did you mean " + near + "?");
  }
  const std::string conversion = ExplainConversion(*sub, e.what());
  return conversion.empty() ? e.what() : path + ": " + conversion;
}

}  // namespace rigidtouch::cli
