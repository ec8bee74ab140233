// libFuzzer: the study log reader (ParseLog) and the validator shared by resume and analyze
// (ValidateLog) on arbitrary bytes. Bad input must be a rigidtouch::Error.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "rigidtouch/types.h"
#include "study/log.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const rigidtouch::study::LogContents contents =
        rigidtouch::study::ParseLog(bytes, "fuzz.jsonl");
    if (!contents.records.empty()) rigidtouch::study::ValidateLog(contents.records, "fuzz.jsonl");
  } catch (const rigidtouch::Error&) {
  }
  return 0;
}
