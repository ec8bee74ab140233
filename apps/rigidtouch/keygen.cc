// `rigidtouch keygen`: writes a fresh random pre-shared key for the UDP device link
// (docs/device-protocol.md, "Key files"), mode 0600, never over an existing key unless told.
#include <iostream>
#include <nlohmann/json.hpp>

#include "command.h"
#include "rigidtouch/bridge.h"

namespace rigidtouch::cli {
namespace {

struct KeygenFlags {
  std::string out;  // empty: the per-user default key file
  bool force = false;
  bool json = false;
};

void RunKeygen(const KeygenFlags& f) {
  const std::string path = f.out.empty() ? device::DefaultDeviceKeyPath() : f.out;
  device::WriteDeviceKey(path, device::GenerateDeviceKey(), f.force);
  // the key itself is never printed: terminals and logs keep what they show
  if (f.json) {
    std::cout << nlohmann::json{{"key_file", path}}.dump() << "\n";
  } else {
    std::cout << "wrote a new device key to " << path
              << " (mode 0600); copy it to the other machine and pass it with --key\n";
  }
}

void RegisterKeygen(CLI::App& root) {
  auto f = std::make_shared<KeygenFlags>();
  CLI::App* app = root.add_subcommand(
      "keygen", "write a fresh random key for the UDP device link (device-sim, serve --key)");
  app->add_option("--out", f->out,
                  "key file to write; default: the per-user key "
                  "($XDG_CONFIG_HOME/rigidtouch/device.key or ~/.config/rigidtouch/device.key)");
  app->add_flag("--force", f->force, "replace an existing key file");
  app->add_flag("--json", f->json, "print one JSON object");
  app->callback([f] { RunKeygen(*f); });
}

const CommandRegistrar keygen_registrar("keygen", &RegisterKeygen);

}  // namespace
}  // namespace rigidtouch::cli
