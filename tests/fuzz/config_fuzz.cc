// libFuzzer: the JSON config reader (io::ApplyConfigFile) on arbitrary bytes. Bad input must be a
// rigidtouch::Error, never a crash, a leak or another exception.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_util.h"
#include "io/config.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rigidtouch::fuzz::InputFile(data, size, ".json");
  rigidtouch::LoadOptions options;
  try {
    rigidtouch::io::ApplyConfigFile(path, options);
  } catch (const rigidtouch::Error&) {
  }
  return 0;
}
