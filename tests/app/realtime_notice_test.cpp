// The line an interactive run logs once when the machine cannot keep its scene in real time: when it
// decides (the first rate window after the start-up second), what it says, and that the window's worker
// logs it for `pool` on a CPU and not for a small tank that keeps real time.
#include <gtest/gtest.h>

#include <chrono>
#include <limits>
#include <thread>

#include "realtime_notice.h"  // app/src
#include "sim_worker.h"       // app/src
#include "sphxr/app/scene_file.h"
#include "support.h"

namespace sphxr::app {
namespace {

TEST(RealTimeNotice, DecidesOnTheFirstWindowAfterTheStartUpSecondAndSaysWhatToChange) {
  RealTimeNotice notice("pool", 105600, "pbf", "cpu", 2);
  EXPECT_FALSE(notice.Observe(0.05, 0.5));  // the start-up's frames do not count
  const auto line = notice.Observe(0.3, 1.0);
  ASSERT_TRUE(line);
  for (const char* part : {"pool:", "0.30 of real time", "105600 particles", "pbf on cpu, 2 threads",
                           "--quality auto", "--device cuda"}) {
    EXPECT_NE(line->find(part), std::string::npos) << part << " in " << *line;
  }
  EXPECT_FALSE(notice.Observe(0.3, 1.5));  // once
  notice.Restart();                         // a reset judges the scene anew
  EXPECT_TRUE(notice.Observe(0.3, 2.0));
}

TEST(RealTimeNotice, SaysNothingWhenTheMachineKeepsUpOrTheRateIsNotANumber) {
  RealTimeNotice fast("stir", 13500, "pbf", "cpu", 2);
  EXPECT_FALSE(fast.Observe(RealTimeNotice::kThreshold, 1.0));
  EXPECT_FALSE(fast.Observe(0.1, 2.0));  // decided already: a later slow window (a pause) says nothing
  RealTimeNotice nan("stir", 13500, "pbf", "cpu", 2);
  EXPECT_FALSE(nan.Observe(std::numeric_limits<double>::quiet_NaN(), 1.0));
}

TEST(RealTimeNotice, OnTheGpuItNamesNoThreadsAndNoGpu) {
  RealTimeNotice notice("pool", 105600, "pbf", "cuda", 16);
  const auto line = notice.Observe(0.5, 1.0);
  ASSERT_TRUE(line);
  EXPECT_EQ(line->find("threads"), std::string::npos) << *line;
  EXPECT_EQ(line->find("--device cuda"), std::string::npos) << *line;
}

/// Runs the window's simulation worker on `scene` until the notice's decision is due, and returns how
/// often the line was logged.
int NoticesOfWorker(const SceneFile& scene, int threads, double seconds) {
  sim::SolverConfig config;
  config.device = sim::Device::kCpu;
  config.threads = threads;
  test::LogCapture log;
  SimWorker worker(config);
  EXPECT_TRUE(worker.Start(SimSceneFromFile(scene)).ok());
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end && log.Count("of real time") == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  worker.Stop();
  return log.Count("of real time", LogLevel::kWarn);
}

TEST(RealTimeNoticeWorker, PoolOnOneCpuThreadSaysOnceThatItIsSlowedDown) {
  SceneFile scene;
  ASSERT_TRUE(LoadScene(SPHXR_SCENES_DIR "/pool.json", &scene).ok());
  // 105,600 particles: a frame takes a large part of a second on one thread, far from real time on any
  // CPU; the decision comes after the start-up second and the rate window that follows it.
  EXPECT_EQ(NoticesOfWorker(scene, 1, 60.0), 1);
}

TEST(RealTimeNoticeWorker, ASmallTankThatKeepsRealTimeSaysNothing) {
  // 96 particles under PBF: a few hundred steps a simulated second, a few percent of a core.
  SceneFile scene;
  ASSERT_TRUE(ParseScene(R"({
  "name": "tiny",
  "solver": { "method": "pbf", "spacing": 0.02 },
  "tank": { "min": [0, 0, 0], "max": [0.2, 0.15, 0.1] },
  "fluid": [ { "min": [0.04, 0.0, 0.02], "max": [0.16, 0.04, 0.06] } ]
})", "tiny", &scene).ok());
  EXPECT_EQ(NoticesOfWorker(scene, 1, 2.5), 0);
}

}  // namespace
}  // namespace sphxr::app
