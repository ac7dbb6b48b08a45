#include "stats_sink.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "csv_continue.h"
#include "dam_break_measure.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {
namespace {

/// How much of an earlier `--stats` file a run continued from a state saved at step `stepsBefore`
/// keeps: the bytes of the header and the rows up to that step, when it is a regular file with this
/// run's header, rows in step order and a row for that step (the first half's CSV); else -1, and the
/// file is written anew. `*dropped` counts the rows after that step (a second half run before).
int64_t StatsBytesToKeep(const std::string& path, const std::string& header, int64_t stepsBefore, int64_t* dropped) {
  *dropped = 0;
  if (stepsBefore <= 0) return -1;
  long long previous = 0;
  bool found = false;  // the row of the state's step itself
  const int64_t keep = CsvBytesToKeep(path, header, [&](const std::string& line) {
    char* end = nullptr;
    const long long step = std::strtoll(line.c_str(), &end, 10);
    if (end == line.c_str() || *end != ',' || step <= previous) return RowFate::kForeign;  // not ours, or not in order
    previous = step;
    if (step > stepsBefore) return RowFate::kDrop;
    found = step == stepsBefore;
    return RowFate::kKeep;
  }, dropped);
  return found ? keep : -1;
}

}  // namespace

Status StatsSink::Open() {
  const std::filesystem::path parent = std::filesystem::path(m_path).parent_path();
  std::error_code ec;
  if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) {
    return Status::Error("--stats " + ShowText(m_path) + ": " + ShowText(parent.string()) + " does not exist; make it first");
  }
  m_out.open(m_path, std::ios::app);
  if (!m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot open for writing");
  return Status::Ok();
}

Status StatsSink::WriteHeader(Simulation& simulation, const std::optional<DamBreakProbe>& probe) {
  m_probe = probe;
  m_stats = sim::SolverInfoOf(simulation.Solver().Method()).columns;
  const interaction::PaddleSystem* paddles = simulation.Paddles();
  std::string header = "step,time,dt,max_speed,mean_density_error,max_density_error,clamped,active_fraction";
  if (m_probe) header += ",front_Z,height_H";
  for (const sim::SolveColumn& column : m_stats) header += std::string(",") + column.name;
  if (paddles) {
    header += ",pushed_out";
    for (int k = 0; k < paddles->Count(); ++k) header += Format(",paddle%d_fx,paddle%d_fy,paddle%d_fz,paddle%d_haptic", k, k, k, k);
  }
  // What the device was asked since the row before (sphxr/sim/launch_counts.h): last, so that the
  // columns before them read as they always have.
  header += ",launches,host_waits,allocations,copies_back,copies_back_unasked,uploads";
  m_counts = simulation.Solver().Counts();
  // A continued run appends to the first half's CSV: the whole run's rows in one file. The first half's
  // rows are never rewritten: later rows (of an earlier continuation) are cut off, then rows appended.
  // A pipe or device is written as it was opened (never read back, never reopened).
  const int64_t stepsBefore = std::max<int64_t>(simulation.StepsBefore(), 0);
  int64_t dropped = 0;
  const int64_t keep = StatsBytesToKeep(m_path, header, stepsBefore, &dropped);
  std::error_code ec;
  if (keep >= 0) {
    m_out.close();
    if (dropped > 0) std::filesystem::resize_file(m_path, static_cast<uintmax_t>(keep), ec);
    if (!ec) m_out.open(m_path, std::ios::app);
    if (ec || !m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot continue the file: " + ec.message());
    SPHXR_LOG_INFO("--stats %s: the rows continue the earlier run's (its steps up to %lld kept%s)", m_path.c_str(),
                   static_cast<long long>(stepsBefore),
                   dropped > 0 ? Format(", %lld rows after it replaced", static_cast<long long>(dropped)).c_str() : "");
  } else {
    // A continued run whose file holds the first half's rows under other columns (another method's
    // statistics, other paddles) would rewrite them: refused, the file left as it is.
    if (stepsBefore > 0) {
      std::string first;
      std::ifstream earlier(m_path, std::ios::binary);
      if (std::filesystem::is_regular_file(m_path, ec) && std::getline(earlier, first) &&
          first.rfind("step,time,", 0) == 0 && first != header) {
        return Status::Error("--stats " + ShowText(m_path) + ": the earlier run's rows there have other columns (" +
                             ShowText(first.substr(first.find(',', 10) + 1), 60) +
                             "; this run's: " + ShowText(header.substr(header.find(',', 10) + 1), 60) +
                             "): continuing into it would rewrite them; give another --stats file");
      }
    }
    if (std::filesystem::is_regular_file(m_path, ec)) {
      m_out.close();
      m_out.open(m_path, std::ios::trunc);
      if (!m_out) return Status::Error("--stats " + ShowText(m_path) + ": cannot open for writing");
    }
    m_out << header << "\n";
  }
  m_out.flush();
  m_whole =
      std::filesystem::is_regular_file(m_path, ec) ? static_cast<int64_t>(std::filesystem::file_size(m_path, ec)) : -1;
  if (ec) m_whole = -1;
  return Status::Ok();
}

Status StatsSink::OnStep(Simulation& simulation, const sim::StepInfo& info) {
  const int64_t wholeStep = simulation.WholeStep();
  const sim::LaunchCounts counts = simulation.Solver().Counts();
  const sim::LaunchCounts step = counts - m_counts;
  m_counts = counts;
  std::ostringstream row;
  row << wholeStep << ',' << info.time << ',' << info.dt << ',' << info.maxSpeed << ',' << info.meanDensityError << ','
      << info.maxDensityError << ',' << info.clamped << ',' << info.activeFraction;
  if (m_probe) {
    simulation.Solver().Download(&m_host);
    const DamBreakMeasure m = MeasureDamBreak(*m_probe, m_host, simulation.Setup().params.spacing);
    row << ',' << m.front << ',' << m.height;
  }
  for (const sim::SolveColumn& column : m_stats) row << ',' << column.Value(info.solve);
  if (const interaction::PaddleSystem* paddles = simulation.Paddles()) {
    row << ',' << info.pushedOut;
    for (int k = 0; k < paddles->Count(); ++k) {
      const interaction::PaddleState& p = paddles->State(k);
      row << ',' << p.force.x << ',' << p.force.y << ',' << p.force.z << ',' << p.haptic;
    }
  }
  row << ',' << step.launches << ',' << step.syncs << ',' << step.allocations << ',' << step.downloads << ','
      << step.UnaskedDownloads() << ',' << step.uploads;
  row << '\n';
  m_pending += row.str();
  const bool due = m_pending.size() > (size_t{1} << 20) || std::chrono::steady_clock::now() - m_last >= std::chrono::seconds(1);
  if (due) {
    if (Status s = Flush(); !s) return Status::Error(s.message() + " (at step " + std::to_string(wholeStep) + ")");
  }
  return Status::Ok();
}

Status StatsSink::Flush() {
  m_last = std::chrono::steady_clock::now();
  if (m_pending.empty() || !m_out.is_open()) return Status::Ok();
  errno = 0;
  m_out.write(m_pending.data(), static_cast<std::streamsize>(m_pending.size()));
  m_out.flush();
  const int error = errno;
  const size_t written = m_pending.size();
  m_pending.clear();
  if (!m_out) {
    m_out.close();  // nothing more is written: what reached the file ends at its last whole row
    CutToWholeRows();
    return Status::Error("--stats " + ShowText(m_path) + ": write failed (" +
                         (error ? std::strerror(error) : "disk full?") + "); the file ends at its last whole row");
  }
  if (m_whole >= 0) m_whole += static_cast<int64_t>(written);
  return Status::Ok();
}

void StatsSink::CutToWholeRows() {
  // A regular file only (a pipe or a device has nothing to cut): the bytes after the last whole row
  // known to be written, up to the last newline among them, are kept.
  if (m_whole < 0) return;
  std::error_code ec;
  const auto size = static_cast<int64_t>(std::filesystem::file_size(m_path, ec));
  if (ec || size <= m_whole) return;
  std::ifstream in(m_path, std::ios::binary);
  in.seekg(m_whole);
  std::string tail(static_cast<size_t>(size - m_whole), '\0');
  in.read(tail.data(), static_cast<std::streamsize>(tail.size()));
  const size_t newline = tail.rfind('\n', static_cast<size_t>(in.gcount() > 0 ? in.gcount() - 1 : 0));
  const int64_t keep = m_whole + (newline == std::string::npos ? 0 : static_cast<int64_t>(newline) + 1);
  std::filesystem::resize_file(m_path, static_cast<uintmax_t>(keep), ec);
}

Status StatsSink::Finish(Simulation&, bool) {
  if (Status s = Flush(); !s) return s;
  if (m_out.is_open()) {
    m_out.close();
    if (m_out.fail()) {
      CutToWholeRows();
      return Status::Error("--stats " + ShowText(m_path) +
                           ": write failed (disk full?); the file ends at its last whole row");
    }
  }
  return Status::Ok();
}

}  // namespace sphxr::app
