// docs/architecture.md's stage table against src/engine/tick.cc: the same stages, numbered the
// same and in the same order, each stage one call in Tick (the function the table names first),
// and Tick short enough to read as the list it is.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace rigidtouch {
namespace {

std::vector<std::string> Lines(const std::string& relative) {
  std::ifstream in(std::string(RIGIDTOUCH_SOURCE_DIR) + "/" + relative);
  EXPECT_TRUE(in) << relative;
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct Stage {
  int number = 0;
  std::vector<std::string> calls;  // the namespace-qualified calls of the stage
};

// Tick's body, from its signature to the closing brace at the start of a line
std::vector<std::string> TickBody() {
  const std::vector<std::string> lines = Lines("src/engine/tick.cc");
  std::vector<std::string> body;
  bool in = false;
  for (const std::string& line : lines) {
    if (line.rfind("DeviceCommand Tick(", 0) == 0) in = true;
    if (in) body.push_back(line);
    if (in && line == "}") break;
  }
  return body;
}

// each "  // N. name: ..." comment of Tick starts stage N; the calls of a stage are the
// `namespace::Function(` calls in its code lines, up to the next stage's comment
std::vector<Stage> TickStages() {
  const std::regex comment(R"(^\s*// (\d+)\. )");
  const std::regex call(R"(\b([a-z]+::[A-Z]\w*)\()");
  std::vector<Stage> stages;
  for (const std::string& line : TickBody()) {
    std::smatch m;
    if (std::regex_search(line, m, comment)) {
      stages.push_back({std::stoi(m[1]), {}});
      continue;
    }
    if (stages.empty() || line.find("//") != std::string::npos) continue;
    for (auto it = std::sregex_iterator(line.begin(), line.end(), call);
         it != std::sregex_iterator(); ++it) {
      stages.back().calls.push_back((*it)[1]);
    }
  }
  return stages;
}

// the table's rows "| N | stage | `namespace::Function` ... |": the number and the first
// function the third column names
std::vector<Stage> TableStages() {
  const std::regex row(R"(^\| (\d+) \| [^|]+ \| `([a-z]+::[A-Z]\w*)`)");
  std::vector<Stage> stages;
  for (const std::string& line : Lines("docs/architecture.md")) {
    std::smatch m;
    if (std::regex_search(line, m, row)) stages.push_back({std::stoi(m[1]), {m[2]}});
  }
  return stages;
}

TEST(TickStagesTest, TheArchitectureTableIsTheListOfTicksCalls) {
  const std::vector<Stage> tick = TickStages();
  const std::vector<Stage> table = TableStages();
  ASSERT_GE(tick.size(), 7u);
  ASSERT_EQ(tick.size(), table.size());
  for (std::size_t i = 0; i < tick.size(); ++i) {
    SCOPED_TRACE("stage " + std::to_string(tick[i].number));
    EXPECT_EQ(tick[i].number, static_cast<int>(i) + 1);
    EXPECT_EQ(table[i].number, tick[i].number);
    ASSERT_EQ(tick[i].calls.size(), 1u) << "a stage is one call in Tick";
    EXPECT_EQ(tick[i].calls[0], table[i].calls[0]);
  }
}

TEST(TickStagesTest, TickIsUnderSixtyLines) {
  const std::vector<std::string> body = TickBody();
  ASSERT_FALSE(body.empty());
  EXPECT_LT(body.size(), 60u);
}

}  // namespace
}  // namespace rigidtouch
