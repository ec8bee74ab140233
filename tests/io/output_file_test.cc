// Output files: the checks before a run, refusing anything but a regular file, and failed writes
// (file size limit, in a child process) that leave nothing behind.
#include "io/output_file.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli/cli_util.h"

namespace rigidtouch::io {
namespace {

namespace fs = std::filesystem;

class OutputFileTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::TempDir("output_file"); }
  void TearDown() override {
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add);
    fs::remove_all(dir_);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string CheckError(const std::string& path) const {
    try {
      CheckOutputPath(path, "trace file");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  std::vector<std::string> Entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_;
};

TEST_F(OutputFileTest, AcceptsAnAbsentOrRegularFileInAWritableFolder) {
  EXPECT_EQ(CheckError(Path("new.csv")), "");
  std::ofstream(Path("old.csv")) << "x";
  EXPECT_EQ(CheckError(Path("old.csv")), "");
  WriteFileAtomically(Path("old.csv"), "new", "trace file");
  EXPECT_EQ(test::ReadAll(Path("old.csv")), "new");
  EXPECT_EQ(Entries(), std::vector<std::string>{"old.csv"});
}

TEST_F(OutputFileTest, MissingFolderIsNamedBeforeAnythingIsWritten) {
  const std::string e = CheckError(Path("missing/t.csv"));
  EXPECT_NE(e.find("folder '" + Path("missing") + "' does not exist"), std::string::npos) << e;
  EXPECT_NE(e.find("cannot write trace file '" + Path("missing/t.csv") + "'"), std::string::npos);
}

TEST_F(OutputFileTest, RefusesLinksFifosDevicesFoldersAndReadOnlyFiles) {
  std::ofstream(Path("target.csv")) << "keep";
  fs::create_symlink(Path("target.csv"), Path("link.csv"));
  EXPECT_NE(CheckError(Path("link.csv")).find("is a symbolic link"), std::string::npos);
  ASSERT_EQ(::mkfifo(Path("fifo").c_str(), 0644), 0);
  EXPECT_NE(CheckError(Path("fifo")).find("is a FIFO"), std::string::npos);
  EXPECT_NE(CheckError("/dev/null").find("is a device"), std::string::npos);
  fs::create_directory(Path("sub"));
  EXPECT_NE(CheckError(Path("sub")).find("is a folder"), std::string::npos);
  std::ofstream(Path("ro.csv")) << "keep";
  fs::permissions(Path("ro.csv"), fs::perms::owner_read);
  EXPECT_NE(CheckError(Path("ro.csv")).find("read-only"), std::string::npos);
  // the writer makes the same checks: the link, its target and the read-only file are untouched
  EXPECT_THROW(WriteFileAtomically(Path("link.csv"), "x", "trace file"), Error);
  EXPECT_THROW(WriteFileAtomically(Path("ro.csv"), "x", "trace file"), Error);
  EXPECT_TRUE(fs::is_symlink(Path("link.csv")));
  EXPECT_EQ(test::ReadAll(Path("target.csv")), "keep");
  EXPECT_EQ(test::ReadAll(Path("ro.csv")), "keep");
  EXPECT_EQ(Entries(),
            (std::vector<std::string>{"fifo", "link.csv", "ro.csv", "sub", "target.csv"}));
}

// a folder that access() calls writable but that takes no file (root passes every access check;
// /proc takes no new file even from root) is refused before the run, not after it (exit 2, not 4)
TEST_F(OutputFileTest, AFolderThatTakesNoNewFileIsRefusedBeforeTheRun) {
  const std::string e = CheckError("/proc/t.csv");
  EXPECT_NE(e.find("folder '/proc'"), std::string::npos) << e;
  EXPECT_THROW(CheckOutputDir("/proc/out", "output folder"), Error);
  // the test leaves nothing behind in a folder that takes files
  EXPECT_EQ(CheckError(Path("t.csv")), "");
  EXPECT_TRUE(Entries().empty());
}

TEST_F(OutputFileTest, OutputDirMayBeCreatedUnderAWritableFolder) {
  EXPECT_NO_THROW(CheckOutputDir(Path("a/b/c"), "output folder"));
  std::ofstream(Path("file")) << "x";
  EXPECT_THROW(CheckOutputDir(Path("file/sub"), "output folder"), Error);
  EXPECT_THROW(CheckOutputDir(Path("file"), "output folder"), Error);
}

// under a file size limit the write fails with EFBIG (SIGXFSZ ignored): OutputError naming the
// limit, the old file unchanged and no temporary file left
TEST_F(OutputFileTest, FileSizeLimitFailsCleanlyAndLeavesNoTemporaryFile) {
  std::ofstream(Path("t.csv")) << "old";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    IgnoreFileSizeSignal();
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      WriteFileAtomically(Path("t.csv"), std::string(100000, 'x'), "trace file");
    } catch (const OutputError& e) {
      const std::string m = e.what();
      ::_exit(m.find("file size limit") != std::string::npos ? 4 : 5);
    } catch (...) {
      ::_exit(6);
    }
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 4);
  EXPECT_EQ(test::ReadAll(Path("t.csv")), "old");
  EXPECT_EQ(Entries(), std::vector<std::string>{"t.csv"});
}

TEST(WriteFailureReasonTest, NamesTheLimitAndTheFullDisk) {
  EXPECT_NE(WriteFailureReason(EFBIG).find("ulimit -f"), std::string::npos);
  EXPECT_NE(WriteFailureReason(ENOSPC).find("disk is full"), std::string::npos);
}

}  // namespace
}  // namespace rigidtouch::io
