#include "checkpoint_sink.h"

#include <cmath>
#include <filesystem>

namespace sphxr::app {

Status CheckpointSink::OnStart(Simulation& simulation) {
  // At whole multiples of the interval on the simulated clock (a continued run keeps the grid).
  const double every = m_options.checkpointEvery;
  m_next = (std::floor(simulation.Solver().Time() / every + 1e-9) + 1.0) * every;
  return Status::Ok();
}

Status CheckpointSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  const double time = simulation.Solver().Time();
  if (time < m_next - 1e-9) return Status::Ok();
  // The CSV first: a run continued from this checkpoint keeps the rows up to its step.
  if (m_stats) {
    if (Status s = m_stats->Flush(); !s) return s;
  }
  // The state saved to `path` (atomically, WriteStateFile), the `keep` - 1 before it moved to path.1
  // (the newest), path.2, ... first. `path` itself always holds a whole state.
  namespace fs = std::filesystem;
  const std::string& path = m_options.saveState;
  const int keep = m_options.checkpointKeep;
  std::error_code ec;
  const std::string base = fs::is_symlink(fs::symlink_status(path, ec)) ? fs::weakly_canonical(path, ec).string() : path;
  if (keep > 1 && fs::is_regular_file(base, ec)) {
    for (int k = keep - 1; k >= 2; --k) {
      const std::string older = base + "." + std::to_string(k - 1);
      if (fs::exists(older, ec)) fs::rename(older, base + "." + std::to_string(k), ec);
    }
    // A second name for the current file, so that `path` is never missing while the next is written.
    const std::string previous = base + ".1";
    fs::remove(previous, ec);
    fs::create_hard_link(base, previous, ec);
    if (ec) fs::copy_file(base, previous, fs::copy_options::overwrite_existing, ec);
  }
  if (Status s = simulation.WriteState(path, m_sceneName); !s) return Status::Error("--checkpoint-every: " + s.message());
  ++m_summary->checkpoints;
  m_summary->checkpointTime = time;
  m_next = (std::floor(time / m_options.checkpointEvery + 1e-9) + 1.0) * m_options.checkpointEvery;
  return Status::Ok();
}

}  // namespace sphxr::app
