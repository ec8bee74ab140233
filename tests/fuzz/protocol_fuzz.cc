// libFuzzer: the study protocol reader (strict JSON, then ParseProtocol and its plan) on
// arbitrary bytes. Bad input must be a rigidtouch::Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/strict_json.h"
#include "rigidtouch/types.h"
#include "study/plan.h"
#include "study/protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const nlohmann::json document =
        rigidtouch::io::ParseJsonText(text, rigidtouch::io::JsonSource("fuzz.json"));
    const rigidtouch::study::Protocol protocol =
        rigidtouch::study::ParseProtocol(document, "fuzz.json");
    rigidtouch::study::MakePlan(protocol, 1);
    rigidtouch::study::ProtocolHash(protocol);
  } catch (const rigidtouch::Error&) {
  }
  return 0;
}
