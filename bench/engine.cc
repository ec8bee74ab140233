#include "bench/engine.h"

#include <algorithm>
#include <utility>

namespace rigidtouch::bench {

double Engine::BodyPenetration_m(std::string_view body) const {
  throw Error("engine " + std::string(Name()) + " cannot report the penetration of body '" +
              std::string(body) + "'");
}

double Engine::JointPosition(std::string_view joint) const {
  throw Error("engine " + std::string(Name()) + " cannot report the position of joint '" +
              std::string(joint) + "'");
}

std::vector<EngineEntry>& Engines() {
  static std::vector<EngineEntry> engines;
  return engines;
}

EngineRegistrar::EngineRegistrar(std::string name, EngineFactory make) {
  std::vector<EngineEntry>& engines = Engines();
  engines.push_back(EngineEntry{std::move(name), make});
  // static initialisation order follows the link order; sort for a stable run order and
  // table layout: the reference engine first, then the peers by name
  std::sort(engines.begin(), engines.end(), [](const EngineEntry& a, const EngineEntry& b) {
    const bool a_reference = a.name == kReferenceEngine;
    const bool b_reference = b.name == kReferenceEngine;
    if (a_reference != b_reference) return a_reference;
    return a.name < b.name;
  });
}

}  // namespace rigidtouch::bench
