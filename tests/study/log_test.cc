#include "study/log.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "rigidtouch/types.h"
#include "study/test_files.h"

namespace rigidtouch::study {
namespace {

using nlohmann::json;
using testing::ReadFile;
using testing::ScratchDir;
using testing::WriteFile;

json Start() {
  return {{"type", "session_start"}, {"format", kLogFormat}, {"format_version", kLogFormatVersion}};
}

std::string RecordLines(std::initializer_list<json> records) {
  std::string out;
  for (const json& r : records) out += RecordLine(r);
  return out;
}

std::string LogErrorOf(const std::string& bytes) {
  try {
    ParseLog(bytes, "log.jsonl");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(LogTest, ParsesCompleteLines) {
  const std::string bytes = RecordLines({Start(), {{"type", "answer"}, {"step", 2}}});
  const LogContents c = ParseLog(bytes, "log.jsonl");
  ASSERT_EQ(c.records.size(), 2u);
  EXPECT_EQ(c.records[1]["step"], 2);
  EXPECT_EQ(c.valid_bytes, bytes.size());
  EXPECT_EQ(c.torn_tail_bytes, 0u);
  EXPECT_TRUE(ParseLog("", "empty").records.empty());
}

TEST(LogTest, UnterminatedRecordAfterCompleteOnesIsATornTail) {
  const std::string whole = RecordLines({Start(), {{"type", "series"}}});
  const std::string torn = R"({"type":"answer","st)";
  const LogContents c = ParseLog(whole + torn, "log.jsonl");
  EXPECT_EQ(c.records.size(), 2u);
  EXPECT_EQ(c.valid_bytes, whole.size());
  EXPECT_EQ(c.torn_tail_bytes, torn.size());
}

TEST(LogTest, RefusesWhatIsNotAStudyLog) {
  EXPECT_NE(LogErrorOf("hello world\n").find("line 1 is not JSON"), std::string::npos);
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + "not json\n").find("line 2 is not JSON"),
            std::string::npos);
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + "[1,2]\n").find("line 2 is not a study record"),
            std::string::npos);
  EXPECT_NE(LogErrorOf(RecordLines({{{"type", "answer"}}})).find("line 1 is not the session_start"),
            std::string::npos);
  EXPECT_NE(LogErrorOf("no line end at all").find("no complete line"), std::string::npos);
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + "garbage").find("neither a record"),
            std::string::npos);
  json future = Start();
  future["format_version"] = 99;
  EXPECT_NE(LogErrorOf(RecordLines({future})).find("version 99 is not supported"),
            std::string::npos);
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + "\n").find("line 2 is not JSON"),
            std::string::npos);
}

// a line nested deeper than every JSON input may be is refused before it is parsed
TEST(LogTest, RefusesALineNestedTooDeep) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']') + "\n";
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + deep)
                .find("line 2 nests arrays and objects more than 64 deep (at byte 65 of the line)"),
            std::string::npos)
      << LogErrorOf(RecordLines({Start()}) + deep).substr(0, 300);
}

// a field of the wrong type in the first record (found by the study_log fuzzer: a "format" that is
// an object threw nlohmann's type_error out of ParseLog) is a rigidtouch::Error like any other
TEST(LogTest, FirstRecordFieldsOfTheWrongTypeAreRefused) {
  for (const char* key : {"format", "type"}) {
    json odd = Start();
    odd[key] = json{{"a", 1}};
    const std::string bytes = RecordLines({odd});
    EXPECT_THROW(ParseLog(bytes, "log.jsonl"), Error) << key;
    EXPECT_NE(LogErrorOf(bytes).find("log.jsonl: line 1 is not"), std::string::npos) << key;
  }
  // a number beyond a double's range threw nlohmann's out_of_range out of ParseLog
  EXPECT_NE(LogErrorOf(RecordLines({Start()}) + R"({"type":"answer","step":1e999})" + "\n")
                .find("log.jsonl: line 2 is not a study record"),
            std::string::npos);
  json huge = Start();
  huge["format_version"] = 4294967297LL;  // truncates to 1 as an int
  EXPECT_NE(LogErrorOf(RecordLines({huge})).find("version 4294967297 is not supported"),
            std::string::npos);
}

TEST(LogTest, AppendedRecordsReadBackInOrder) {
  ScratchDir dir;
  const std::string path = dir.File("a.jsonl");
  {
    auto log = LogFile::Open(path);
    EXPECT_TRUE(log->contents().records.empty());
    log->Append(Start(), true);
    log->Append({{"type", "answer"}, {"step", 1}}, true);
    log->Append({{"type", "answer"}, {"step", 2}, {"text", "caf\xc3\xa9"}}, false);
  }
  const LogContents c = ReadLog(path);
  ASSERT_EQ(c.records.size(), 3u);
  EXPECT_EQ(c.records[2]["step"], 2);
  EXPECT_EQ(c.records[2]["text"], "caf\xc3\xa9");
  EXPECT_EQ(ReadFile(path),
            RecordLines({Start(),
                         {{"type", "answer"}, {"step", 1}},
                         {{"type", "answer"}, {"step", 2}, {"text", "caf\xc3\xa9"}}}));
}

TEST(LogTest, DropTornTailTruncatesExactlyTheTornBytes) {
  ScratchDir dir;
  const std::string path = dir.File("torn.jsonl");
  const std::string whole = RecordLines({Start(), {{"type", "answer"}, {"step", 1}}});
  WriteFile(path, whole + R"({"type":"ans)");
  auto log = LogFile::Open(path);
  EXPECT_EQ(log->contents().torn_tail_bytes, 12u);
  log->DropTornTail();
  EXPECT_EQ(ReadFile(path), whole);
  log->Append({{"type", "answer"}, {"step", 2}}, true);
  EXPECT_EQ(ReadLog(path).records.size(), 3u);
}

TEST(LogTest, OpenRefusesNonJsonLinesWithoutTouchingIt) {
  ScratchDir dir;
  const std::string path = dir.File("notes.txt");
  const std::string bytes = "these are my notes\nnot a log\n{\"partial";
  WriteFile(path, bytes);
  const auto before = std::filesystem::last_write_time(path);
  EXPECT_THROW(LogFile::Open(path), Error);
  EXPECT_EQ(ReadFile(path), bytes);
  EXPECT_EQ(std::filesystem::last_write_time(path), before);
}

TEST(LogTest, SecondWriterIsRefused) {
  ScratchDir dir;
  const std::string path = dir.File("busy.jsonl");
  auto first = LogFile::Open(path);
  try {
    LogFile::Open(path);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("in use by another running session"), std::string::npos);
  }
}

TEST(LogTest, DirectoryIsRefused) {
  ScratchDir dir;
  EXPECT_THROW(LogFile::Open(dir.path()), Error);
  EXPECT_THROW(ReadLog(dir.path()), Error);
}

TEST(LogTest, MissingFileReadsAsEmpty) {
  ScratchDir dir;
  EXPECT_TRUE(ReadLog(dir.File("none.jsonl")).records.empty());
  EXPECT_FALSE(std::filesystem::exists(dir.File("none.jsonl")));
}

}  // namespace
}  // namespace rigidtouch::study
