// The scene reader (app/src/scene_reader.h and its parts, scene_json.cpp, scene_tank.cpp,
// scene_paddles.cpp, scene_probes.cpp) against hostile and careless input: nesting, huge values,
// duplicate and unknown keys, names a terminal would act on, lists longer than a scene may hold, a probe
// interval below what can be written. Each is refused in one short, clean line at once, or, where the
// input is legal, read in linear time.
#include <gtest/gtest.h>

#include <string>

#include "refusal.h"
#include "sphxr/app/cli.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/common/log.h"
#include "support.h"

namespace sphxr::app {
namespace {

using test::ExpectBriefRefusal;
using test::ExpectCleanRefusal;

Status Parse(const std::string& text, SceneFile* scene) { return ParseScene(text, "test.json", scene); }

const char* kTank = R"("tank": {"min": [0, 0, 0], "max": [1, 1, 1]})";

std::string SceneWith(const std::string& body) { return std::string("{") + kTank + ", " + body + "}"; }

TEST(SceneReader, DeepNestingIsRefusedNotACrash) {
  // 100,000 levels: a message that dumped the value recursively would overflow the stack.
  const std::string deep = R"({"tank": {"min": )" + std::string(100000, '[') + std::string(100000, ']') +
                           R"(, "max": [1,1,1]}})";
  SceneFile scene;
  ExpectBriefRefusal(Parse(deep, &scene), "nested more than 64 levels");
  // 40 levels is legal JSON nesting, and the message about the wrong type stays short.
  const std::string forty = R"({"tank": {"min": )" + std::string(40, '[') + std::string(40, ']') + R"(, "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(forty, &scene), "tank.min");
}

TEST(SceneReader, AHugeValueIsEchoedInAtMost80Characters) {
  SceneFile scene;
  const std::string text = R"({"tank": {"min": [0, 0, ")" + std::string(5000000, 'a') + R"("], "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(text, &scene), "tank.min[2]: must be a number");
  std::string many;
  for (int k = 0; k < 100000; ++k) many += "1,";
  const std::string array = R"({"tank": {"min": [)" + many + R"(2], "max": [1,1,1]}})";
  ExpectBriefRefusal(Parse(array, &scene), "tank.min");
  // An unterminated 5 MB string: the parser's own message quotes what it read last.
  ExpectBriefRefusal(Parse(R"({"name": ")" + std::string(5000000, 'b'), &scene), "not valid JSON");
}

TEST(SceneReader, DuplicateKeysAreRefusedNamingTheKeyAndBothLines) {
  SceneFile scene;
  const std::string twoSolvers = "{\n  \"solver\": {\"stiffness\": 2e5},\n  \"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n"
                                 "  \"solver\": {\"spacing\": 0.05}\n}";
  ExpectBriefRefusal(Parse(twoSolvers, &scene), "key \"solver\" appears twice at the top level (lines 2 and 4)");
  const std::string twoFluids = "{\"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n\"fluid\": [{\"min\": [0,0,0], "
                                "\"max\": [0.5,0.5,0.5]}],\n\"fluid\": []}";
  ExpectBriefRefusal(Parse(twoFluids, &scene), "key \"fluid\" appears twice");
  // Inside a section, and spelt with an escape: the parser reads "sp\u0061cing" as "spacing".
  const std::string nested = "{\"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]},\n\"solver\": {\"spacing\": 0.1,\n"
                             "  \"sp\\u0061cing\": 0.05}}";
  ExpectBriefRefusal(Parse(nested, &scene), "appears twice in solver (lines 2 and 3)");
  // The same key in two objects is fine.
  const std::string fine = R"({"tank": {"min": [0,0,0], "max": [1,1,1]}, "fluid": [{"min": [0,0,0], "max": [1,0.5,1]}]})";
  EXPECT_TRUE(Parse(fine, &scene).ok());
}

TEST(SceneReader, AHundredThousandKeysParseAtOnceWithFewWarnings) {
  std::string text = R"({"tank": {"min": [0,0,0], "max": [1,1,1]})";
  for (int k = 0; k < 100000; ++k) text += ",\"k" + std::to_string(k) + "\": 1";
  text += "}";
  SceneFile scene;
  const LogLevel level = GetLogLevel();
  SetLogLevel(LogLevel::kError);
  Status s;
  const double seconds = test::Seconds([&] { s = Parse(text, &scene); });
  SetLogLevel(level);
  EXPECT_TRUE(s.ok()) << s.message();
  // (0.3 s in a release build, 3 s under the sanitizers; a quadratic check takes minutes.)
  EXPECT_LT(seconds, 20.0) << "the duplicate check is not quadratic";
  ASSERT_EQ(scene.warnings.size(), 21u) << "20 by name, then one line counting the rest";
  EXPECT_EQ(scene.warnings.back(), "99980 more unknown keys ignored");
}

TEST(SceneReader, NamesWithTerminalEscapesAreRefused) {
  SceneFile scene;
  ExpectBriefRefusal(Parse("{\"name\": \"\\u001b[31mred\", \"tank\": {\"min\": [0,0,0], \"max\": [1,1,1]}}", &scene),
                     "name: \\x1B[31mred: has control, format or line-separator characters");
}

TEST(SceneReader, NamesWithControlBidiOrLineSeparatorsAreRefused) {
  SceneFile scene;
  for (const char* bad : {"a\\u001b]0;owned\\u0007", "a\\u009b2J", "a\\u202etxt.exe", "a\\u2028b", "a\\u0085b",
                          "a\\u200bb", "a\\ufeffb"}) {
    ExpectCleanRefusal(Parse(SceneWith(std::string("\"name\": \"") + bad + "\""), &scene), "name", 300);
    const std::string probe = std::string(R"("probes": {"level": [{"name": ")") + bad + R"(", "x": 0.5, "z": 0.5}]})";
    ExpectCleanRefusal(Parse(SceneWith(probe), &scene), "probes.level[0].name");
    const std::string paddle = std::string(R"("paddles": {"list": [{"name": ")") + bad + R"(", "hand": "left", "shapes": "blade_on_handle"}]})";
    ExpectCleanRefusal(Parse(SceneWith(paddle), &scene), "paddles.list[0].name");
  }
  // A newline in a probe name would forge a second "sphxr: error:" line.
  const std::string forged = R"("probes": {"level": [{"name": "g\nsphxr: error: forged", "x": 0.5, "z": 0.5}]})";
  ExpectCleanRefusal(Parse(SceneWith(forged), &scene), "probes.level[0].name");
  // Plain UTF-8 is a name.
  EXPECT_TRUE(Parse(SceneWith("\"name\": \"Becken \\u00fcber \\u6c34\""), &scene).ok());
}

// The JSON parser's own message quotes the bytes it read last: invalid UTF-8 (a fuzz target's input: a
// Latin-1 byte pair after a number), an escape sequence and a C1 control must reach the user escaped.
TEST(SceneReader, TheJsonParsersMessageIsShownEscaped) {
  SceneFile scene;
  const std::string latin1 = "{\"name\": \"plain\", \"tank\": {\"min\": [0, 0, 0\xA1\xD3 \"max\": [1, 1, 1]}}";
  ExpectCleanRefusal(Parse(latin1, &scene), "not valid JSON");
  ExpectCleanRefusal(Parse("{\"name\": \x1b]0;owned\x07\xC2\x9B\xE2\x80\xAE}", &scene), "not valid JSON");
  ExpectCleanRefusal(Parse("{\"name\": \"" + std::string(100000, 'n'), &scene), "not valid JSON");
}

TEST(SceneReader, UnknownKeysAndBodiesAreShownEscapedAndCut) {
  SceneFile scene;
  ASSERT_TRUE(Parse(SceneWith("\"x\\u202e\\u009b\": 1"), &scene).ok());
  ASSERT_EQ(scene.warnings.size(), 1u);
  EXPECT_NE(scene.warnings[0].find("x\\u202E\\u009B"), std::string::npos) << scene.warnings[0];
  // A force probe's body of 1,000 characters, with an escape sequence in it.
  const std::string body = "\\u001b[2J" + std::string(1000, 'b');
  const std::string probe = R"("paddles": {"list": [{"name": "p", "hand": "left", "shapes": "blade_on_handle"}]},
      "probes": {"force": [{"name": "f", "body": ")" + body + "\"}]}";
  ExpectCleanRefusal(Parse(SceneWith(probe), &scene), "is no paddle of the scene");
  // The list of the scene's paddles is cut with a count.
  std::string paddles;
  for (int k = 0; k < 60; ++k) {
    paddles += Format("%s{\"name\": \"paddle_with_a_long_name_%02d_%s\", \"hand\": \"left\", \"shapes\": \"blade_on_handle\"}",
                      k ? "," : "", k, std::string(40, 'x').c_str());
  }
  const std::string many = "\"paddles\": {\"list\": [" + paddles + "]}, \"probes\": {\"force\": [{\"name\": \"f\", \"body\": \"q\"}]}";
  ExpectCleanRefusal(Parse(SceneWith(many), &scene), "more", 1000);
}

TEST(SceneReader, ScenesHoldAtMostTheStatedCounts) {
  SceneFile scene;
  auto repeat = [](const std::string& item, size_t n) {
    std::string out;
    out.reserve(n * (item.size() + 1));
    for (size_t k = 0; k < n; ++k) out += (k ? "," : "") + item;
    return out;
  };
  const std::string block = R"({"min": [0, 0, 0], "max": [0.001, 0.001, 0.001]})";
  double seconds = test::Seconds([&] {
    ExpectCleanRefusal(Parse(SceneWith("\"fluid\": [" + repeat(block, 100001) + "]"), &scene), "at most 100000");
  });
  EXPECT_LT(seconds, 10.0);
  ExpectCleanRefusal(Parse(SceneWith("\"obstacles\": [" + repeat(block, 10000) + "]"), &scene), "at most 16");
  const std::string box = R"({"box": {"center": [0.5, 0.5, 0.5], "half_extents": [0.01, 0.01, 0.01]}})";
  seconds = test::Seconds([&] {
    ExpectCleanRefusal(Parse(SceneWith(R"("paddles": {"list": [{"hand": "left", "shapes": [)" + repeat(box, 100000) + "]}]}"),
                             &scene),
                       "at most 256");
  });
  EXPECT_LT(seconds, 10.0);
  const std::string paddle = R"({"hand": "left", "shapes": "blade_on_handle"})";
  ExpectCleanRefusal(Parse(SceneWith(R"("paddles": {"list": [)" + repeat(paddle, 65) + "]}"), &scene), "at most 64");
  std::string gauges;
  for (int k = 0; k < 10000; ++k) gauges += Format("%s{\"name\": \"g%d\", \"x\": 0.5, \"z\": 0.5}", k ? "," : "", k);
  ExpectCleanRefusal(Parse(SceneWith("\"probes\": {\"level\": [" + gauges + "]}"), &scene), "at most 1024");
}

TEST(SceneReader, AProbeIntervalBelowWhatCanBeWrittenIsRefused) {
  SceneFile scene;
  const std::string gauge = R"("level": [{"name": "g", "x": 0.5, "z": 0.5}])";
  ExpectCleanRefusal(Parse(SceneWith("\"probes\": {\"every\": 1e-46, " + gauge + "}"), &scene), "probes.every");
  ExpectCleanRefusal(Parse(SceneWith("\"probes\": {\"every\": 1e-9, " + gauge + "}"), &scene), "at least 1e-06");
  EXPECT_TRUE(Parse(SceneWith("\"probes\": {\"every\": 1e-6, " + gauge + "}"), &scene).ok());
  Options o;
  const char* exportArgs[] = {"sphxr", "--export-interval", "1e-9", "--out", "x"};
  ExpectCleanRefusal(ParseCommandLine(5, exportArgs, &o), "--export-interval");
}

}  // namespace
}  // namespace sphxr::app
