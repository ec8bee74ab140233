#include "base/names.h"

namespace rigidtouch::text {
namespace {

// in enum order: the index of a name is its enumerator
const std::vector<std::string> kRendererNames = {"penalty", "impulse", "train", "event"};
const std::vector<std::string> kCouplingNames = {"none", "direct", "virtual"};

const char* NameOf(const std::vector<std::string>& names, int index) {
  return index >= 0 && index < static_cast<int>(names.size()) ? names[index].c_str() : "unknown";
}

}  // namespace

const std::vector<std::string>& RendererNames() {
  return kRendererNames;
}

const char* RendererName(RendererKind kind) {
  return NameOf(kRendererNames, static_cast<int>(kind));
}

const std::vector<std::string>& CouplingNames() {
  return kCouplingNames;
}

const char* CouplingName(Coupling coupling) {
  return NameOf(kCouplingNames, static_cast<int>(coupling));
}

}  // namespace rigidtouch::text
