#pragma once
// The progress of the headless run's steps, a sink of the Simulation (simulation.h).
#include <chrono>
#include <cstdint>

#include "progress.h"
#include "sphxr/app/simulation.h"

namespace sphxr::app {

/// The progress bar (or a line a minute) of the steps towards the run's end.
class ProgressSink : public SimulationSink {
 public:
  ProgressSink(Progress* progress, int64_t targetSteps, double targetTime, double startTime)
      : m_progress(progress), m_targetSteps(targetSteps), m_targetTime(targetTime), m_startTime(startTime) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  /// Wall seconds since OnStart.
  double WallSeconds() const;

 private:
  Progress* m_progress;
  int64_t m_targetSteps;
  double m_targetTime;
  double m_startTime;
  std::chrono::steady_clock::time_point m_begin{};
};

}  // namespace sphxr::app
