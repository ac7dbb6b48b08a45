// The output files of a headless run (app/src/output_files.cpp): a directory is made only in one that exists.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "refusal.h"
#include "sphxr/app/headless.h"
#include "support.h"

namespace sphxr::app {
namespace {

using test::ExpectBriefRefusal;

TEST(OutputFiles, OutputDirectoriesAreMadeOnlyInADirectoryThatExists) {
  test::TempDir dir("sinks_outdir");
  const std::string scene = dir.Write("scene.json", test::kSmallTankScene);
  Options options;
  options.scenePath = scene;
  options.steps = 1;
  options.threads = 1;
  options.progress = 0;
  options.exportEvery = 1;
  options.outDir = dir.File("missing/out");
  RunSummary summary;
  ExpectBriefRefusal(RunHeadless(options, &summary), "does not exist; make it first");
  EXPECT_FALSE(std::filesystem::exists(dir.File("missing")));
  options.outDir = dir.File("out/");  // one level is made
  EXPECT_TRUE(RunHeadless(options, &summary).ok());
  EXPECT_TRUE(std::filesystem::is_directory(dir.File("out")));
  options.exportEvery = 0;
  options.outDir = "out";
  options.statsPath = dir.File("missing/stats.csv");
  ExpectBriefRefusal(RunHeadless(options, &summary), "does not exist; make it first");
}

}  // namespace
}  // namespace sphxr::app
