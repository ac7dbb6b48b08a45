// The parameter registry: one description per parameter, read by scene files, --set and the panel.
#include <gtest/gtest.h>

#include "sphxr/app/param_registry.h"
#include "sphxr/app/scene_file.h"

namespace sphxr::app {
namespace {

TEST(ParamRegistryTest, SolverEntriesAreSimsTableWithTheirDefaults) {
  const sim::SolverParams defaults;
  int solver = 0;
  for (const sim::ParamInfo& info : sim::SolverParamInfos()) {
    const ParamDesc* p = FindParam(std::string("solver.") + info.key);
    ASSERT_NE(p, nullptr) << info.key;
    EXPECT_EQ(p, FindParam(info.key)) << "bare solver names resolve to the same entry";
    EXPECT_EQ(p->min, info.min);
    EXPECT_EQ(p->max, info.max);
    EXPECT_EQ(p->help, info.help);
    EXPECT_EQ(p->defaultValue, static_cast<double>(defaults.*(info.member)));
    ++solver;
  }
  const sim::ReuseParams reuse;
  EXPECT_EQ(FindParam("reuse.threshold")->defaultValue, static_cast<double>(reuse.threshold));
  EXPECT_EQ(FindParam("reuse.idle")->defaultValue, static_cast<double>(reuse.idle));
  EXPECT_TRUE(FindParam("reuse.idle")->integer);
  EXPECT_EQ(FindParam("threshold"), nullptr) << "reuse keys need their section";
  EXPECT_EQ(FindParam("reuse.impulse"), nullptr) << "retired: the impulse hold is the only hold";
  // delta1, delta2, threshold, pressure_scale, cell_count, idle
  EXPECT_EQ(static_cast<int>(ParamRegistry().size()), solver + 6);
}

TEST(ParamRegistryTest, SceneFilesAndSetReadReuseThroughTheRegistry) {
  SceneFile scene;
  const std::string base = R"({"tank": {"min": [0,0,0], "max": [1,1,1]}, "reuse": )";
  Status s = ParseScene(base + R"({"threshold": 0.7, "idle": 5, "delta2": 2.5}})", "t.json", &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(scene.setup.reuse.enabled);
  EXPECT_FLOAT_EQ(scene.setup.reuse.threshold, 0.7f);
  EXPECT_EQ(scene.setup.reuse.idle, 5);
  EXPECT_FLOAT_EQ(scene.setup.reuse.delta2, 2.5f);
  s = ParseScene(base + R"({"idle": 2000}})", "t.json", &scene);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("reuse.idle: 2000 is out of range: must be from 0 to 1000 steps"), std::string::npos)
      << s.message();
  s = ParseScene(base + R"({"idle": 2.5}})", "t.json", &scene);
  EXPECT_NE(s.message().find("reuse.idle: must be an integer"), std::string::npos) << s.message();
  s = ParseScene(base + R"({"threshold": -1}})", "t.json", &scene);
  EXPECT_NE(s.message().find("reuse.threshold: -1 is out of range"), std::string::npos) << s.message();

  sim::SceneSetup setup;
  ASSERT_TRUE(SetSolverParam(&setup, "reuse.threshold=0.9").ok());
  EXPECT_FLOAT_EQ(setup.reuse.threshold, 0.9f);
  ASSERT_TRUE(SetSolverParam(&setup, "stiffness=2e5").ok());
  EXPECT_FLOAT_EQ(setup.params.stiffness, 2e5f);
  s = SetSolverParam(&setup, "reuse.idle=-1");
  EXPECT_NE(s.message().find("--set reuse.idle: -1 is out of range"), std::string::npos) << s.message();
  s = SetSolverParam(&setup, "nonsense=1");
  EXPECT_NE(s.message().find("reuse.idle"), std::string::npos) << "the known list names the reuse keys: " << s.message();
}

}  // namespace
}  // namespace sphxr::app
