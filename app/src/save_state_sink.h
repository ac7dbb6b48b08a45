#pragma once
// `--save-state FILE`, a sink of the Simulation (simulation.h): the state at the end of the run.
#include <string>
#include <utility>

#include "sphxr/app/headless.h"
#include "sphxr/app/options.h"
#include "sphxr/app/simulation.h"

namespace sphxr::app {

/// --save-state FILE: the state at the end of the run (also of one stopped by a signal). A failed save
/// does not stop the others' Finish: it is reported after the summary (Saved()), which covers the run.
class SaveStateSink : public SimulationSink {
 public:
  SaveStateSink(const Options& options, std::string sceneName, double settle, RunSummary* summary)
      : m_options(options), m_sceneName(std::move(sceneName)), m_settle(settle), m_summary(summary) {}
  Status OnStep(Simulation&, const sim::StepInfo&) override { return Status::Ok(); }
  Status Finish(Simulation& simulation, bool interrupted) override;
  const Status& Saved() const { return m_saved; }

 private:
  const Options& m_options;
  std::string m_sceneName;
  double m_settle;
  RunSummary* m_summary;
  Status m_saved;
};

}  // namespace sphxr::app
