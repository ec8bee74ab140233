// The pre-shared key of the UDP device link and its files (docs/device-protocol.md, "Key
// files"). A key file is 64 hexadecimal digits and a newline, mode 0600, owned by its user.
#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "device/udp_protocol.h"
#include "rigidtouch/bridge.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

constexpr std::size_t kHexDigits = 2 * kDeviceKeyBytes;
// longest file we read: the key, a newline and some slack for CRLF or trailing blanks
constexpr std::size_t kMaxKeyFileBytes = 256;

[[noreturn]] void ThrowSystem(const std::string& what, const std::string& path, int error) {
  throw Error("device key file " + path + ": " + what + ": " + std::strerror(error));
}

std::string ToHex(const DeviceKey& key) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  for (const std::uint8_t byte : key.bytes) {
    hex.push_back(kDigits[byte >> 4]);
    hex.push_back(kDigits[byte & 0xf]);
  }
  return hex;
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// writes all of `text` to a file created exclusively with mode 0600; throws on any failure
void WriteExclusive(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    ThrowSystem("cannot create", path, errno);
  }
  // the mode given to open is reduced by the umask; fchmod makes it exactly 0600
  bool ok = ::fchmod(fd, 0600) == 0;
  std::size_t written = 0;
  while (ok && written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) written += static_cast<std::size_t>(n);
  }
  ok = ok && ::fsync(fd) == 0;
  const int error = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(path.c_str());
    ThrowSystem("cannot write", path, error);
  }
}

void CreateParentDirectory(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code error;
  std::filesystem::create_directories(parent, error);
  if (error) {
    throw Error("device key file " + path + ": cannot create its folder " + parent.string() + ": " +
                error.message());
  }
  // only a folder we may have just made is narrowed; an existing one keeps its mode
  ::chmod(parent.c_str(), 0700);
}

}  // namespace

DeviceKey GenerateDeviceKey() {
  InitSodium();
  DeviceKey key;
  randombytes_buf(key.bytes.data(), key.bytes.size());
  return key;
}

std::string DefaultDeviceKeyPath() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  // the XDG base directory specification ignores relative paths
  if (xdg != nullptr && xdg[0] == '/') return std::string(xdg) + "/rigidtouch/device.key";
  const char* home = std::getenv("HOME");
  if (home != nullptr && home[0] == '/')
    return std::string(home) + "/.config/rigidtouch/device.key";
  throw Error(
      "no default device key file: neither XDG_CONFIG_HOME nor HOME is an absolute path; "
      "pass a key file (--key FILE, created with `rigidtouch keygen --out FILE`)");
}

DeviceKey LoadDeviceKey(const std::string& path) {
  // O_NOFOLLOW: the checks below are about the file itself, not a link to it
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    if (error == ENOENT) {
      throw Error("device key file " + path +
                  " does not exist; create one with `rigidtouch keygen --out " + path + "`");
    }
    ThrowSystem("cannot open", path, error);
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int error = errno;
    ::close(fd);
    ThrowSystem("cannot stat", path, error);
  }
  const auto refuse = [&](const std::string& why) {
    ::close(fd);
    throw Error("device key file " + path + ": " + why);
  };
  if (!S_ISREG(info.st_mode)) refuse("not a regular file");
  if (info.st_uid != ::geteuid()) {
    refuse("owned by uid " + std::to_string(info.st_uid) + ", not by this user (uid " +
           std::to_string(::geteuid()) + "); refusing to trust it");
  }
  if ((info.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(info.st_mode & 07777));
    refuse(std::string("permissions ") + mode +
           " are too open: group or others may read or write it, and anyone who reads the key "
           "can command the device; run `chmod 600 " +
           path + "`");
  }
  char text[kMaxKeyFileBytes + 1];
  std::size_t length = 0;
  for (;;) {
    const ssize_t n = ::read(fd, text + length, sizeof text - length);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      ThrowSystem("cannot read", path, error);
    }
    if (n == 0 || length + static_cast<std::size_t>(n) == sizeof text) {
      length += static_cast<std::size_t>(n);
      break;
    }
    length += static_cast<std::size_t>(n);
  }
  ::close(fd);
  const auto malformed = [&] {
    sodium_memzero(text, sizeof text);
    throw Error("device key file " + path + " is malformed: expected " +
                std::to_string(kHexDigits) + " hexadecimal digits (rigidtouch keygen writes one)");
  };
  if (length < kHexDigits || length > kMaxKeyFileBytes) malformed();
  for (std::size_t i = kHexDigits; i < length; ++i) {
    if (text[i] != '\n' && text[i] != '\r' && text[i] != ' ' && text[i] != '\t') malformed();
  }
  DeviceKey key;
  for (std::size_t i = 0; i < kDeviceKeyBytes; ++i) {
    const int high = HexValue(text[2 * i]);
    const int low = HexValue(text[2 * i + 1]);
    if (high < 0 || low < 0) malformed();
    key.bytes[i] = static_cast<std::uint8_t>(16 * high + low);
  }
  sodium_memzero(text, sizeof text);
  return key;
}

void WriteDeviceKey(const std::string& path, const DeviceKey& key, bool overwrite) {
  CreateParentDirectory(path);
  // the key goes to a private temporary file first, so no reader ever sees half a key
  const std::string temporary = path + ".tmp" + std::to_string(::getpid());
  ::unlink(temporary.c_str());
  WriteExclusive(temporary, ToHex(key) + "\n");
  // rename replaces; link refuses atomically when the file exists
  const int status = overwrite ? ::rename(temporary.c_str(), path.c_str())
                               : ::link(temporary.c_str(), path.c_str());
  const int error = errno;
  ::unlink(temporary.c_str());
  if (status == 0) return;
  if (error == EEXIST) {
    throw Error("device key file " + path +
                " already exists; refusing to overwrite it (--force replaces it)");
  }
  ThrowSystem("cannot write", path, error);
}

DeviceKey ResolveDeviceKey(const std::optional<DeviceKey>& key, const std::string& key_file) {
  InitSodium();
  if (key) return *key;
  if (!key_file.empty()) return LoadDeviceKey(key_file);
  const std::string path = DefaultDeviceKeyPath();
  // first use: one user on one host needs no configuration
  if (::access(path.c_str(), F_OK) != 0 && errno == ENOENT) {
    try {
      WriteDeviceKey(path, GenerateDeviceKey(), /*overwrite=*/false);
    } catch (const Error&) {
      // another process created it first; the load below reads theirs or reports the problem
      if (::access(path.c_str(), F_OK) != 0) throw;
    }
  }
  return LoadDeviceKey(path);
}

}  // namespace rigidtouch::device
