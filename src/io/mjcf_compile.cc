#include "io/mjcf_compile.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>

namespace rigidtouch::io {
namespace {

bool StartsWith(const std::string& s, std::size_t at, const char* prefix) {
  return s.compare(at, std::strlen(prefix), prefix) == 0;
}

// the stack the compiler gets at most: 2^27 numbers (1 GB); a file needing more is refused by
// MuJoCo's own "Stack overflow" message
constexpr long kMaxStack = 1L << 27;

}  // namespace

std::size_t RootEndTag(const std::string& xml) {
  std::size_t last = std::string::npos;
  std::size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string::npos) {
    // markup whose text may hold '<' or '>' that are not tags
    const char* close = StartsWith(xml, pos, "<!--")        ? "-->"
                        : StartsWith(xml, pos, "<![CDATA[") ? "]]>"
                        : StartsWith(xml, pos, "<?")        ? "?>"
                        : StartsWith(xml, pos, "<!")        ? ">"
                                                            : nullptr;
    if (close != nullptr) {
      const std::size_t end = xml.find(close, pos + 2);
      if (end == std::string::npos) return last;  // unterminated: MuJoCo's parser says so
      pos = end + std::strlen(close);
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
