#include "summary_sink.h"

#include <algorithm>

namespace sphxr::app {

Status SummarySink::OnStep(Simulation& simulation, const sim::StepInfo& info) {
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) {
    for (int k = 0; k < paddles->Count(); ++k) {
      m_forceSum += Length(paddles->State(k).force);
      m_summary->paddlePeakHaptic = std::max(m_summary->paddlePeakHaptic, paddles->State(k).haptic);
    }
  }
  m_summary->peakMeanDensityError = std::max(m_summary->peakMeanDensityError, info.meanDensityError);
  m_summary->maxSpeed = std::max(m_summary->maxSpeed, info.maxSpeed);
  m_activeSum += info.activeFraction;
  return Status::Ok();
}

}  // namespace sphxr::app
