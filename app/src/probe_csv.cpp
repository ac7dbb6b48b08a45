#include "sphxr/app/probe_csv.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "csv_continue.h"
#include "sphxr/common/host_memory.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::app {
namespace {

double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// a + u (b - a); NaN on either side stays NaN (an empty cell).
float Lerp(float a, float b, double u) { return static_cast<float>(a + u * (static_cast<double>(b) - a)); }

void Cell(std::string* row, float v) {
  *row += ',';
  if (std::isnan(v)) return;
  *row += Format("%.7g", v);
}

/// The bytes of an earlier run's probe CSV at `path` to keep when a run continues it with rows from
/// `firstRow` (s) on: the header and the whole rows before firstRow (csv_continue.h); rows out of time
/// order are foreign.
int64_t ProbeBytesToKeep(const std::string& path, const std::string& header, double firstRow, double every,
                         int64_t* dropped) {
  double previous = -1.0;
  return CsvBytesToKeep(path, header, [&](const std::string& line) {
    char* end = nullptr;
    const double t = std::strtod(line.c_str(), &end);
    if (end == line.c_str() || *end != ',' || !(t > previous)) return RowFate::kForeign;
    previous = t;
    return t < firstRow - 0.5 * every ? RowFate::kKeep : RowFate::kDrop;
  }, dropped);
}

}  // namespace

std::string ProbeCsvHeader(const sim::ProbeSet& set) {
  std::string h = "time,step";
  for (const sim::PressureProbe& p : set.pressure) h += "," + p.name + "_p";
  for (const sim::LevelGauge& g : set.level) h += "," + g.name + "_level";
  for (const sim::ForceProbe& f : set.force) {
    for (const char* q : {"fx", "fy", "fz", "tx", "ty", "tz"}) h += "," + f.name + "_" + q;
  }
  return h;
}

Status ProbeCsv::Open(const std::string& path, const ProbeConfig& config, double start, std::unique_ptr<ProbeCsv>* out) {
  out->reset();
  if (!(config.every >= kMinProbeInterval) || !std::isfinite(config.every)) {
    return Status::Error(Format("probes.every = %g s: must be at least %g s", config.every, kMinProbeInterval));
  }
  std::unique_ptr<ProbeCsv> csv(new ProbeCsv());
  csv->m_path = path;
  csv->m_every = config.every;
  // The first row at or after `start`; the tiny slack keeps a start that is a multiple of `every` in
  // (k every rounds either way in binary).
  csv->StartAt(start);
  const std::string header = ProbeCsvHeader(config.set);
  int64_t dropped = 0;
  const int64_t keep = start > 0.0 ? ProbeBytesToKeep(path, header, csv->NextTime(), config.every, &dropped) : -1;
  if (keep >= 0) {
    std::error_code ec;
    std::filesystem::resize_file(path, static_cast<uintmax_t>(keep), ec);
    if (ec) return Status::Error("--probes " + ShowText(path) + ": cannot continue the file: " + ec.message());
    csv->m_file = std::fopen(path.c_str(), "ab");
    if (!csv->m_file) return Status::Error("--probes " + ShowText(path) + ": cannot open for writing: " + std::strerror(errno));
    SPHXR_LOG_INFO("--probes %s: the rows continue the earlier run's (its rows before t = %.6g s kept%s)", path.c_str(),
                   csv->NextTime(), dropped > 0 ? Format(", %lld after it replaced", static_cast<long long>(dropped)).c_str() : "");
  } else {
    csv->m_file = std::fopen(path.c_str(), "wb");
    if (!csv->m_file) return Status::Error("--probes " + ShowText(path) + ": cannot open for writing: " + std::strerror(errno));
    const std::string line = header + "\n";
    if (std::fwrite(line.data(), 1, line.size(), csv->m_file) != line.size() || std::fflush(csv->m_file) != 0) {
      return Status::Error("--probes " + ShowText(path) + ": write failed (disk full?)");
    }
  }
  csv->m_lastFlush = WallSeconds();
  *out = std::move(csv);
  return Status::Ok();
}

void ProbeCsv::StartAt(double start) { m_next = static_cast<int64_t>(std::ceil(start / m_every - 1e-9)); }

ProbeCsv::~ProbeCsv() {
  if (!m_file) return;
  (void)Flush();
  std::fclose(m_file);
}

void ProbeCsv::Row(double t, const sim::ProbeSample& a, const sim::ProbeSample* b) {
  const double u = b && b->time > a.time ? (t - a.time) / (b->time - a.time) : 0.0;
  auto value = [&](float va, float vb) { return b ? Lerp(va, vb, u) : va; };
  std::string row = Format("%.10g,%lld", t, static_cast<long long>(a.steps));
  for (size_t k = 0; k < a.pressure.size(); ++k) Cell(&row, value(a.pressure[k], b ? b->pressure[k] : 0.0f));
  for (size_t k = 0; k < a.level.size(); ++k) Cell(&row, value(a.level[k], b ? b->level[k] : 0.0f));
  for (size_t k = 0; k < a.load.size(); ++k) {
    const sim::BodyLoad& la = a.load[k];
    const sim::BodyLoad lb = b ? b->load[k] : la;
    for (const auto& [x, y] : {std::pair{la.force.x, lb.force.x}, std::pair{la.force.y, lb.force.y},
                               std::pair{la.force.z, lb.force.z}, std::pair{la.torque.x, lb.torque.x},
                               std::pair{la.torque.y, lb.torque.y}, std::pair{la.torque.z, lb.torque.z}}) {
      Cell(&row, value(x, y));
    }
  }
  row += '\n';
  m_pending += row;
  ++m_rows;
}

Status ProbeCsv::Add(const sim::ProbeSample& sample) {
  // A row at a reading's own time is that reading; between two readings, their interpolation. A step
  // longer than kMaxProbeRowsPerStep intervals is refused before a row of it is made.
  const double rows = std::floor(sample.time / m_every + 1e-9) - static_cast<double>(m_next) + 1.0;
  if (rows > static_cast<double>(kMaxProbeRowsPerStep)) {
    const double span = m_previous ? sample.time - m_previous->time : sample.time - NextTime();
    return Status::Error(Format("--probes %s: probes.every = %g s asks for %.3g rows in one step of %g s; at most %lld "
                                "rows a step are written: use probes.every >= %g s",
                                ShowText(m_path).c_str(), m_every, rows, span, static_cast<long long>(kMaxProbeRowsPerStep),
                                span / static_cast<double>(kMaxProbeRowsPerStep)));
  }
  MemoryUse use("the probe rows (--probes, probes.every)");
  for (;;) {
    const double t = static_cast<double>(m_next) * m_every;
    if (t > sample.time) break;
    if (m_pending.size() > (size_t{1} << 20)) {
      if (Status s = Flush(); !s) return s;
    }
    if (m_previous && t >= m_previous->time) {
      Row(t, *m_previous, &sample);
    } else if (t == sample.time || !m_previous) {
      // No reading before this one (the run's first): only a row at its own time, or one that lies
      // before the first reading (a continued run's start between two rows) at the reading's values.
      Row(t, sample, nullptr);
    }
    ++m_next;
  }
  m_previous = sample;
  if (m_pending.size() > (size_t{1} << 20) || WallSeconds() - m_lastFlush >= 1.0) return Flush();
  return Status::Ok();
}

Status ProbeCsv::Flush() {
  m_lastFlush = WallSeconds();
  if (m_pending.empty()) return Status::Ok();
  errno = 0;
  const bool ok = std::fwrite(m_pending.data(), 1, m_pending.size(), m_file) == m_pending.size() && std::fflush(m_file) == 0;
  const int error = errno;
  m_pending.clear();
  if (!ok) {
    return Status::Error("--probes " + ShowText(m_path) + ": write failed (" +
                         (error ? std::strerror(error) : "disk full?") + ")");
  }
  return Status::Ok();
}

Status ProbeSink::Create(const std::string& path, const ProbeConfig& config, double start,
                         std::unique_ptr<ProbeSink>* out) {
  std::unique_ptr<ProbeSink> sink(new ProbeSink());
  sink->m_path = path;
  sink->m_config = config;
  if (Status s = ProbeCsv::Open(path, config, start, &sink->m_csv); !s) return s;
  *out = std::move(sink);
  return Status::Ok();
}

Status ProbeSink::OnStart(Simulation& simulation) {
  if (Status s = simulation.Solver().SetProbes(m_config.set); !s) return Status::Error("--probes " + ShowText(m_path) + ": " + s.message());
  m_csv->StartAt(simulation.Solver().Time());
  return Status::Ok();
}

Status ProbeSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  return m_csv->Add(simulation.Solver().LastProbes());
}

Status ProbeSink::Finish(Simulation& simulation, bool) {
  // The readings so far end at the last step's start; one more on the final state gives the rows up to
  // the end, so a run continued from this state (whose first reading is here) leaves no row out.
  sim::ProbeSample last;
  if (simulation.Solver().Time() > 0.0 && simulation.Solver().SampleProbes(m_config.set, &last).ok()) {
    if (Status s = m_csv->Add(last); !s) return s;
  }
  return m_csv->Flush();
}

}  // namespace sphxr::app
