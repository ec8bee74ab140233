// libFuzzer: the MJCF loader's checks (bounds, overlap, supported types) on small fuzzed scenes,
// compiled by MuJoCo from a file. Bad input must be a rigidtouch::Error.
#include <mujoco/mujoco.h>

#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_util.h"
#include "rigidtouch/rigidtouch.h"

namespace {
void Quiet(const char*) {}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;  // small scenes keep MuJoCo's compile fast
  mju_user_warning = Quiet;   // no MUJOCO_LOG.TXT and no console noise
  const std::string path = rigidtouch::fuzz::InputFile(data, size, ".xml");
  try {
    rigidtouch::LoadModel(path, {});
  } catch (const rigidtouch::Error&) {
  }
  return 0;
}
