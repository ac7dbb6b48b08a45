// The scene's "probes" section and the probe CSV (app/src/scene_probes.cpp, app/src/probe_csv.cpp): what
// parses, what is refused naming the key, and rows exactly `every` apart in simulated time whatever the
// solver's step.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "sphxr/app/probe_csv.h"
#include "sphxr/app/probe_history.h"
#include "sphxr/app/simulation.h"
#include "sphxr/app/scene_file.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::app {
namespace {

std::string Scene(const std::string& probes) {
  return R"({
  "solver": { "spacing": 0.01, "max_dt": 0.001 },
  "tank": { "min": [0, 0, 0], "max": [0.3, 0.2, 0.06] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.15, 0.06] } ],
  "probes": )" + probes + "}";
}

constexpr const char* kProbes = R"({ "every": 0.001,
    "pressure": [ { "name": "P1", "at": [0.3, 0.02, 0.03], "normal": [1, 0, 0] },
                  { "name": "P2", "at": [0.0, 0.05, 0.03], "normal": [-2, 0, 0], "offset": 0.002 },
                  { "name": "in", "at": [0.05, 0.05, 0.03] } ],
    "level": [ { "name": "G1", "x": 0.05, "z": 0.03 }, { "name": "G2", "x": 0.2, "z": 0.03, "bottom": 0.0, "top": 0.1 } ] })";

TEST(ProbeScene, ParsesTheSection) {
  SceneFile scene;
  const Status s = ParseScene(Scene(kProbes), "test.json", &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(scene.probes.has_value());
  const ProbeConfig& p = *scene.probes;
  EXPECT_EQ(p.every, 0.001);
  ASSERT_EQ(p.set.pressure.size(), 3u);
  EXPECT_EQ(p.set.pressure[0].name, "P1");
  EXPECT_FALSE(p.set.pressure[0].offset.has_value());
  EXPECT_FLOAT_EQ(p.set.pressure[1].normal.x, -1.0f) << "the normal is normalised";
  EXPECT_FLOAT_EQ(*p.set.pressure[1].offset, 0.002f);
  ASSERT_EQ(p.set.level.size(), 2u);
  EXPECT_FALSE(p.set.level[0].top.has_value());
  EXPECT_FLOAT_EQ(*p.set.level[1].top, 0.1f);
  EXPECT_TRUE(scene.warnings.empty());
}

void ExpectRefused(const std::string& probes, std::initializer_list<std::string> needles) {
  SceneFile scene;
  const Status s = ParseScene(Scene(probes), "test.json", &scene);
  ASSERT_FALSE(s.ok()) << "should be refused: " << probes;
  for (const std::string& n : needles) {
    EXPECT_NE(s.message().find(n), std::string::npos) << "message should contain '" << n << "': " << s.message();
  }
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line: " << s.message();
}

TEST(ProbeScene, RefusesBadProbesNamingTheKey) {
  ExpectRefused(R"({ "every": 0 })", {"probes.every", "at least 1e-06 s"});
  ExpectRefused(R"({ "every": -1 })", {"probes.every"});
  ExpectRefused(R"({ "pressure": [ { "name": "P", "at": [0.5, 0.1, 0.03] } ] })", {"probes.pressure[0].at", "outside the tank"});
  ExpectRefused(R"({ "pressure": [ { "name": "P", "at": [0.3, 0.1, 0.03], "normal": [-1, 0, 0] } ] })",
                {"probes.pressure[0].offset", "outside the tank"});
  ExpectRefused(R"({ "pressure": [ { "at": [0.1, 0.1, 0.03] } ] })", {"probes.pressure[0].name"});
  ExpectRefused(R"({ "pressure": [ { "name": "A", "at": [0.1, 0.1, 0.03] } ], "level": [ { "name": "A", "x": 0.1, "z": 0.03 } ] })",
                {"probes.level[0].name", "another probe"});
  ExpectRefused(R"({ "level": [ { "name": "G", "x": 0.1, "z": 0.5 } ] })", {"probes.level[0].z", "outside the tank"});
  ExpectRefused(R"({ "level": [ { "name": "G", "x": 0.1, "z": 0.03, "bottom": 0.1, "top": 0.05 } ] })", {"probes.level[0].top"});
  ExpectRefused(R"({ "force": [ { "name": "F", "body": "box1" } ] })", {"probes.force[0].body", "box1", "no paddle"});
  ExpectRefused(R"({ "pressure": [ { "name": "a,b", "at": [0.1, 0.1, 0.03] } ] })", {"probes.pressure[0].name", "comma"});
}

/// The file's rows as numbers (an empty cell: NaN), after its header.
std::vector<std::vector<double>> ReadRows(const std::string& path, std::string* header) {
  std::ifstream in(path);
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<double> row;
    std::stringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(cell.empty() ? std::nan("") : std::stod(cell));
    if (!line.empty() && line.back() == ',') row.push_back(std::nan(""));
    rows.push_back(row);
  }
  return rows;
}

// Readings at uneven times of quantities linear in time: the rows fall exactly on the multiples of
// `every` and carry the line's values there (linear interpolation reproduces a line to rounding); a dry
// reading on either side of a row leaves its cell empty.
TEST(ProbeCsv, RowsAtEveryMultipleInterpolated) {
  const std::string path = ::testing::TempDir() + "probe_rows.csv";
  ProbeConfig config;
  config.every = 0.001;
  config.set.pressure.push_back({"P", {}, {}, {}});
  config.set.level.push_back({"G", 0, 0, {}, {}});
  std::unique_ptr<ProbeCsv> csv;
  ASSERT_TRUE(ProbeCsv::Open(path, config, 0.0, &csv).ok());
  auto pressure = [](double t) { return 1000.0 + 5.0e5 * t; };
  auto level = [](double t) { return 0.2 - 3.0 * t; };
  double t = 0.0;
  int64_t step = 0;
  for (double dt : {0.0004, 0.00037, 0.0009, 0.0013, 0.00021, 0.0007, 0.0025, 0.0004}) {
    sim::ProbeSample s;
    s.time = t;
    s.steps = step++;
    // Dry between 4 and 5 ms.
    s.pressure = {t > 0.004 && t < 0.005 ? std::nanf("") : static_cast<float>(pressure(t))};
    s.level = {static_cast<float>(level(t))};
    ASSERT_TRUE(csv->Add(s).ok());
    t += dt;
  }
  const double last = t - 0.0004;  // the last reading's time
  csv.reset();
  std::string header;
  const auto rows = ReadRows(path, &header);
  EXPECT_EQ(header, "time,step,P_p,G_level");
  ASSERT_EQ(rows.size(), static_cast<size_t>(std::floor(last / 0.001)) + 1);
  for (size_t k = 0; k < rows.size(); ++k) {
    SCOPED_TRACE("row " + std::to_string(k));
    ASSERT_EQ(rows[k].size(), 4u);
    EXPECT_NEAR(rows[k][0], 0.001 * k, 1e-12);
    EXPECT_NEAR(rows[k][3], level(0.001 * k), 1e-6);
    const bool dryNear = rows[k][0] > 0.0036 && rows[k][0] < 0.0063;  // a bracketing reading is dry
    if (std::isnan(rows[k][2])) {
      EXPECT_TRUE(dryNear);
    } else {
      EXPECT_NEAR(rows[k][2], pressure(0.001 * k), 1e-6 * pressure(0.001 * k));
    }
  }
  std::filesystem::remove(path);
}

// With the solver's adaptive step, rows come 1 ms apart whatever the step: a small dam break, whose step
// changes as the water speeds up.
TEST(ProbeCsv, SolverRowsOneMillisecondApart) {
  SceneFile scene;
  ASSERT_TRUE(ParseScene(Scene(kProbes), "test.json", &scene).ok());
  std::unique_ptr<sim::Solver> solver;
  ASSERT_TRUE(sim::Solver::Create(scene.setup, ::sphxr::test::TestConfig(), &solver).ok());
  ASSERT_TRUE(solver->SetProbes(scene.probes->set).ok());
  const std::string path = ::testing::TempDir() + "probe_solver.csv";
  std::unique_ptr<ProbeCsv> csv;
  ASSERT_TRUE(ProbeCsv::Open(path, *scene.probes, 0.0, &csv).ok());
  float smallest = 1.0f, largest = 0.0f;
  while (solver->Time() < 0.02) {
    ASSERT_TRUE(solver->Step().ok());
    smallest = std::min(smallest, solver->LastStep().dt);
    largest = std::max(largest, solver->LastStep().dt);
    ASSERT_TRUE(csv->Add(solver->LastProbes()).ok());
  }
  csv.reset();
  EXPECT_LT(smallest, largest) << "the step should change (adaptive)";
  std::string header;
  const auto rows = ReadRows(path, &header);
  EXPECT_EQ(header, "time,step,P1_p,P2_p,in_p,G1_level,G2_level");
  ASSERT_GE(rows.size(), 19u);
  for (size_t k = 0; k < rows.size(); ++k) {
    EXPECT_NEAR(rows[k][0], 0.001 * k, 1e-12) << "row " << k;
    EXPECT_FALSE(std::isnan(rows[k][4])) << "the point in the water column is wet";
    EXPECT_GT(rows[k][5], 0.1) << "the gauge in the column sees its water";
  }
  std::filesystem::remove(path);
}

// The panels' plots: a trace per probe, a point every span / kPoints simulated seconds, the last
// kPoints kept; and a Simulation built from a scene with probes reads them in every step.
TEST(ProbeHistory, KeepsTheLastSecondsOfEveryProbe) {
  SceneFile scene;
  ASSERT_TRUE(ParseScene(Scene(kProbes), "test.json", &scene).ok());
  const SimScene simScene = SimSceneFromFile(scene);
  ASSERT_EQ(simScene.probes.pressure.size(), 3u);
  std::unique_ptr<Simulation> simulation;
  SimulationConfig config;
  config.solver = ::sphxr::test::TestConfig();
  ASSERT_TRUE(Simulation::Create(simScene, config, &simulation).ok());
  const double span = 0.01;  // s: a point every span / kPoints
  ProbeHistory history(simScene.probes, span);
  ASSERT_EQ(history.Traces().size(), 5u);
  EXPECT_EQ(history.Traces()[0].label, "P1 (Pa)");
  EXPECT_EQ(history.Traces()[3].label, "G1 (m)");
  int steps = 0;
  while (simulation->Solver().Time() < 0.02) {
    ASSERT_TRUE(simulation->Step().ok());
    history.Add(simulation->Solver().LastProbes());
    ++steps;
  }
  for (const ProbeTrace& t : history.Traces()) {
    // More steps than points: the points are thinned to the span's, and only the last kPoints kept.
    EXPECT_LE(t.values.size(), static_cast<size_t>(ProbeHistory::kPoints)) << t.label;
    EXPECT_GT(t.values.size(), 0u) << t.label;
    EXPECT_LE(t.values.size(), static_cast<size_t>(steps)) << t.label;
  }
  EXPECT_EQ(history.Traces()[3].values.back(), simulation->Solver().LastProbes().level[0]);
}

}  // namespace
}  // namespace sphxr::app
