#pragma once
// `--checkpoint-every S`, a sink of the Simulation (simulation.h): the state saved during the run.
#include <string>
#include <utility>

#include "sphxr/app/headless.h"
#include "sphxr/app/options.h"
#include "sphxr/app/simulation.h"
#include "stats_sink.h"

namespace sphxr::app {

/// --checkpoint-every S: the state saved to the --save-state file at whole multiples of S on the simulated
/// clock, the --checkpoint-keep - 1 before it moved to FILE.1 (the newest), FILE.2, ...
class CheckpointSink : public SimulationSink {
 public:
  CheckpointSink(const Options& options, std::string sceneName, StatsSink* stats, RunSummary* summary)
      : m_options(options), m_sceneName(std::move(sceneName)), m_stats(stats), m_summary(summary) {}
  Status OnStart(Simulation& simulation) override;
  Status OnStep(Simulation& simulation, const sim::StepInfo& info) override;

 private:
  const Options& m_options;
  std::string m_sceneName;
  StatsSink* m_stats;  // may be null
  RunSummary* m_summary;
  double m_next = 0.0;
};

}  // namespace sphxr::app
