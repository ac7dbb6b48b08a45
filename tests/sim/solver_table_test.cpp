// The solver table (sim/src/solver_table.cpp, sphxr/sim/solver_table.h): what every row promises the
// code that reads it (the scene check, --set, the panel, --quality auto, the stats CSV, the scene
// reference), and each row's stable step against its paper's rule. What each solver then does with a
// scene: tests/sim/solvers/conformance_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include "sphxr/sim/params.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {
namespace {

float SoundSpeedOf(const SolverParams& p) { return std::sqrt(p.exponent * p.stiffness / p.restDensity); }
float SmoothingOf(const SolverParams& p) { return 0.5f * p.spacing * p.supportFactor; }

const SolverInfo& Row(const char* name) {
  const SolverInfo* row = FindSolver(name);
  EXPECT_NE(row, nullptr) << name;
  return row ? *row : SolverTable()[0];
}

TEST(SolverTable, NamesAreUniqueSceneWordsAndEachRowSaysWhatItIs) {
  ASSERT_FALSE(SolverTable().empty());
  std::set<std::string> names;
  std::set<SolverMethod> methods;
  for (const SolverInfo& row : SolverTable()) {
    SCOPED_TRACE(row.name);
    const std::string name = row.name;
    ASSERT_FALSE(name.empty());
    // A scene's `solver.method` is a lower-case word (never a number, STYLE.md).
    EXPECT_TRUE(std::all_of(name.begin(), name.end(), [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; }));
    EXPECT_FALSE(name[0] >= '0' && name[0] <= '9');
    EXPECT_TRUE(names.insert(name).second) << "a second row named " << name;
    EXPECT_TRUE(methods.insert(row.method).second) << "a second row for one SolverMethod";
    EXPECT_GT(std::string(row.paper).size(), 10u);
    EXPECT_GT(std::string(row.summary).size(), 10u);
    EXPECT_NE(row.stableDt, nullptr);
    EXPECT_NE(row.bytesPerFluid, nullptr);
  }
}

TEST(SolverTable, FindSolverAndSolverNamesRoundTrip) {
  std::string joined;
  for (const SolverInfo& row : SolverTable()) {
    EXPECT_EQ(FindSolver(row.name), &row) << row.name;
    EXPECT_EQ(&SolverInfoOf(row.method), &row) << row.name;
    EXPECT_STREQ(SolverMethodName(row.method), row.name);
    SolverMethod parsed{};
    ASSERT_TRUE(ParseSolverMethod(row.name, &parsed)) << row.name;
    EXPECT_EQ(parsed, row.method);
    joined += (joined.empty() ? "" : ", ") + std::string(row.name);
  }
  // Every name of the list a user reads, in the table's order, and nothing else.
  EXPECT_EQ(SolverNames(), joined);
  EXPECT_EQ(FindSolver(""), nullptr);
  EXPECT_EQ(FindSolver("sph"), nullptr);
  EXPECT_EQ(FindSolver(std::string(SolverTable()[0].name) + " "), nullptr) << "names are matched exactly";
  SolverMethod untouched = SolverTable()[0].method;
  EXPECT_FALSE(ParseSolverMethod("WCSPH2", &untouched));
  EXPECT_EQ(untouched, SolverTable()[0].method) << "a refused name leaves the method as it was";
}

// Every SolverMethod has a row (SolverInfoOf asserts it for the others): the enum's values, one by one.
TEST(SolverTable, EachRowIsItsMethodsOnlyRow) {
  std::set<int> methods;
  for (const SolverInfo& row : SolverTable()) {
    EXPECT_TRUE(methods.insert(static_cast<int>(row.method)).second) << row.name << ": a method with two rows";
    EXPECT_EQ(&SolverInfoOf(row.method), &row) << row.name;
  }
  // The methods the scenes and the state files name have rows (a new method is a row, not an edit here).
  for (const SolverMethod m : {SolverMethod::kWcsph, SolverMethod::kDfsph, SolverMethod::kPbf}) {
    EXPECT_TRUE(methods.count(static_cast<int>(m))) << static_cast<int>(m);
  }
}

TEST(SolverTable, StatsHaveColumnNamesAndReadTheirReportField) {
  SolveReport report;
  report.densityIterations = 7;
  report.divergenceIterations = 5;
  report.densityError = 0.25f;
  report.divergenceError = 0.125f;
  // A column's name means one field of the report in every row that has it (the stats CSV of a run
  // continued under another method, and the panel, read it by name).
  std::map<std::string, double> valueOf;
  for (const SolverInfo& row : SolverTable()) {
    std::set<std::string> seen;
    for (const SolveColumn& column : row.columns) {
      EXPECT_TRUE(seen.insert(column.name).second) << row.name << ": " << column.name << " twice";
      EXPECT_TRUE((column.count != nullptr) != (column.fraction != nullptr)) << row.name << ": " << column.name
                                                                            << " reads one field";
      const double value = column.Value(report);
      EXPECT_TRUE(value == 7.0 || value == 5.0 || value == 0.25 || value == 0.125) << column.name << " " << value;
      auto [it, fresh] = valueOf.emplace(column.name, value);
      if (!fresh) {
        EXPECT_EQ(it->second, value) << column.name << " reads another field in " << row.name;
      }
    }
  }
  // An iteration count is a count, an error a fraction.
  for (const auto& [name, value] : valueOf) {
    if (name.find("iterations") != std::string::npos) {
      EXPECT_GE(value, 1.0) << name;
    }
    if (name.find("error") != std::string::npos) {
      EXPECT_LT(value, 1.0) << name;
    }
  }
}

TEST(SolverTable, ParametersNamedByARowAreInTheRegistryAndNameRows) {
  for (const SolverInfo& row : SolverTable()) {
    if (!row.speedCapParam) continue;
    const ParamInfo* cap = FindSolverParam(row.speedCapParam);
    ASSERT_NE(cap, nullptr) << row.name << ": " << row.speedCapParam;
    ASSERT_NE(cap->method, nullptr) << row.speedCapParam << " is the row's own parameter";
    EXPECT_STREQ(cap->method, row.name);
    EXPECT_GT(cap->min, 0.0) << "a speed cap of 0 would stop the water";
  }
  // The registry's method column names rows only (the panel shows a parameter with its row's method).
  for (const ParamInfo& p : SolverParamInfos()) {
    if (p.method) {
      EXPECT_NE(FindSolver(p.method), nullptr) << p.key << " belongs to " << p.method;
    }
  }
}

TEST(SolverTable, BytesPerFluidGrowWithTheNeighbourSlots) {
  for (const SolverInfo& row : SolverTable()) {
    SCOPED_TRACE(row.name);
    int64_t last = row.bytesPerFluid(0);
    EXPECT_GE(last, 0);
    for (const int64_t slots : {1, 16, 17, 64, 200, 1000}) {
      const int64_t bytes = row.bytesPerFluid(slots);
      EXPECT_GE(bytes, last) << slots << " slots";
      last = bytes;
    }
  }
}

// Every row's stable step is a positive, finite time, and never longer for a faster flow or a larger
// acceleration, from rest to a flow at PBF's speed cap (20 m/s) and 100 g.
TEST(SolverTable, EveryRowsStableStepIsPositiveAndShrinksWithTheFlow) {
  SceneSetup scene;
  scene.params.spacing = 0.01f;
  for (const SolverInfo& row : SolverTable()) {
    SCOPED_TRACE(row.name);
    float last = INFINITY;
    for (const float speed : {0.0f, 0.1f, 1.0f, 5.0f, 20.0f}) {
      for (const float accel : {9.81f, 100.0f, 981.0f}) {
        const float dt = row.stableDt(StableDtInput{scene, speed, accel});
        EXPECT_TRUE(std::isfinite(dt) && dt > 0.0f) << speed << " m/s, " << accel << " m/s^2: " << dt;
        if (accel == 9.81f) {
          EXPECT_LE(dt, last) << "a faster flow, " << speed << " m/s, allowed a longer step";
          last = dt;
        }
        EXPECT_LE(dt, row.stableDt(StableDtInput{scene, speed, 9.81f})) << "a larger acceleration allowed a longer step";
      }
    }
  }
}

// WCSPH (Becker & Teschner 2007, sec. 5): at rest the acoustic CFL step cfl h / c, under max_dt; the
// step is bounded by max_dt wherever the flow allows a longer one.
TEST(SolverTable, WcsphsStepIsTheAcousticCflBoundedByMaxDt) {
  const SolverInfo& row = Row("wcsph");
  SceneSetup scene;
  scene.params.spacing = 0.01f;
  const SolverParams& p = scene.params;
  const float acoustic = p.cfl * SmoothingOf(p) / SoundSpeedOf(p);
  ASSERT_LT(acoustic, p.maxDt);
  EXPECT_NEAR(row.stableDt(StableDtInput{scene, 0.0f, 9.81f}), acoustic, 1e-6f * acoustic);
  EXPECT_NEAR(row.stableDt(StableDtInput{scene, 2.0f, 9.81f}), p.cfl * SmoothingOf(p) / (SoundSpeedOf(p) + 2.0f), 1e-6f * acoustic);
  scene.params.maxDt = 0.5f * acoustic;
  EXPECT_EQ(row.stableDt(StableDtInput{scene, 0.0f, 9.81f}), scene.params.maxDt);
}

// DFSPH (Bender & Koschier 2017, sec. 5): the step follows the flow, cfl h / v, bounded by max_dt; the
// sound speed does not enter.
TEST(SolverTable, DfsphsStepFollowsTheFlowBoundedByMaxDt) {
  const SolverInfo& row = Row("dfsph");
  SceneSetup scene;
  scene.params.spacing = 0.01f;
  const SolverParams& p = scene.params;
  EXPECT_EQ(row.stableDt(StableDtInput{scene, 0.0f, 9.81f}), p.maxDt) << "at rest";
  const float v = 10.0f, flow = p.cfl * SmoothingOf(p) / v;
  ASSERT_LT(flow, p.maxDt);
  EXPECT_NEAR(row.stableDt(StableDtInput{scene, v, 9.81f}), flow, 1e-6f * flow);
  scene.params.stiffness *= 100.0f;  // a hundred times the sound speed's square
  EXPECT_NEAR(row.stableDt(StableDtInput{scene, v, 9.81f}), flow, 1e-6f * flow);
}

// PBF (Macklin & Müller 2013): pbf_substeps steps a displayed frame, whatever the flow; max_dt and cfl
// are not its (pbf_frame's help in the registry says so).
TEST(SolverTable, PbfsStepIsItsFrameOverItsSubsteps) {
  const SolverInfo& row = Row("pbf");
  SceneSetup scene;
  const float step = scene.params.pbfFrame / scene.params.pbfSubsteps;
  for (const float speed : {0.0f, 20.0f}) {
    EXPECT_FLOAT_EQ(row.stableDt(StableDtInput{scene, speed, 981.0f}), step);
  }
  scene.params.maxDt = 1e-5f;
  EXPECT_FLOAT_EQ(row.stableDt(StableDtInput{scene, 0.0f, 9.81f}), step);
}

}  // namespace
}  // namespace sphxr::sim
