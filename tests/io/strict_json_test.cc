#include "io/strict_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "base/text.h"
#include "rigidtouch/types.h"
#include "test_util.h"

namespace rigidtouch::io {
namespace {

using nlohmann::json;

// the message of the Error `f` throws, or "" if it throws none
template <typename F>
std::string ThrownErrorOf(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const JsonSource kSource("s.json");

json Parse(const std::string& text) {
  return ParseJsonText(text, kSource);
}

TEST(StrictJsonTest, ParsesValidText) {
  const json j = Parse(R"({"a": [1, {"b": true}], "c": "x"})");
  EXPECT_EQ(j["a"][1]["b"], true);
  EXPECT_EQ(j["c"], "x");
}

TEST(StrictJsonTest, SyntaxErrorsGiveLineColumnAndField) {
  const std::string line2 = ThrownErrorOf([] { Parse("{\"a\": 1,\n \"b\": tru}"); });
  EXPECT_NE(line2.find("s.json: not valid JSON at line 2, column 10 (reading field b): "),
            std::string::npos)
      << line2;
  const std::string e =
      ThrownErrorOf([] { Parse(R"({"tests": [{"name": "x"}, {"name": nan}]})"); });
  EXPECT_NE(e.find("(reading field tests[1].name)"), std::string::npos) << e;
  EXPECT_NE(e.find("invalid literal"), std::string::npos) << e;
  // no "[json.exception...]" noise in the message
  EXPECT_EQ(e.find("json.exception"), std::string::npos) << e;
}

TEST(StrictJsonTest, OverflowingNumbersNameTheField) {
  EXPECT_EQ(ThrownErrorOf([] { Parse(R"({"a": {"b": [0, 1e309]}})"); }),
            "s.json: a.b[1]: 1e309 is not a finite number");
  EXPECT_EQ(ThrownErrorOf([] { Parse("-2e308"); }), "s.json: -2e308 is not a finite number");
}

TEST(StrictJsonTest, DuplicateFieldsAreErrors) {
  EXPECT_EQ(ThrownErrorOf([] { Parse(R"({"a": {"b": 1, "c": 2, "b": 3}})"); }),
            "s.json: a.b: the field is given twice; give it once");
  // the same name in different objects is fine
  EXPECT_EQ(ThrownErrorOf([] { Parse(R"([{"b": 1}, {"b": 2}])"); }), "");
}

TEST(StrictJsonTest, ReadJsonFileNamesTheFileAndTheProblem) {
  EXPECT_EQ(ThrownErrorOf([] { ReadJsonFile("missing.json", "widget file"); }),
            "missing.json: cannot open the widget file");
  const std::string empty = test::WriteTempFile("empty.json", "  \n");
  EXPECT_EQ(ThrownErrorOf([&] { ReadJsonFile(empty, "widget file"); }),
            empty + ": the widget file is empty");
  const std::string dir = test::TempDir().string();
  EXPECT_EQ(ThrownErrorOf([&] { ReadJsonFile(dir, "widget file"); }),
            dir + ": is a directory, not a widget file");
  const std::string bad = test::WriteTempFile("bad.json", "{\"x\": 1e999}");
  EXPECT_EQ(ThrownErrorOf([&] { ReadJsonFile(bad, "widget file"); }),
            bad + ": x: 1e999 is not a finite number");
  const std::string good = test::WriteTempFile("good.json", "{\"x\": 2}");
  EXPECT_EQ(ReadJsonFile(good, "widget file")["x"], 2);
}

// arrays and objects deeper than kMaxJsonDepth are refused before parsing, at the bracket that
// goes one level too deep; brackets in strings do not count
TEST(StrictJsonTest, NestingDeeperThanTheLimitIsRefusedWithItsPlace) {
  const auto nested = [](int depth, char open, const std::string& inner, char close) {
    std::string text;
    for (int i = 0; i < depth; ++i) text += open == '{' ? std::string("{\"k\":") : "[";
    text += inner;
    for (int i = 0; i < depth; ++i) text += close;
    return text;
  };
  EXPECT_EQ(ThrownErrorOf([&] { Parse(nested(kMaxJsonDepth, '[', "1", ']')); }), "");
  const std::string deep = ThrownErrorOf([&] { Parse(nested(kMaxJsonDepth + 1, '[', "1", ']')); });
  EXPECT_EQ(deep,
            "s.json: arrays and objects nested more than 64 deep at line 1, column 65 (the "
            "limit of every JSON input rigidtouch reads)");
  for (const char open : {'[', '{'}) {
    const std::string huge =
        ThrownErrorOf([&] { Parse(nested(100000, open, "1", open == '[' ? ']' : '}')); });
    EXPECT_NE(huge.find("s.json: arrays and objects nested more than 64 deep"), std::string::npos)
        << huge.substr(0, 200);
  }
  // unclosed: the depth is found before the parser would report the missing brackets
  EXPECT_NE(ThrownErrorOf([] { Parse(std::string(100000, '[')); }).find("nested more than 64"),
            std::string::npos);
  // brackets inside strings, escaped quotes included, are text
  const std::string in_string =
      "[\"" + std::string(200, '[') + "\\\"" + std::string(200, '{') + "\"]";
  EXPECT_EQ(Parse(in_string)[0].get<std::string>().size(), 401u);
  EXPECT_EQ(JsonDepthExceededAt(in_string), std::string_view::npos);
  // two levels, a string holding a bracket, then 64 more: the 63rd of them is level 65
  const std::string after_string = "[[\"]\"" + std::string(kMaxJsonDepth, '[');
  EXPECT_EQ(JsonDepthExceededAt(after_string), 5u + (kMaxJsonDepth - 2));
}

// a file larger than kMaxJsonFileBytes is refused without being read whole (a sparse file: the
// size is what is checked, whatever the bytes)
TEST(StrictJsonTest, AFileOverTheSizeLimitIsRefused) {
  const std::string big = test::WriteTempFile("big.json", "");
  std::filesystem::resize_file(big, kMaxJsonFileBytes + 1);
  EXPECT_EQ(ThrownErrorOf([&] { ReadJsonFile(big, "widget file"); }),
            big +
                ": the widget file is larger than 64 MiB, the limit of every JSON file "
                "rigidtouch reads");
  std::filesystem::resize_file(big, kMaxJsonFileBytes);  // at the limit: read, then parsed
  EXPECT_NE(ThrownErrorOf([&] { ReadJsonFile(big, "widget file"); }).find("not valid JSON"),
            std::string::npos);
  std::filesystem::remove(big);
}

TEST(StrictJsonTest, UnknownFieldsListTheValidOnes) {
  const json j = {{"a", 1}, {"z", 2}};
  EXPECT_EQ(ThrownErrorOf([&] {
              StrictObject(kSource, j, "top", {"a", "b"});
            }),
            "s.json: top: unknown field \"z\"; valid fields: a, b");
  EXPECT_EQ(ThrownErrorOf([&] { StrictObject(kSource, j, "", {"a", "z"}); }), "");
  EXPECT_EQ(ThrownErrorOf([&] { StrictObject(kSource, json(3), "", {"a"}, "a widget"); }),
            "s.json: expected a widget (a JSON object), got a number 3");
}

TEST(StrictJsonTest, GettersCheckTypesAndNameThePath) {
  const json j = json::parse(R"({"n": 2.5, "s": "text", "b": false, "i": 7, "o": {"k": "v"},
                                 "big": 18446744073709551615, "neg": -3})");
  const StrictObject in(kSource, j, "sec", {"n", "s", "b", "i", "o", "big", "neg", "absent"});
  EXPECT_EQ(in.Number("n"), 2.5);
  EXPECT_EQ(in.Number("i"), 7.0);
  EXPECT_EQ(in.Number("absent"), std::nullopt);
  EXPECT_EQ(in.String("s"), "text");
  EXPECT_EQ(in.Bool("b"), false);
  EXPECT_EQ(in.Integer("i", 0, 1, 10), 7);
  EXPECT_EQ(in.Integer("absent", 4, 1, 10), 4);
  EXPECT_EQ(in.Unsigned("big"), 18446744073709551615ULL);
  EXPECT_EQ(in.Path("n"), "sec.n");
  EXPECT_EQ(in.Object("o", {"k"}, "an o").String("k"), "v");
  double d = 1.0;
  in.Read("absent", d);
  EXPECT_EQ(d, 1.0);
  in.Read("n", d);
  EXPECT_EQ(d, 2.5);

  EXPECT_EQ(ThrownErrorOf([&] { in.Number("s"); }),
            "s.json: sec.s: expected a number, got a string \"text\"");
  EXPECT_EQ(ThrownErrorOf([&] { in.String("n"); }),
            "s.json: sec.n: expected a string, got a number 2.5");
  EXPECT_EQ(ThrownErrorOf([&] { in.Bool("i"); }),
            "s.json: sec.i: expected true or false, got a number 7");
  EXPECT_EQ(ThrownErrorOf([&] { in.Integer("n", 0, 1, 10); }),
            "s.json: sec.n: expected an integer, got 2.5; valid: integers 1 to 10");
  EXPECT_EQ(ThrownErrorOf([&] { in.Integer("i", 0, 1, 5); }),
            "s.json: sec.i: 7 is out of range; valid: integers 1 to 5");
  EXPECT_EQ(ThrownErrorOf([&] { in.Integer("big", 0, 1, 5); }),
            "s.json: sec.big: 18446744073709551615 is out of range; valid: integers 1 to 5");
  EXPECT_EQ(ThrownErrorOf([&] { in.Unsigned("neg"); }),
            "s.json: sec.neg: expected a non-negative integer below 2^64, got -3");
  EXPECT_EQ(ThrownErrorOf([&] { in.RequiredString("absent"); }),
            "s.json: sec: missing required field \"absent\"");
  EXPECT_EQ(ThrownErrorOf([&] {
              in.OneOf("s", {"a", "b"}, "mode");
            }),
            "s.json: sec.s: unknown mode \"text\"; valid modes: a, b");
  EXPECT_EQ(ThrownErrorOf([&] { in.Object("o", {"q"}, "an o"); }),
            "s.json: sec.o: unknown field \"k\"; valid fields: q");
}

TEST(StrictJsonTest, NonFiniteNumbersBuiltInCodeAreRejected) {
  const json j = {{"x", std::numeric_limits<double>::quiet_NaN()},
                  {"y", std::numeric_limits<double>::infinity()}};
  const StrictObject in(kSource, j, "", {"x", "y"});
  EXPECT_EQ(ThrownErrorOf([&] { in.Number("x"); }), "s.json: x: nan is not a finite number");
  EXPECT_EQ(ThrownErrorOf([&] { in.Number("y"); }), "s.json: y: inf is not a finite number");
}

TEST(TextTest, QuoteLowerTrimJoinFormat) {
  EXPECT_EQ(text::Quote("a b"), "\"a b\"");
  EXPECT_EQ(text::Lower("QuIt"), "quit");
  EXPECT_EQ(text::Trim("  x y \t\n"), "x y");
  EXPECT_EQ(text::Trim(" \t"), "");
  EXPECT_EQ(text::Join({"a", "b", "c"}), "a, b, c");
  EXPECT_EQ(text::Join({}), "");
  EXPECT_EQ(text::FormatNumber(0.1), "0.1");
  EXPECT_EQ(text::FormatNumber(1234567.0), "1.23457e+06");
}

}  // namespace
}  // namespace rigidtouch::io
