// The scene reference is generated from the parameter registry: docs/user/scenes.md holds the output of
// `sphxr --print-scene-reference` between two markers, and fails here when the two disagree.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "sphxr/app/cli.h"
#include "sphxr/app/param_registry.h"

namespace sphxr::app {
namespace {

TEST(SceneReferenceTest, TheUserDocHoldsTheRegistrysReference) {
  const std::string path = SPHXR_SCENES_DIR "/../docs/user/scenes.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const size_t begin = doc.find(kSceneReferenceBegin);
  const size_t end = doc.find(kSceneReferenceEnd);
  ASSERT_NE(begin, std::string::npos) << path << " has no begin marker: " << kSceneReferenceBegin;
  ASSERT_NE(end, std::string::npos) << path << " has no end marker: " << kSceneReferenceEnd;
  ASSERT_LT(begin, end);
  const size_t from = begin + std::string(kSceneReferenceBegin).size() + 1;  // the line after the marker
  EXPECT_EQ(doc.substr(from, end - from), SceneParameterReference())
      << path << " and the registry disagree: put the output of `sphxr --print-scene-reference` between the markers";
}

TEST(SceneReferenceTest, EveryParameterIsARowWithItsRangeAndDefault) {
  const std::string reference = SceneParameterReference();
  for (const ParamDesc& p : ParamRegistry()) {
    const size_t row = reference.find("| `" + p.name + "` | ");
    ASSERT_NE(row, std::string::npos) << p.key;
    const std::string line = reference.substr(row, reference.find('\n', row) - row);
    EXPECT_NE(line.find(p.help), std::string::npos) << line;
    // The default and the range as numbers: each reads back as the registry's value.
    std::istringstream cells(line);
    std::string cell, unit, value, range;
    std::getline(cells, cell, '|');
    std::getline(cells, cell, '|');
    std::getline(cells, unit, '|');
    std::getline(cells, value, '|');
    std::getline(cells, range, '|');
    EXPECT_FLOAT_EQ(static_cast<float>(std::stod(value)), static_cast<float>(p.defaultValue)) << line;  // stored as floats
    const size_t dash = range.find("–");
    ASSERT_NE(dash, std::string::npos) << line;
    EXPECT_DOUBLE_EQ(std::stod(range.substr(0, dash)), p.min) << line;
    EXPECT_DOUBLE_EQ(std::stod(range.substr(dash + std::string("–").size())), p.max) << line;
  }
  EXPECT_NE(reference.find("| `method` |"), std::string::npos) << "the solver's one named key";
}

TEST(SceneReferenceTest, TheCommandLineAsksForIt) {
  const char* argv[] = {"sphxr", "--print-scene-reference"};
  Options o;
  ASSERT_TRUE(ParseCommandLine(2, argv, &o).ok());
  EXPECT_TRUE(o.printSceneReference);
}

}  // namespace
}  // namespace sphxr::app
