#include "progress_sink.h"

#include <algorithm>

namespace sphxr::app {

Status ProgressSink::OnStart(Simulation&) {
  m_begin = std::chrono::steady_clock::now();
  return Status::Ok();
}

double ProgressSink::WallSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_begin).count();
}

Status ProgressSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  const double time = simulation.Solver().Time();
  const int64_t step = simulation.Solver().GetTotals().steps;  // this run's
  const double fraction = m_targetSteps > 0 ? static_cast<double>(step) / m_targetSteps
                                            : (time - m_startTime) / (m_targetTime - m_startTime);
  m_progress->Update(std::min(1.0, fraction), time, simulation.WholeStep(), 1e3 * WallSeconds() / step);
  return Status::Ok();
}

}  // namespace sphxr::app
