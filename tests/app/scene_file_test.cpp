// Scene files (app/src/scene_file.cpp): what parses, what is warned about by name, what is refused with
// the key and the reason; the solver's own validation of what the parser lets through.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "sphxr/app/scene_file.h"
#include "sphxr/sim/solver.h"
#include "support.h"

namespace sphxr::app {
namespace {

const char* kMinimal = R"({
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1] },
  "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1] } ]
})";

/// Parses `text`; the test fails if it does not parse.
SceneFile ParseOk(const std::string& text) {
  SceneFile scene;
  const Status s = ParseScene(text, "test.json", &scene);
  EXPECT_TRUE(s.ok()) << s.message() << "\nscene: " << text;
  return scene;
}

/// Parses `text` expecting a refusal whose message contains every one of `needles`.
void ExpectRefused(const std::string& text, std::initializer_list<std::string> needles) {
  SceneFile scene;
  const Status s = ParseScene(text, "test.json", &scene);
  ASSERT_FALSE(s.ok()) << "should be refused: " << text;
  EXPECT_NE(s.message().find("test.json"), std::string::npos) << "message must name the file: " << s.message();
  for (const std::string& n : needles) {
    EXPECT_NE(s.message().find(n), std::string::npos) << "message should contain '" << n << "': " << s.message();
  }
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << "one line: " << s.message();
}

/// Parses `text` (must parse) and expects Solver::Create to refuse it with every one of `needles`.
void ExpectSolverRefuses(const std::string& text, std::initializer_list<std::string> needles) {
  const SceneFile scene = ParseOk(text);
  std::unique_ptr<sim::Solver> solver;
  const Status s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok()) << "Solver::Create should refuse: " << text;
  EXPECT_EQ(solver, nullptr);
  for (const std::string& n : needles) {
    EXPECT_NE(s.message().find(n), std::string::npos) << "message should contain '" << n << "': " << s.message();
  }
}

TEST(SceneFileTest, MinimalSceneParses) {
  const SceneFile scene = ParseOk(kMinimal);
  EXPECT_TRUE(scene.warnings.empty());
  EXPECT_EQ(scene.path, "test.json");
  EXPECT_FLOAT_EQ(scene.setup.tank.max.x, 0.2f);
  EXPECT_FLOAT_EQ(scene.setup.tank.max.z, 0.1f);
  ASSERT_EQ(scene.setup.fluid.size(), 1u);
  EXPECT_FLOAT_EQ(scene.setup.fluid[0].box.max.y, 0.1f);
  EXPECT_FLOAT_EQ(scene.setup.fluid[0].velocity.x, 0.0f);
  // everything not given keeps the documented defaults
  const sim::SceneSetup defaults;
  EXPECT_EQ(scene.setup.params.spacing, defaults.params.spacing);
  EXPECT_EQ(scene.setup.params.stiffness, defaults.params.stiffness);
  EXPECT_EQ(scene.setup.gravity.y, defaults.gravity.y);
  EXPECT_EQ(scene.setup.openTop, defaults.openTop);
  EXPECT_EQ(scene.setup.boundaryLayers, defaults.boundaryLayers);
  EXPECT_EQ(scene.runSettle, 0.0) << "no settling unless the scene asks";
  EXPECT_FALSE(scene.damBreak.has_value());
  // and the solver accepts it: 5 x 5 x 5 particles at the default spacing 0.02 m
  std::unique_ptr<sim::Solver> solver;
  const Status s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(solver->FluidCount(), 125);
}

TEST(SceneFileTest, FullSceneParsesEveryKey) {
  const SceneFile scene = ParseOk(R"({
    "name": "full", "description": "every key",
    "solver": { "spacing": 0.01, "support_factor": 2.5, "rest_density": 998, "stiffness": 1e5, "exponent": 7,
                "viscosity": 0.1, "boundary_viscosity": 0.2, "cfl": 0.3, "max_dt": 5e-4, "fixed_dt": 1e-4 },
    "gravity": [0, -1.62, 0],
    "tank": { "min": [-1, 0, -0.5], "max": [1, 1, 0.5], "open_top": false, "boundary_layers": 2,
              "friction": { "walls": "no_slip", "x_max": "artificial", "floor": "free_slip", "obstacles": "no_slip" },
              "wall_pressure": "wall_density" },
    "fluid": [ { "min": [-1, 0, -0.5], "max": [0, 0.5, 0.5], "velocity": [1, 0, -2] },
               { "min": [0.5, 0.5, 0], "max": [0.6, 0.6, 0.1] } ],
    "obstacles": [ { "min": [0.2, 0, -0.1], "max": [0.3, 0.2, 0.1] } ],
    "run": { "time": 1.5, "steps": 100, "settle": 12.5 },
    "probe": { "dam_break_column_width": 0.25 }
  })");
  EXPECT_TRUE(scene.warnings.empty());
  EXPECT_EQ(scene.name, "full");
  EXPECT_EQ(scene.description, "every key");
  const sim::SolverParams& p = scene.setup.params;
  EXPECT_FLOAT_EQ(p.spacing, 0.01f);
  EXPECT_FLOAT_EQ(p.supportFactor, 2.5f);
  EXPECT_FLOAT_EQ(p.restDensity, 998.0f);
  EXPECT_FLOAT_EQ(p.stiffness, 1e5f);
  EXPECT_FLOAT_EQ(p.exponent, 7.0f);
  EXPECT_FLOAT_EQ(p.viscosity, 0.1f);
  EXPECT_FLOAT_EQ(p.boundaryViscosity, 0.2f);
  EXPECT_FLOAT_EQ(p.cfl, 0.3f);
  EXPECT_FLOAT_EQ(p.maxDt, 5e-4f);
  EXPECT_FLOAT_EQ(p.fixedDt, 1e-4f);
  EXPECT_FLOAT_EQ(scene.setup.gravity.y, -1.62f);
  EXPECT_FALSE(scene.setup.openTop);
  EXPECT_EQ(scene.setup.boundaryLayers, 2);
  const sim::TankFriction& f = scene.setup.friction;
  EXPECT_EQ(f.floor, sim::WallFriction::kFreeSlip);
  EXPECT_EQ(f.top, sim::WallFriction::kArtificial);  // not named: the default
  EXPECT_EQ(f.xMin, sim::WallFriction::kNoSlip);     // "walls"
  EXPECT_EQ(f.xMax, sim::WallFriction::kArtificial);  // named on its own: overrides "walls"
  EXPECT_EQ(f.zMin, sim::WallFriction::kNoSlip);
  EXPECT_EQ(f.zMax, sim::WallFriction::kNoSlip);
  EXPECT_EQ(f.obstacles, sim::WallFriction::kNoSlip);
  EXPECT_EQ(scene.setup.wallPressure, sim::SceneSetup::WallPressure::kWallDensity);
  ASSERT_EQ(scene.setup.fluid.size(), 2u);
  EXPECT_FLOAT_EQ(scene.setup.fluid[0].velocity.z, -2.0f);
  ASSERT_EQ(scene.setup.obstacles.size(), 1u);
  EXPECT_FLOAT_EQ(scene.setup.obstacles[0].max.y, 0.2f);
  EXPECT_DOUBLE_EQ(scene.runTime, 1.5);
  EXPECT_EQ(scene.runSteps, 100);
  EXPECT_DOUBLE_EQ(scene.runSettle, 12.5);
  ASSERT_TRUE(scene.damBreak.has_value());
  EXPECT_FLOAT_EQ(scene.damBreak->columnWidth, 0.25f);
  EXPECT_FLOAT_EQ(scene.damBreak->wallX, -1.0f);
  EXPECT_FLOAT_EQ(scene.damBreak->depth, 1.0f);
}

TEST(SceneFileTest, UnknownKeysAreWarnedByName) {
  test::LogCapture log;
  const SceneFile scene = ParseOk(R"({
    "tank": { "min": [0, 0, 0], "max": [0.2, 0.2, 0.1], "lid": true },
    "fluid": [ { "min": [0, 0, 0], "max": [0.1, 0.1, 0.1], "colour": "blue" } ],
    "solver": { "spacing": 0.02, "stifness": 1000 },
    "gravitee": [0, -9.81, 0]
  })");
  auto warned = [&](const std::string& key) {
    for (const std::string& w : scene.warnings)
      if (w.find("'" + key + "'") != std::string::npos) return true;
    return false;
  };
  EXPECT_EQ(scene.warnings.size(), 4u);
  EXPECT_TRUE(warned("gravitee"));
  EXPECT_TRUE(warned("tank.lid"));
  EXPECT_TRUE(warned("fluid[0].colour"));
  EXPECT_TRUE(warned("solver.stifness"));
  EXPECT_EQ(log.Count("stifness", LogLevel::kWarn), 1) << "also logged once:\n" << log.All();
  // the misspelt key did not change anything
  EXPECT_EQ(scene.setup.params.stiffness, sim::SolverParams{}.stiffness);
}

TEST(SceneFileTest, SurfaceSectionParsesOnlyWhenPresent) {
  EXPECT_FALSE(ParseOk(kMinimal).surface.has_value());
  std::string text = kMinimal;
  text.insert(text.rfind('}'), R"(, "surface": { "cell_size": 0.005, "iso_level": 0.4, "margin": 0.02 })");
  const SceneFile scene = ParseOk(text);
  ASSERT_TRUE(scene.surface.has_value());
  EXPECT_FLOAT_EQ(scene.surface->cellSize, 0.005f);
  EXPECT_FLOAT_EQ(scene.surface->isoLevel, 0.4f);
  EXPECT_FLOAT_EQ(scene.surface->margin, 0.02f);
  // Absent keys keep the defaults (cell = spacing, iso 0.5, margin = support radius).
  text = kMinimal;
  text.insert(text.rfind('}'), R"(, "surface": { "cell_size": 0.01, "smoothing": 2 })");
  const SceneFile partial = ParseOk(text);
  ASSERT_TRUE(partial.surface.has_value());
  EXPECT_FLOAT_EQ(partial.surface->isoLevel, 0.5f);
  EXPECT_LT(partial.surface->margin, 0.0f);
  ASSERT_EQ(partial.warnings.size(), 1u);
  EXPECT_NE(partial.warnings[0].find("surface.smoothing"), std::string::npos);
  for (const char* bad : {R"("surface": { "cell_size": -1 })", R"("surface": { "iso_level": 0 })",
                          R"("surface": { "iso_level": 12 })", R"("surface": { "margin": "big" })",
                          R"("surface": [1, 2])"}) {
    text = kMinimal;
    text.insert(text.rfind('}'), std::string(", ") + bad);
    ExpectRefused(text, {"surface"});
  }
}

TEST(SceneFileTest, InvalidJsonRefused) {
  ExpectRefused("{ \"tank\": { \"min\": [0, 0, 0], ", {"not valid JSON"});
  ExpectRefused("", {"not valid JSON"});
  ExpectRefused("[1, 2, 3]", {"JSON object"});
}

TEST(SceneFileTest, NegativeSpacingRefused) {
  ExpectRefused(R"({ "solver": { "spacing": -0.01 }, "tank": { "min": [0,0,0], "max": [1,1,1] } })",
                {"solver.spacing", "out of range", "-0.01"});
}

TEST(SceneFileTest, NonNumbersRefused) {
  const std::string tank = R"("tank": { "min": [0,0,0], "max": [1,1,1] })";
  ExpectRefused(R"({ "solver": { "spacing": "0.01" }, )" + tank + "}", {"solver.spacing", "must be a number"});
  ExpectRefused(R"({ "solver": { "spacing": null }, )" + tank + "}", {"solver.spacing", "must be a number"});
  ExpectRefused(R"({ "solver": { "stiffness": true }, )" + tank + "}", {"solver.stiffness", "must be a number"});
  // NaN is not JSON
  ExpectRefused(R"({ "solver": { "spacing": NaN }, )" + tank + "}", {"not valid JSON"});
  ExpectRefused(R"({ "solver": { "spacing": Infinity }, )" + tank + "}", {"not valid JSON"});
  ExpectRefused(R"({ "gravity": [0, "down", 0], )" + tank + "}", {"gravity[1]", "must be a number"});
  ExpectRefused(R"({ "run": { "time": "long" }, )" + tank + "}", {"run.time", "must be a number"});
  ExpectRefused(R"({ "run": { "settle": "yes" }, )" + tank + "}", {"run.settle", "must be a number"});
  ExpectRefused(R"({ "run": { "settle": -1 }, )" + tank + "}", {"run.settle", "0 to 3600 seconds"});
  ExpectRefused(R"({ "run": { "settle": 1e5 }, )" + tank + "}", {"run.settle", "0 to 3600 seconds"});
}

// A number literal too large for a double (1e999) makes nlohmann::json::parse throw json::out_of_range
// (406), not a parse_error: it must still come back as a one-line error, not abort the program.
TEST(SceneFileTest, NumberOverflowRefusedWithoutThrowing) {
  const std::string tank = R"("tank": { "min": [0,0,0], "max": [1,1,1] })";
  for (const std::string& text : {R"({ "solver": { "stiffness": 1e999 }, )" + tank + "}",
                                  R"({ "gravity": [0, -1e999, 0], )" + tank + "}"}) {
    SceneFile scene;
    Status s;
    EXPECT_NO_THROW(s = ParseScene(text, "test.json", &scene)) << text;
    EXPECT_FALSE(s.ok()) << text;
    EXPECT_NE(s.message().find("test.json"), std::string::npos) << s.message();
  }
}

// 4294967297 (2^32 + 1) must not narrow to 1 and be accepted: the range check runs on the 64-bit value.
// Scene numbers are stored as floats: a finite double beyond the float range is refused by key
// (converting it is undefined behaviour), not turned into infinity.
TEST(SceneFileTest, NumbersBeyondTheFloatRangeRefused) {
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1e39,1,1] } })", {"tank.max[0]", "beyond the range of a float"});
  ExpectRefused(R"({ "solver": { "stiffness": -1e300 }, "tank": { "min": [0,0,0], "max": [1,1,1] } })",
                {"solver.stiffness", "beyond the range of a float"});
}

// A block's start velocity is bounded like gravity (1e30 m/s passed and the first step collapsed with
// a message about instability, not about the key).
TEST(SceneFileTest, AHugeBlockVelocityIsRefusedBySolver) {
  const SceneFile scene = ParseOk(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.2] },
                                       "fluid": [ { "min": [0,0,0], "max": [0.1,0.1,0.1], "velocity": [1e30, 0, 0] } ] })");
  std::unique_ptr<sim::Solver> solver;
  const Status s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("fluid[0].velocity"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("at most 1000 m/s"), std::string::npos) << s.message();
}

// A binary file's bytes quoted by the JSON parser do not reach the terminal raw.
TEST(SceneFileTest, ControlBytesInAParseErrorAreReplaced) {
  SceneFile scene;
  const Status s = ParseScene(std::string("{\"a\": \x01\x7f\x1b[31m"), "bin.json", &scene);
  ASSERT_FALSE(s.ok());
  for (char c : s.message()) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << s.message();
}

TEST(SceneFileTest, HugeIntegerBoundaryLayersRefused) {
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "boundary_layers": 4294967297 } })",
                {"tank.boundary_layers"});
}

TEST(SceneFileTest, WrongTypesRefused) {
  const std::string tank = R"("tank": { "min": [0,0,0], "max": [1,1,1] })";
  ExpectRefused(R"({ "name": 5, )" + tank + "}", {"name", "string"});
  ExpectRefused(R"({ "solver": [1, 2], )" + tank + "}", {"solver", "object"});
  ExpectRefused(R"({ "tank": [0, 1] })", {"tank", "object"});
  ExpectRefused(R"({ "tank": { "min": [0, 0], "max": [1, 1, 1] } })", {"tank.min", "three numbers"});
  ExpectRefused(R"({ "tank": { "max": [1, 1, 1] } })", {"tank", "min"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "open_top": "yes" } })", {"tank.open_top", "true or false"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "boundary_layers": 1.5 } })",
                {"tank.boundary_layers", "integer"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "boundary_layers": 9 } })",
                {"tank.boundary_layers", "1 to 4"});
  // The fitted floor viscosity is gone; a scene that still sets it is refused (not silently run
  // with another friction).
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "floor_viscosity": 1 } })",
                {"tank.floor_viscosity", "removed", "tank.friction"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "friction": "sticky" } })",
                {"tank.friction", "no_slip", "free_slip", "artificial"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "friction": { "floor": 1 } } })",
                {"tank.friction.floor", "no_slip"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "friction": { "walls": "rough" } } })",
                {"tank.friction.walls", "no_slip"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "friction": [ "no_slip" ] } })",
                {"tank.friction", "object of faces"});
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1], "wall_pressure": "adami" } })",
                {"tank.wall_pressure", "mirrored", "wall_density"});
  ExpectRefused(R"({ "fluid": { "min": [0,0,0], "max": [1,1,1] }, )" + tank + "}", {"fluid", "array"});
  ExpectRefused(R"({ "fluid": [ 3 ], )" + tank + "}", {"fluid[0]", "object"});
  ExpectRefused(R"({ "fluid": [ { "min": [0,0,0], "max": [1,1,1] }, { "min": [0,0,0] } ], )" + tank + "}",
                {"fluid[1]", "max"});
  ExpectRefused(R"({ "fluid": [ { "min": [0,0,0], "max": [1,1,1], "velocity": 2 } ], )" + tank + "}",
                {"fluid[0].velocity", "three numbers"});
  ExpectRefused(R"({ "obstacles": [ { "min": [0,0,0], "max": ["a",1,1] } ], )" + tank + "}", {"obstacles[0].max[0]"});
  ExpectRefused(R"({ "run": { "steps": 2.5 }, )" + tank + "}", {"run.steps", "positive integer"});
  ExpectRefused(R"({ "run": { "steps": -3 }, )" + tank + "}", {"run.steps", "positive integer"});
  ExpectRefused(R"({ "run": { "time": 0 }, )" + tank + "}", {"run.time", "positive"});
  ExpectRefused(R"({ "probe": { "dam_break_column_width": -1 }, )" + tank + "}", {"probe.dam_break_column_width"});
}

TEST(SceneFileTest, MissingTankRefused) {
  ExpectRefused(R"({ "fluid": [ { "min": [0,0,0], "max": [1,1,1] } ] })", {"tank", "missing"});
  ExpectRefused("{}", {"tank", "missing"});
}

// The reuse section: a preset first, then the keys it names. The retired keys of the held acceleration
// and live density (`impulse`, `accel_tolerance`) are named in one warning each and change nothing.
TEST(SceneFileTest, ReuseSectionAppliesThePresetThenItsKeys) {
  const SceneFile scene = ParseOk(R"({ "tank": { "min": [0,0,0], "max": [1,1,1] },
                                       "reuse": { "preset": "balanced", "impulse": 2, "idle": 1,
                                                  "accel_tolerance": 0.3 } })");
  sim::ReuseParams balanced;
  ASSERT_TRUE(sim::ApplyReusePreset("balanced", &balanced));
  const sim::ReuseParams& r = scene.setup.reuse;
  EXPECT_TRUE(r.enabled);
  EXPECT_EQ(r.threshold, balanced.threshold);
  EXPECT_EQ(r.delta1, balanced.delta1);
  EXPECT_EQ(r.idle, 1);
  EXPECT_EQ(balanced.idle, 3);
  ASSERT_EQ(scene.warnings.size(), 2u);
  EXPECT_NE(scene.warnings[0].find("retired key 'reuse.impulse'"), std::string::npos) << scene.warnings[0];
  EXPECT_NE(scene.warnings[1].find("retired key 'reuse.accel_tolerance'"), std::string::npos) << scene.warnings[1];
  ExpectRefused(R"({ "tank": { "min": [0,0,0], "max": [1,1,1] }, "reuse": { "preset": "fastest" } })",
                {"reuse.preset", "balanced"});
}

TEST(SceneFileTest, OutOfRangeSolverValuesRefused) {
  // Every parameter, just below its minimum and just above its maximum (from the parameter table).
  for (const sim::ParamInfo& p : sim::SolverParamInfos()) {
    for (double v : {p.min - (std::abs(p.min) * 0.5 + 1e-3), p.max * 1.5 + 1.0}) {
      const std::string text = Format(R"({ "solver": { "%s": %.17g }, "tank": { "min": [0,0,0], "max": [1,1,1] } })",
                                      p.key, v);
      ExpectRefused(text, {std::string("solver.") + p.key, "out of range"});
    }
    // and the range ends themselves are accepted
    for (double v : {p.min, p.max}) {
      const std::string text = Format(R"({ "solver": { "%s": %.17g }, "tank": { "min": [0,0,0], "max": [1,1,1] } })",
                                      p.key, v);
      SceneFile scene;
      const Status s = ParseScene(text, "test.json", &scene);
      EXPECT_TRUE(s.ok()) << p.key << " = " << v << ": " << s.message();
    }
  }
}

TEST(SceneFileTest, SolverAcceptsTheRangeEndsItPrints) {
  // The solver stores parameters as floats; a value typed exactly at a printed limit (cfl 0.01,
  // support_factor 1.8) must not be refused with "must be a number from 0.01 ...". A range end may
  // still be refused for another, named reason (a too-fine grid, no room for the walls' mass).
  for (const sim::ParamInfo& p : sim::SolverParamInfos()) {
    for (double v : {p.min, p.max}) {
      // The smallest spacing in a 2 mm tank: 20 spacings across (a 0.2 m tank would be 24M wall particles).
      const double size = std::string(p.key) == "spacing" && v == p.min ? 0.002 : 0.2;
      const SceneFile scene = ParseOk(Format(R"({ "solver": { "%s": %.17g }, "tank": { "min": [0,0,0], "max": [%g,%g,%g] } })",
                                             p.key, v, size, size, size));
      std::unique_ptr<sim::Solver> solver;
      const Status s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver);
      EXPECT_EQ(s.message().find("is invalid: must be a number from"), std::string::npos)
          << p.key << " = " << v << ": " << s.message();
    }
  }
}

TEST(SceneFileTest, GravityBeyondAHundredGRefused) {
  // 1e30 m/s^2 used to overflow the float length to inf, make dt 0 and hang the run.
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] }, "gravity": [0, -1e30, 0] })",
                      {"gravity", "at most 1000"});
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] }, "gravity": [800, -800, 0] })",
                      {"gravity", "at most 1000"});
  const SceneFile ok = ParseOk(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] }, "gravity": [0, -98.1, 0] })");
  std::unique_ptr<sim::Solver> solver;
  EXPECT_TRUE(sim::Solver::Create(ok.setup, test::TestConfig(), &solver).ok());
}

TEST(SceneFileTest, FluidBlockOutsideTheTankRefusedBySolver) {
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] },
                           "fluid": [ { "min": [0.1,0,0], "max": [0.3,0.1,0.1] } ] })",
                      {"fluid[0]", "not inside the tank"});
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] },
                           "fluid": [ { "min": [0,0,0], "max": [0.1,0.1,0.1] }, { "min": [0,-0.05,0], "max": [0.1,0.1,0.1] } ] })",
                      {"fluid[1]", "not inside the tank"});
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] },
                           "obstacles": [ { "min": [0.1,0,0], "max": [0.3,0.1,0.1] } ] })",
                      {"obstacles[0]", "not inside the tank"});
}

TEST(SceneFileTest, BoxWithMinAboveMaxRefused) {
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,-0.2,0.1] } })", {"tank", "must be below max"});
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] },
                           "fluid": [ { "min": [0.1,0,0], "max": [0.05,0.1,0.1] } ] })",
                      {"fluid[0]", "must be below max"});
  ExpectSolverRefuses(R"({ "tank": { "min": [0,0,0], "max": [0.2,0.2,0.1] },
                           "obstacles": [ { "min": [0.1,0.1,0.05], "max": [0.15,0.1,0.08] } ] })",
                      {"obstacles[0]", "must be below max"});
}

TEST(SceneFileTest, TooFineGridRefusedQuickly) {
  // 1e-4 m in a 1 m tank: 5000 cells along each axis, more than the 10-bit Morton codes address.
  double seconds = 0;
  std::unique_ptr<sim::Solver> solver;
  Status s;
  const SceneFile scene = ParseOk(R"({ "solver": { "spacing": 0.0001 }, "tank": { "min": [0,0,0], "max": [1,1,1] },
                                       "fluid": [ { "min": [0,0,0], "max": [1,0.5,1] } ] })");
  seconds = test::Seconds([&] { s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver); });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("solver.spacing"), std::string::npos) << s.message();
  EXPECT_LT(seconds, 1.0) << "refusing must not sample the particles";
}

long MaxRssKiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

TEST(SceneFileTest, MoreParticlesThanMemoryRefusedBeforeAllocating) {
  // A spacing fine enough that the particles need more than this machine's memory, yet coarse enough that
  // the grid (at most 1024 cells per axis) is accepted: the memory estimate must refuse it.
  const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
  ASSERT_GT(pages, 0);
  const double memory = static_cast<double>(pages) * pageSize;
  // The estimate is over 100 bytes per fluid particle: n^3 * 100 > memory is refused. (Not much more:
  // counting the particles to refuse them takes time proportional to n^3.)
  const double perAxis = std::cbrt(1.2 * memory / 100.0);
  if (perAxis > 1900.0) GTEST_SKIP() << "this machine's memory exceeds what a 1024-cell grid can hold";
  const double spacing = 1.0 / std::max(perAxis, 200.0);
  const std::string text = Format(R"({ "solver": { "spacing": %.9g }, "tank": { "min": [0,0,0], "max": [1,1,1] },
                                       "fluid": [ { "min": [0,0,0], "max": [1,1,1] } ] })",
                                  spacing);
  const SceneFile scene = ParseOk(text);
  const long rssBefore = MaxRssKiB();
  std::unique_ptr<sim::Solver> solver;
  Status s;
  const double seconds = test::Seconds([&] { s = sim::Solver::Create(scene.setup, test::TestConfig(), &solver); });
  const long rssAfter = MaxRssKiB();
  ASSERT_FALSE(s.ok()) << "spacing " << spacing << " (" << perAxis << "^3 particles) must not fit in "
                       << memory / 1073741824.0 << " GiB";
  EXPECT_EQ(solver, nullptr);
  EXPECT_NE(s.message().find("solver.spacing"), std::string::npos) << s.message();
  // (Beyond 2^29 particles, on a machine of more than ~50 GiB, the count limit refuses it first.)
  const bool countLimit = perAxis * perAxis * perAxis >= 536870912.0 * 0.99;
  EXPECT_NE(s.message().find(countLimit ? "at most" : "GiB"), std::string::npos) << s.message();
  EXPECT_LT(rssAfter - rssBefore, 64 * 1024) << "peak memory grew by " << (rssAfter - rssBefore) / 1024
                                             << " MiB while refusing";
  EXPECT_LT(seconds, 5.0) << "refusing took " << seconds << " s";
  RecordProperty("refusal_seconds", std::to_string(seconds));
  RecordProperty("particles_per_axis", std::to_string(perAxis));
}

TEST(SceneFileTest, SetSolverParam) {
  sim::SceneSetup setup;
  ASSERT_TRUE(SetSolverParam(&setup, "stiffness=2e5").ok());
  EXPECT_FLOAT_EQ(setup.params.stiffness, 2e5f);
  ASSERT_TRUE(SetSolverParam(&setup, "spacing=0.005").ok());
  EXPECT_FLOAT_EQ(setup.params.spacing, 0.005f);
  ASSERT_TRUE(SetSolverParam(&setup, "fixed_dt=0").ok());
  EXPECT_EQ(setup.params.fixedDt, 0.0f);
  for (const sim::ParamInfo& p : sim::SolverParamInfos()) {
    EXPECT_TRUE(SetSolverParam(&setup, Format("%s=%.17g", p.key, p.max)).ok()) << p.key;
    EXPECT_EQ(setup.params.*p.member, static_cast<float>(p.max)) << p.key;
  }

  const sim::SceneSetup before = setup;
  auto refused = [&](const std::string& assignment, std::initializer_list<std::string> needles) {
    const Status s = SetSolverParam(&setup, assignment);
    ASSERT_FALSE(s.ok()) << assignment;
    for (const std::string& n : needles)
      EXPECT_NE(s.message().find(n), std::string::npos) << assignment << ": '" << n << "' not in: " << s.message();
  };
  refused("stiffness", {"key=value"});
  refused("stifness=5", {"stifness", "unknown", "stiffness"});  // lists the known names
  refused("cfl=abc", {"cfl", "not a finite number"});
  refused("cfl=", {"cfl", "not a finite number"});
  refused("cfl=0.5x", {"cfl", "not a finite number"});
  refused("spacing=nan", {"spacing", "not a finite number"});
  refused("spacing=inf", {"spacing", "not a finite number"});
  refused("cfl=5", {"cfl", "out of range"});
  refused("spacing=-0.01", {"spacing", "out of range"});
  // a refused assignment leaves the scene unchanged
  EXPECT_EQ(setup.params.cfl, before.params.cfl);
  EXPECT_EQ(setup.params.spacing, before.params.spacing);
  EXPECT_EQ(setup.params.stiffness, before.params.stiffness);
}

TEST(SceneFileTest, EveryShippedSceneParsesWithoutWarnings) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(SPHXR_SCENES_DIR)) {
    if (entry.path().extension() != ".json") continue;
    ++count;
    SCOPED_TRACE(entry.path().string());
    SceneFile scene;
    const Status s = LoadScene(entry.path().string(), &scene);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.size() << " warning(s), first: " << scene.warnings.front();
    EXPECT_FALSE(scene.name.empty());
    EXPECT_TRUE(scene.runTime > 0 || scene.runSteps > 0) << "no default run length";
    EXPECT_FALSE(scene.setup.fluid.empty());
    // the solver accepts it too
    std::unique_ptr<sim::Solver> solver;
    const Status c = sim::Solver::Create(scene.setup, test::TestConfig(), &solver);
    EXPECT_TRUE(c.ok()) << c.message();
  }
  EXPECT_GE(count, 3) << "no scenes found in " << SPHXR_SCENES_DIR;
}

TEST(SceneFileTest, LoadSceneOfAMissingFileNamesIt) {
  SceneFile scene;
  const Status s = LoadScene("/nonexistent/dir/scene.json", &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("/nonexistent/dir/scene.json"), std::string::npos) << s.message();
}

// Scenes by name (app/src/scene_search.cpp, docs/user/install.md): the current directory first, then
// the installed scenes, or, for a program without installed scenes beside it, the build's.
TEST(SceneSearchTest, AShippedSceneByNameFromTheBuildTree) {
  std::string path;
  ASSERT_TRUE(FindScene("stir", &path));
  EXPECT_EQ(std::filesystem::path(path), std::filesystem::path(SPHXR_SCENES_DIR) / "stir.json");
  ASSERT_TRUE(FindScene("stir.json", &path));
  EXPECT_EQ(std::filesystem::path(path), std::filesystem::path(SPHXR_SCENES_DIR) / "stir.json");
  // A path is the caller's, found or not.
  ASSERT_TRUE(FindScene("some/where/else.json", &path));
  EXPECT_EQ(path, "some/where/else.json");
}

TEST(SceneSearchTest, InstalledScenesReplaceTheBuildsAndTheCurrentDirectoryComesFirst) {
  test::TempDir installed("installed_scenes");
  installed.Write("mine.json", kMinimal);
  std::string path;
  ASSERT_TRUE(FindScene("mine", &path, installed.path().string()));
  EXPECT_EQ(path, installed.File("mine.json"));
  // The build's scenes are not an installed program's: a name only they have is not found.
  const Status s = FindScene("stir", &path, installed.path().string());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("--scene stir: no scene of that name (nor with .json) in the current directory, " +
                             installed.path().string()),
            std::string::npos)
      << s.message();
  EXPECT_EQ(s.message().find(SPHXR_SCENES_DIR), std::string::npos) << s.message();

  test::TempDir here("current_dir");
  here.Write("mine.json", kMinimal);
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(here.path());
  const Status found = FindScene("mine", &path, installed.path().string());
  std::filesystem::current_path(before);
  ASSERT_TRUE(found) << found.message();
  EXPECT_EQ(path, "mine.json");
}

}  // namespace
}  // namespace sphxr::app
