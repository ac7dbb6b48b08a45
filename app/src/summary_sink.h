#pragma once
// The headless run's summary measures, a sink of the Simulation (simulation.h).
#include "sphxr/app/headless.h"
#include "sphxr/app/simulation.h"

namespace sphxr::app {

/// The summary's measures over the run (RunSummary: peaks, the mean active fraction, the paddles' mean
/// force and peak haptic amplitude).
class SummarySink : public SimulationSink {
 public:
  explicit SummarySink(RunSummary* summary) : m_summary(summary) {}
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;
  double ActiveSum() const { return m_activeSum; }
  double ForceSum() const { return m_forceSum; }

 private:
  RunSummary* m_summary;
  double m_activeSum = 0.0;
  double m_forceSum = 0.0;
};

}  // namespace sphxr::app
