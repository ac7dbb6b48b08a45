#include "save_state_sink.h"

#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {

Status SaveStateSink::Finish(Simulation& simulation, bool) {
  m_saved = simulation.WriteState(m_options.saveState, m_sceneName);
  if (!m_saved) {
    m_saved = Status::Error("--save-state " + m_saved.message() +
                            (m_summary->checkpoints > 0
                                 ? Format(" (the last checkpoint, t = %.6g s, is there)", m_summary->checkpointTime)
                                 : ""));
    return Status::Ok();
  }
  m_summary->stateSaved = m_options.saveState;
  // The file does not record how it was made: a run from it skips the scene's settle as if it were done.
  if (m_summary->settle.stopped) {
    SPHXR_LOG_WARN("%s holds water whose settle was stopped at %.4g of %g s: a run from it starts from water that is "
                   "not at rest (settle again without --load-state to have a settled start)",
                   m_options.saveState.c_str(), m_summary->settle.time, m_settle);
  }
  return Status::Ok();
}

}  // namespace sphxr::app
