// A fluid block that does not hold a whole number of layers is filled with whole layers, and the solver
// says so in one info line with the size filled and the size asked for (a 0.55 m column at 2 cm is
// 0.54 m of water).
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::sim {
namespace {

std::vector<std::string> InfoLinesOfCreate(const SceneSetup& scene) {
  std::vector<std::string> lines;
  const LogLevel level = GetLogLevel();
  SetLogLevel(LogLevel::kInfo);
  SetLogSink([&](LogLevel l, const std::string& line) {
    if (l == LogLevel::kInfo && line.find("fluid[") != std::string::npos) lines.push_back(line);
  });
  std::unique_ptr<Solver> solver;
  const Status st = Solver::Create(scene, ::sphxr::test::TestConfig(), &solver);
  SetLogSink(nullptr);
  SetLogLevel(level);
  EXPECT_TRUE(st.ok()) << st.message();
  return lines;
}

TEST(CutBlock, OneInfoLineGivesTheSizeFilledAndAsked) {
  SceneSetup s = ::sphxr::test::TankScene({0, 0, 0}, {0.3f, 0.7f, 0.1f}, 0.02f);
  s.fluid.push_back(::sphxr::test::Block({0, 0, 0}, {0.1f, 0.55f, 0.1f}));  // 27.5 layers high
  const std::vector<std::string> lines = InfoLinesOfCreate(s);
  ASSERT_EQ(lines.size(), 1u);
  // 27 whole layers of 2 cm: 0.54 m of the 0.55 m asked.
  EXPECT_NE(lines[0].find("fluid[0]: filled 0.1 x 0.54 x 0.1 m of the 0.1 x 0.55 x 0.1 m asked for"), std::string::npos)
      << lines[0];
}

TEST(CutBlock, WholeLayersSayNothing) {
  SceneSetup s = ::sphxr::test::TankScene({0, 0, 0}, {0.3f, 0.7f, 0.1f}, 0.02f);
  s.fluid.push_back(::sphxr::test::Block({0, 0, 0}, {0.1f, 0.54f, 0.1f}));
  s.params.spacing = 0.02f;
  EXPECT_TRUE(InfoLinesOfCreate(s).empty());
  // The dam-break column at a spacing that divides it (0.55 / 0.0212 is not whole either: 25.9 layers).
  SceneSetup t = ::sphxr::test::TankScene({0, 0, 0}, {0.3f, 0.7f, 0.11f}, 0.011f);
  t.fluid.push_back(::sphxr::test::Block({0, 0, 0}, {0.11f, 0.55f, 0.11f}));
  EXPECT_TRUE(InfoLinesOfCreate(t).empty());
}

}  // namespace
}  // namespace sphxr::sim
