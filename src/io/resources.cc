#include "io/resources.h"

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "rigidtouch/types.h"

namespace rigidtouch::io {

std::string ShippedFile(const std::string& relative) {
  std::vector<std::string> roots;
  if (const char* env = std::getenv("RIGIDTOUCH_DATA_DIR")) roots.emplace_back(env);
  roots.emplace_back(RIGIDTOUCH_DATA_DIR);
  roots.emplace_back(RIGIDTOUCH_SOURCE_DIR);
  std::string tried;
  for (const std::string& root : roots) {
    const std::filesystem::path p = std::filesystem::path(root) / relative;
    std::error_code ec;
    if (std::filesystem::exists(p, ec)) return p.string();
    tried += (tried.empty() ? "" : ", ") + p.string();
  }
  throw Error("shipped file '" + relative + "' not found (looked in: " + tried +
              "); set RIGIDTOUCH_DATA_DIR to the folder holding scenes/ and python/");
}

}  // namespace rigidtouch::io
