// Key files of the UDP device link: created 0600, refused when group or others may read them,
// never overwritten unless asked. Every test works in its own temporary folder and points
// XDG_CONFIG_HOME and HOME there, so the real home directory is never touched.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "rigidtouch/bridge.h"
#include "rigidtouch/types.h"

namespace rigidtouch::device {
namespace {

namespace fs = std::filesystem;

unsigned ModeOf(const fs::path& path) {
  struct stat info {};
  EXPECT_EQ(::stat(path.c_str(), &info), 0) << path;
  return info.st_mode & 07777;
}

std::string Contents(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string MessageOf(const auto& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

// a private folder, with XDG_CONFIG_HOME and HOME pointing into it for the test's duration
class KeyFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigidtouch_key_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    Save("XDG_CONFIG_HOME", &saved_xdg_);
    Save("HOME", &saved_home_);
    ::setenv("XDG_CONFIG_HOME", (dir_ / "xdg").c_str(), 1);
    ::setenv("HOME", (dir_ / "home").c_str(), 1);
  }
  void TearDown() override {
    Restore("XDG_CONFIG_HOME", saved_xdg_);
    Restore("HOME", saved_home_);
    fs::remove_all(dir_);
  }
  static void Save(const char* name, std::optional<std::string>* saved) {
    const char* value = std::getenv(name);
    if (value != nullptr) *saved = value;
  }
  static void Restore(const char* name, const std::optional<std::string>& saved) {
    if (saved) {
      ::setenv(name, saved->c_str(), 1);
    } else {
      ::unsetenv(name);
    }
  }

  fs::path dir_;
  std::optional<std::string> saved_xdg_;
  std::optional<std::string> saved_home_;
};

TEST_F(KeyFileTest, WrittenWithMode0600AndReadBack) {
  const fs::path path = dir_ / "keys" / "a.key";
  const DeviceKey key = GenerateDeviceKey();
  WriteDeviceKey(path.string(), key, /*overwrite=*/false);
  EXPECT_EQ(ModeOf(path), 0600u);
  EXPECT_EQ(ModeOf(path.parent_path()), 0700u);
  const std::string text = Contents(path);
  ASSERT_EQ(text.size(), 65u);
  EXPECT_EQ(text.back(), '\n');
  EXPECT_EQ(LoadDeviceKey(path.string()), key);
  EXPECT_NE(GenerateDeviceKey(), key);  // random: 2^-256 chance of a false failure
}

TEST_F(KeyFileTest, RefusesToOverwriteUnlessAsked) {
  const fs::path path = dir_ / "a.key";
  const DeviceKey first = GenerateDeviceKey();
  WriteDeviceKey(path.string(), first, false);
  const std::string message =
      MessageOf([&] { WriteDeviceKey(path.string(), GenerateDeviceKey(), false); });
  EXPECT_NE(message.find("already exists"), std::string::npos) << message;
  EXPECT_EQ(LoadDeviceKey(path.string()), first) << "the existing key is untouched";
  const DeviceKey second = GenerateDeviceKey();
  WriteDeviceKey(path.string(), second, /*overwrite=*/true);
  EXPECT_EQ(LoadDeviceKey(path.string()), second);
  EXPECT_EQ(ModeOf(path), 0600u);
  // no temporary file is left behind
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(KeyFileTest, GroupOrOtherAccessIsRefusedLikeSsh) {
  const fs::path path = dir_ / "a.key";
  WriteDeviceKey(path.string(), GenerateDeviceKey(), false);
  for (const fs::perms extra : {fs::perms::group_read, fs::perms::others_read,
                                fs::perms::group_write, fs::perms::others_exec}) {
    fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write | extra);
    const std::string message = MessageOf([&] { LoadDeviceKey(path.string()); });
    EXPECT_NE(message.find("too open"), std::string::npos) << message;
    EXPECT_NE(message.find("chmod 600 " + path.string()), std::string::npos) << message;
  }
  fs::permissions(path, fs::perms::owner_read);
  EXPECT_NO_THROW(LoadDeviceKey(path.string())) << "0400 is private too";
}

TEST_F(KeyFileTest, MalformedMissingAndLinkedFilesAreRefused) {
  const fs::path path = dir_ / "a.key";
  for (const std::string& text :
       {std::string(""), std::string(63, 'a') + "\n", std::string(64, 'g') + "\n",
        std::string(64, 'a') + "x\n", std::string(128, 'a')}) {
    fs::remove(path);
    std::ofstream(path) << text;
    fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
    const std::string message = MessageOf([&] { LoadDeviceKey(path.string()); });
    EXPECT_NE(message.find("malformed"), std::string::npos) << text << ": " << message;
  }
  fs::remove(path);
  std::ofstream(path) << std::string(64, 'A') << "\r\n";
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(LoadDeviceKey(path.string()).bytes[0], 0xaa) << "upper case and CRLF are fine";

  const std::string missing = (dir_ / "none.key").string();
  const std::string message = MessageOf([&] { LoadDeviceKey(missing); });
  EXPECT_NE(message.find("rigidtouch keygen --out " + missing), std::string::npos) << message;

  fs::create_symlink(path, dir_ / "link.key");
  EXPECT_THROW(LoadDeviceKey((dir_ / "link.key").string()), Error);
}

TEST_F(KeyFileTest, DefaultKeyIsCreatedOnFirstUseUnderXdgConfigHome) {
  const fs::path expected = dir_ / "xdg" / "rigidtouch" / "device.key";
  EXPECT_EQ(DefaultDeviceKeyPath(), expected.string());
  ASSERT_FALSE(fs::exists(expected));
  const DeviceKey first = ResolveDeviceKey(std::nullopt, "");
  ASSERT_TRUE(fs::exists(expected));
  EXPECT_EQ(ModeOf(expected), 0600u);
  EXPECT_EQ(ModeOf(expected.parent_path()), 0700u);
  EXPECT_EQ(ResolveDeviceKey(std::nullopt, ""), first) << "later uses read the same key";
  EXPECT_FALSE(fs::exists(dir_ / "home")) << "HOME is not used when XDG_CONFIG_HOME is set";
}

TEST_F(KeyFileTest, DefaultKeyFallsBackToHomeConfig) {
  ::unsetenv("XDG_CONFIG_HOME");
  EXPECT_EQ(DefaultDeviceKeyPath(), (dir_ / "home" / ".config" / "rigidtouch" / "device.key"));
  ::setenv("XDG_CONFIG_HOME", "relative/ignored", 1);
  ResolveDeviceKey(std::nullopt, "");
  EXPECT_TRUE(fs::exists(dir_ / "home" / ".config" / "rigidtouch" / "device.key"));
  ::unsetenv("XDG_CONFIG_HOME");
  ::unsetenv("HOME");
  EXPECT_THROW(DefaultDeviceKeyPath(), Error);
}

TEST_F(KeyFileTest, AnExplicitKeyOrKeyFileWinsAndIsNeverCreated) {
  const DeviceKey given = GenerateDeviceKey();
  EXPECT_EQ(ResolveDeviceKey(given, "/nonexistent"), given);
  const std::string file = (dir_ / "shared.key").string();
  EXPECT_THROW(ResolveDeviceKey(std::nullopt, file), Error);
  EXPECT_FALSE(fs::exists(file)) << "a named key file must come from keygen";
  WriteDeviceKey(file, given, false);
  EXPECT_EQ(ResolveDeviceKey(std::nullopt, file), given);
  EXPECT_FALSE(fs::exists(dir_ / "xdg")) << "the default key is not created when not used";
}

}  // namespace
}  // namespace rigidtouch::device
