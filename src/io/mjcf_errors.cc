#include "io/mjcf_errors.h"

#include <unistd.h>

#include <cstdio>
#include <regex>

namespace rigidtouch::io {
namespace {

std::string Trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(first, last - first + 1));
}

// "QH6421" from Qhull's report, or empty
std::string QhullCode(std::string_view report) {
  std::match_results<std::string_view::const_iterator> m;
  static const std::regex code("QH[0-9]{4}");
  if (std::regex_search(report.begin(), report.end(), m, code)) return m.str();
  return "";
}

}  // namespace

std::string TranslateCompileError(std::string_view error, std::string_view qhull_report) {
  std::string text = Trim(error);
  if (text.rfind("Error:", 0) == 0) text = Trim(std::string_view(text).substr(6));
  if (text.rfind("XML Error:", 0) == 0) text = Trim(std::string_view(text).substr(10));
  // MuJoCo's trailer on the line after the reason: the object or element and its line
  std::string reason = text, where;
  if (const auto newline = text.find('\n'); newline != std::string::npos) {
    reason = Trim(std::string_view(text).substr(0, newline));
    const std::string trailer = Trim(std::string_view(text).substr(newline + 1));
    std::smatch m;
    static const std::regex object("Object name = ([^,]*), id = [0-9-]+(?:, line = ([0-9]+))?");
    static const std::regex element(
        "Element (?:name '([^']*)' id [0-9-]+|'([^']*)'), line ([0-9]+)");
    if (std::regex_search(trailer, m, object)) {
      where = "'" + m[1].str() + "'" + (m[2].matched ? " (line " + m[2].str() + ")" : "");
    } else if (std::regex_search(trailer, m, element)) {
      where = (m[1].matched ? "'" + m[1].str() + "'" : "<" + m[2].str() + ">") + " (line " +
              m[3].str() + ")";
    } else if (!trailer.empty()) {
      where = trailer;
    }
  }
  if (reason == "qhull error" || !QhullCode(qhull_report).empty()) {
    const std::string code = QhullCode(qhull_report);
    return "mesh " + (where.empty() ? std::string("(unnamed)") : where) +
           ": its convex hull cannot be built: the vertices are all the same point, or lie on one "
           "line or one plane (a mesh needs four vertices that span a volume)" +
           (code.empty() ? "" : " [qhull " + code + "]");
  }
  if (where.empty()) return reason;
  return where.front() == '<' || where.front() == '\'' ? "element " + where + ": " + reason
                                                       : reason + " (" + where + ")";
}

std::string WithStderrCaptured(const std::function<void()>& compile) {
  std::FILE* sink = std::tmpfile();
  const int saved = sink != nullptr ? ::dup(STDERR_FILENO) : -1;
  if (saved < 0 || ::dup2(::fileno(sink), STDERR_FILENO) < 0) {
    if (saved >= 0) ::close(saved);
    if (sink != nullptr) std::fclose(sink);
    compile();
    return "";
  }
  // restored whatever `compile` throws
  struct Restore {
    int saved;
    ~Restore() {
      std::fflush(stderr);
      ::dup2(saved, STDERR_FILENO);
      ::close(saved);
    }
  };
  {
    const Restore restore{saved};
    compile();
  }
  std::string captured(4096, '\0');
  std::rewind(sink);
  captured.resize(std::fread(captured.data(), 1, captured.size(), sink));
  std::fclose(sink);
  return captured;
}

}  // namespace rigidtouch::io
