#include "io/mjcf_compile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string_view>

namespace rigidtouch::io {
namespace {

bool StartsWith(const std::string& s, std::size_t at, const char* prefix) {
  return s.compare(at, std::strlen(prefix), prefix) == 0;
}

// markup at `pos` ('<') whose text may hold '<' or '>' that are not tags (a comment, CDATA, a
// processing instruction or a declaration): the offset just after it, std::string::npos when it is
// unterminated, or `pos` itself when `pos` starts a tag
std::size_t AfterMarkup(const std::string& xml, std::size_t pos) {
  const char* close = StartsWith(xml, pos, "<!--")        ? "-->"
                      : StartsWith(xml, pos, "<![CDATA[") ? "]]>"
                      : StartsWith(xml, pos, "<?")        ? "?>"
                      : StartsWith(xml, pos, "<!")        ? ">"
                                                          : nullptr;
  if (close == nullptr) return pos;
  const std::size_t end = xml.find(close, pos + 2);
  return end == std::string::npos ? end : end + std::strlen(close);
}

// the stack the compiler gets at most: 2^27 numbers (1 GB); a file needing more is refused by
// MuJoCo's own "Stack overflow" message
constexpr long kMaxStack = 1L << 27;

// attributes whose values are names, references or paths: text, even when it reads "inf"
bool IsTextAttribute(std::string_view name) {
  static constexpr std::string_view kText[] = {
      "name",       "class",    "childclass",   "body",       "body1",     "body2",
      "joint",      "joint1",   "joint2",       "geom",       "geom1",     "geom2",
      "site",       "site1",    "site2",        "mesh",       "material",  "texture",
      "hfield",     "tendon",   "tendon1",      "tendon2",    "actuator",  "target",
      "file",       "model",    "prefix",       "objname",    "refname",   "meshdir",
      "texturedir", "assetdir", "content_type", "slidersite", "cranksite", "jointinparent",
      "fileright",  "fileleft", "fileup",       "filedown",   "filefront", "fileback"};
  return std::find(std::begin(kText), std::end(kText), name) != std::end(kText);
}

// true when every whitespace-separated token of `value` is a number and one is not finite
bool HoldsNonFiniteNumber(std::string_view value) {
  bool any = false;
  bool non_finite = false;
  std::size_t pos = 0;
  while (pos < value.size()) {
    while (pos < value.size() && std::isspace(static_cast<unsigned char>(value[pos])) != 0) ++pos;
    std::size_t end = pos;
    while (end < value.size() && std::isspace(static_cast<unsigned char>(value[end])) == 0) ++end;
    if (end == pos) break;
    const std::string token(value.substr(pos, end - pos));
    char* parsed_end = nullptr;
    const double number = std::strtod(token.c_str(), &parsed_end);
    if (parsed_end != token.c_str() + token.size()) return false;  // not a list of numbers
    any = true;
    non_finite = non_finite || !std::isfinite(number);
    pos = end;
  }
  return any && non_finite;
}

// calls visit(element, attribute, value, offset) for each attribute of each start tag of `xml`,
// outside comments, CDATA, processing instructions and declarations, until it returns true
template <class Visit>
void VisitAttributes(const std::string& xml, Visit&& visit) {
  const auto is_name = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == ':' ||
           c == '.';
  };
  std::size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string::npos) {
    if (const std::size_t after = AfterMarkup(xml, pos); after != pos) {
      if (after == std::string::npos) return;  // unterminated: MuJoCo's parser says so
      pos = after;
      continue;
    }
    std::size_t i = pos + 1;
    const std::size_t name_begin = i;
    while (i < xml.size() && is_name(xml[i])) ++i;
    const std::string element = xml.substr(name_begin, i - name_begin);
    // attributes: name = "value" or 'value', up to the tag's end
    while (i < xml.size() && xml[i] != '>') {
      if (!is_name(xml[i])) {
        ++i;
        continue;
      }
      const std::size_t attr_begin = i;
      while (i < xml.size() && is_name(xml[i])) ++i;
      const std::string attribute = xml.substr(attr_begin, i - attr_begin);
      while (i < xml.size() && std::isspace(static_cast<unsigned char>(xml[i])) != 0) ++i;
      if (i >= xml.size() || xml[i] != '=') continue;
      ++i;
      while (i < xml.size() && std::isspace(static_cast<unsigned char>(xml[i])) != 0) ++i;
      if (i >= xml.size() || (xml[i] != '"' && xml[i] != '\'')) continue;
      const std::size_t value_end = xml.find(xml[i], i + 1);
      if (value_end == std::string::npos) return;  // unterminated: MuJoCo's parser says so
      const std::string_view value(xml.data() + i + 1, value_end - i - 1);
      if (visit(element, attribute, value, attr_begin)) return;
      i = value_end + 1;
    }
    pos = i;
  }
}

}  // namespace

NonFiniteValue FindNonFiniteValue(const std::string& xml) {
  NonFiniteValue found;
  VisitAttributes(xml, [&](const std::string& element, const std::string& attribute,
                           std::string_view value, std::size_t offset) {
    if (IsTextAttribute(attribute) || !HoldsNonFiniteNumber(value)) return false;
    found.element = element;
    found.attribute = attribute;
    found.value = std::string(value);
    found.line = 1 + static_cast<int>(std::count(xml.begin(), xml.begin() + offset, '\n'));
    return true;
  });
  return found;
}

std::vector<std::string> IncludedFiles(const std::string& xml) {
  std::vector<std::string> files;
  VisitAttributes(xml, [&](const std::string& element, const std::string& attribute,
                           std::string_view value, std::size_t) {
    if (element == "include" && attribute == "file") files.emplace_back(value);
    return false;
  });
  return files;
}

std::size_t RootEndTag(const std::string& xml) {
  std::size_t last = std::string::npos;
  std::size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string::npos) {
    if (const std::size_t after = AfterMarkup(xml, pos); after != pos) {
      if (after == std::string::npos) return last;  // unterminated: MuJoCo's parser says so
      pos = after;
      continue;
    }
    if (StartsWith(xml, pos, "</mujoco")) {
      const std::size_t after = pos + 8;
      if (after < xml.size() &&
          (xml[after] == '>' || std::isspace(static_cast<unsigned char>(xml[after])) != 0)) {
        last = pos;
      }
    }
    ++pos;
  }
  return last;
}

std::string WithMinimalSolverSizes(const std::string& xml, long nstack) {
  const std::size_t end = RootEndTag(xml);
  if (end == std::string::npos) return "";
  std::string out = xml.substr(0, end);
  out += "<size nconmax=\"0\" njmax=\"0\" nstack=\"" + std::to_string(nstack) + "\"/>";
  out.append(xml, end, std::string::npos);
  return out;
}

long InitialStackSize(const std::string& xml) {
  // a free body takes about four '<' (body, joint, geom, end tag) and six degrees of freedom;
  // the compiler's mj_setConst needs 12 numbers per degree of freedom and one per body
  const long elements = static_cast<long>(std::count(xml.begin(), xml.end(), '<'));
  return std::min(kMaxStack, 1000 + 100 * elements);
}

mjModel* CompileWithoutSolverSizes(const std::string& path, char* error, int error_size) {
  std::ifstream in(path, std::ios::binary);
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string name = std::filesystem::path(path).filename().string();
  // MuJoCo's virtual file system keeps names without their folder, of fewer than mjMAXVFSNAME
  // characters; a file it cannot hold is compiled from disk as it is
  if (!in || xml.empty() || xml.size() > (1u << 30) || name.empty() ||
      name.size() >= mjMAXVFSNAME || RootEndTag(xml) == std::string::npos) {
    return mj_loadXML(path.c_str(), nullptr, error, error_size);
  }
  auto vfs = std::make_unique<mjVFS>();
  for (long nstack = InitialStackSize(xml);; nstack = std::min(kMaxStack, 2 * nstack)) {
    const std::string text = WithMinimalSolverSizes(xml, nstack);
    mj_defaultVFS(vfs.get());
    if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(text.size())) != 0) {
      return mj_loadXML(path.c_str(), nullptr, error, error_size);
    }
    const int file = mj_findFileVFS(vfs.get(), name.c_str());
    std::memcpy(vfs->filedata[file], text.data(), text.size());
    // the path itself, so that includes and assets are found relative to the file as before
    mjModel* m = mj_loadXML(path.c_str(), vfs.get(), error, error_size);
    mj_deleteVFS(vfs.get());
    if (m != nullptr || nstack >= kMaxStack || std::strstr(error, "Stack overflow") == nullptr) {
      return m;
    }
  }
}

}  // namespace rigidtouch::io
