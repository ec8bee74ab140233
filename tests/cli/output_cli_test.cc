// End-to-end: output paths are checked before a run, only regular files are replaced, and a full
// file size limit ends with a message, exit code 4 and no leftovers (README, "Exit codes").
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <set>

#include "cli/cli_util.h"

namespace rigidtouch::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> Entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

// a run that takes many seconds if it starts: a bad output path must stop it first
constexpr char kLongTap[] = "tap --taps 1000 ";

TEST(OutputCliTest, MissingTraceFolderFailsBeforeTheRun) {
  const fs::path dir = TempDir("missing_folder");
  const auto t0 = std::chrono::steady_clock::now();
  const CliResult r = RunCli(kLongTap + std::string("--trace ") + (dir / "no/t.csv").string());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: error: cannot write trace file"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  EXPECT_LT(seconds, 5.0) << "the run started before the path was checked";
  for (const char* flag : {"--plot ", "--compare-walls --out-dir "}) {
    std::ofstream(dir / "file") << "x";
    const CliResult p = RunCli(kLongTap + std::string(flag) + (dir / "file/sub").string());
    EXPECT_EQ(p.exit_code, 2) << flag << p.err;
  }
  fs::remove_all(dir);
}

TEST(OutputCliTest, TraceRefusesLinksFifosAndDevices) {
  const fs::path dir = TempDir("special");
  std::ofstream(dir / "target.csv") << "keep";
  fs::create_symlink(dir / "target.csv", dir / "link.csv");
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0644), 0);
  std::vector<fs::path> refused = {dir / "link.csv", dir / "fifo"};
  // a device node of our own (a copy of /dev/null, root only): if the check ever broke, the run
  // would replace this node and never the system's /dev/null
  const bool device = ::mknod((dir / "null").c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0;
  if (device) refused.push_back(dir / "null");
  for (const fs::path& p : refused) {
    const CliResult r = RunCli(kLongTap + std::string("--trace ") + p.string());
    EXPECT_EQ(r.exit_code, 2) << p << r.err;
    EXPECT_NE(r.err.find("only a regular file is replaced"), std::string::npos) << r.err;
  }
  EXPECT_TRUE(fs::is_symlink(dir / "link.csv"));
  EXPECT_EQ(ReadAll(dir / "target.csv"), "keep");
  EXPECT_TRUE(fs::is_fifo(dir / "fifo"));
  if (device) {
    EXPECT_TRUE(fs::is_character_file(dir / "null"));
  }
  fs::remove_all(dir);
}

TEST(OutputCliTest, FileSizeLimitEndsWithExitFourAndNoLeftovers) {
  const fs::path dir = TempDir("ulimit");
  const std::string trace = (dir / "t.csv").string();
  // ulimit -f counts 512-byte blocks: a one-tap trace is far larger
  const CliResult r = RunCli("tap --taps 1 --trace " + trace, "ulimit -f 4;");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("rigidtouch: error: cannot write trace file '" + trace + "'"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("file size limit (ulimit -f)"), std::string::npos) << r.err;
  EXPECT_TRUE(Entries(dir).empty());
  fs::remove_all(dir);
}

// study run: the first record (the session_start with the protocol) is larger than the limit
TEST(OutputCliTest, StudyLogPastTheFileSizeLimitIsRemovedNotLeftTorn) {
  const fs::path dir = TempDir("study_ulimit");
  const nlohmann::json protocol = {
      {"name", "limit"},
      {"series", 2},
      {"conditions",
       {{"soft", {{"renderer", "penalty"}, {"stiffness_N_per_m", 400}}},
        {"click", {{"renderer", "impulse"}, {"restitution", 0}}}}},
      {"tests", {{{"name", "only"}, {"conditions", {"soft", "click"}}}}}};
  std::ofstream(dir / "p.json") << protocol.dump();
  const std::string log = (dir / "p01.jsonl").string();
  const std::string args = "study run --protocol " + (dir / "p.json").string() +
                           " --participant P01 --presenter text --seed 1 --log " + log +
                           " </dev/null";
  const CliResult r = RunCli(args, "ulimit -f 1;");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("file size limit"), std::string::npos) << r.err;
  EXPECT_EQ(Entries(dir), std::vector<std::string>{"p.json"});
  // a link as the log is refused and left alone
  std::ofstream(dir / "other.jsonl") << "keep\n";
  fs::create_symlink(dir / "other.jsonl", dir / "link.jsonl");
  const CliResult l = RunCli("study run --protocol " + (dir / "p.json").string() +
                             " --participant P01 --presenter text --log " +
                             (dir / "link.jsonl").string() + " </dev/null");
  EXPECT_EQ(l.exit_code, 2) << l.err;
  EXPECT_NE(l.err.find("is a symbolic link"), std::string::npos) << l.err;
  EXPECT_EQ(ReadAll(dir / "other.jsonl"), "keep\n");
  fs::remove_all(dir);
}

// Runs `script` (sh) with a fresh tmpfs of `kib` KiB mounted at `disk`, in a private mount
// namespace (unshare -rm: no root needed where user namespaces are allowed; nothing is mounted
// outside the child). False when the machine does not allow it.
bool RunOnSmallDisk(const fs::path& disk, int kib, const std::string& script) {
  fs::create_directories(disk);
  const std::string command = "unshare -rm sh -c 'mount -t tmpfs -o size=" + std::to_string(kib) +
                              "k rigidtouch-full " + disk.string() + " && " + script + "'";
  return std::system(command.c_str()) == 0;
}

bool SmallDisksAvailable(const fs::path& dir) {
  return RunOnSmallDisk(dir / "probe", 16, "true");
}

// ENOSPC (the disk is full), not a file size limit: `tap --trace` onto a 16 KiB tmpfs ends with
// exit 4, a message naming the file and the full disk, and nothing left on the disk
TEST(OutputCliTest, FullDiskEndsWithExitFourAndNoLeftovers) {
  const fs::path dir = TempDir("enospc");
  if (!SmallDisksAvailable(dir)) GTEST_SKIP() << "no private tmpfs here (unshare -rm refused)";
  const fs::path disk = dir / "disk";
  const std::string trace = (disk / "t.csv").string();
  ASSERT_TRUE(RunOnSmallDisk(disk, 16,
                             std::string(RIGIDTOUCH_CLI) + " tap --taps 1 --trace " + trace + " >" +
                                 (dir / "out").string() + " 2>" + (dir / "err").string() +
                                 "; echo $? >" + (dir / "status").string() + "; ls -A " +
                                 disk.string() + " >" + (dir / "left").string()));
  const std::string err = ReadAll(dir / "err");
  EXPECT_EQ(ReadAll(dir / "status"), "4\n") << err;
  EXPECT_NE(err.find("rigidtouch: error: cannot write trace file '" + trace + "'"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("disk is full"), std::string::npos) << err;
  EXPECT_EQ(ReadAll(dir / "left"), "") << "a partial or temporary file was left";
  fs::remove_all(dir);
}

// a study log fills the disk in the middle of a session: exit 4 naming the full disk; every
// answer written before is intact (the log reads back, at most with a torn last line), and the
// session resumes on a disk with room and completes with every answer once
TEST(OutputCliTest, StudyLogOnAFullDiskKeepsEveryWrittenAnswerAndResumes) {
  const fs::path dir = TempDir("study_enospc");
  if (!SmallDisksAvailable(dir)) GTEST_SKIP() << "no private tmpfs here (unshare -rm refused)";
  const int series = 60;  // about 60 x 300 bytes of answers: more than the disk holds
  const nlohmann::json protocol = {
      {"name", "full"},
      {"series", series},
      {"conditions",
       {{"soft", {{"renderer", "penalty"}, {"stiffness_N_per_m", 400}}},
        {"click", {{"renderer", "impulse"}, {"restitution", 0}}}}},
      {"tests", {{{"name", "only"}, {"conditions", {"soft", "click"}}}}}};
  std::ofstream(dir / "p.json") << protocol.dump();
  std::string answers;
  for (int k = 0; k < series; ++k) answers += k % 3 == 0 ? "2\n" : "1\n";
  std::ofstream(dir / "answers") << answers;
  const fs::path disk = dir / "disk";
  const std::string run = std::string(RIGIDTOUCH_CLI) + " study run --protocol " +
                          (dir / "p.json").string() +
                          " --participant P01 --presenter text --seed 3 --log ";
  ASSERT_TRUE(RunOnSmallDisk(
      disk, 8,
      run + (disk / "p01.jsonl").string() + " <" + (dir / "answers").string() + " >/dev/null 2>" +
          (dir / "err").string() + "; echo $? >" + (dir / "status").string() + "; cp " +
          (disk / "p01.jsonl").string() + " " + dir.string()));
  const std::string err = ReadAll(dir / "err");
  EXPECT_EQ(ReadAll(dir / "status"), "4\n") << err;
  EXPECT_NE(err.find("disk is full"), std::string::npos) << err;
  const std::string torn = ReadAll(dir / "p01.jsonl");
  const auto written = static_cast<long>(std::count(torn.begin(), torn.end(), '\n'));
  ASSERT_GT(written, 5) << "the disk filled before the session got going";

  // resume on the normal disk: the answers already given are not asked again
  std::string rest;
  for (int k = 0; k < series; ++k) rest += k % 3 == 0 ? "2\n" : "1\n";
  std::ofstream(dir / "rest") << rest;
  const CliResult resumed = RunCli("study run --protocol " + (dir / "p.json").string() +
                                   " --participant P01 --presenter text --seed 3 --resume --log " +
                                   (dir / "p01.jsonl").string() + " <" + (dir / "rest").string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  const CliResult analyzed = RunCli("study analyze --json " + (dir / "p01.jsonl").string());
  ASSERT_EQ(analyzed.exit_code, 0) << analyzed.err;
  std::ifstream log(dir / "p01.jsonl");
  long answer_records = 0;
  std::set<long> steps;
  for (std::string line; std::getline(log, line);) {
    const auto record = nlohmann::json::parse(line);
    if (record["type"] == "answer") {
      ++answer_records;
      steps.insert(record["step"].get<long>());
    }
  }
  EXPECT_EQ(answer_records, series) << "each series answered exactly once";
  EXPECT_EQ(static_cast<long>(steps.size()), series);
  fs::remove_all(dir);
}

TEST(OutputCliTest, ScenesWithAbsurdValuesAreLoadErrors) {
  const fs::path dir = TempDir("absurd");
  std::ofstream(dir / "heavy.xml")
      << "<mujoco><worldbody><body name=\"tool\"><freejoint/><geom type=\"sphere\" "
         "size=\"0.01\" mass=\"1e300\"/></body></worldbody></mujoco>";
  const CliResult r = RunCli("simulate --steps 10 --scene " + (dir / "heavy.xml").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("the mass of body 'tool' is 1e+300 kg"), std::string::npos) << r.err;
  const CliResult c = RunCli("simulate --steps 10 --scene " + (dir / "heavy.xml").string() +
                             " --config " + dir.string());
  EXPECT_EQ(c.exit_code, 2) << c.err;
  EXPECT_NE(c.err.find("is a directory, not a config file"), std::string::npos) << c.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rigidtouch::test
