#include "bench/engine.h"

#include <utility>

namespace rigidtouch::bench {

std::vector<EngineEntry>& Engines() {
  static std::vector<EngineEntry> engines;
  return engines;
}

EngineRegistrar::EngineRegistrar(std::string name, EngineFactory make) {
  Engines().push_back(EngineEntry{std::move(name), make});
}

}  // namespace rigidtouch::bench
