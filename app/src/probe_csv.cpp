#include "sphxr/app/probe_csv.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

#include "sphxr/common/log.h"

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
  if (!(config.every > 0.0) || !std::isfinite(config.every)) {
    return Status::Error(Format("probes.every = %g s: must be a positive time", config.every));
  }
  std::unique_ptr<ProbeCsv> csv(new ProbeCsv());
  csv->m_path = path;
  csv->m_every = config.every;
  // The first row at or after `start`; the tiny slack keeps a start that is a multiple of `every` in
  // (k every rounds either way in binary).
  csv->StartAt(start);
  csv->m_file = std::fopen(path.c_str(), "wb");
  if (!csv->m_file) return Status::Error("--probes " + path + ": cannot open for writing: " + std::strerror(errno));
  const std::string header = ProbeCsvHeader(config.set) + "\n";
  if (std::fwrite(header.data(), 1, header.size(), csv->m_file) != header.size() || std::fflush(csv->m_file) != 0) {
    return Status::Error("--probes " + path + ": write failed (disk full?)");
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
  // A row at a reading's own time is that reading; between two readings, their interpolation.
  for (;;) {
    const double t = static_cast<double>(m_next) * m_every;
    if (t > sample.time) break;
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
  const bool ok = std::fwrite(m_pending.data(), 1, m_pending.size(), m_file) == m_pending.size() && std::fflush(m_file) == 0;
  m_pending.clear();
  if (!ok) return Status::Error("--probes " + m_path + ": write failed (disk full?)");
  return Status::Ok();
}

Status ProbeSink::Create(const std::string& path, const ProbeConfig& config, std::unique_ptr<ProbeSink>* out) {
  std::unique_ptr<ProbeSink> sink(new ProbeSink());
  sink->m_path = path;
  sink->m_config = config;
  if (Status s = ProbeCsv::Open(path, config, 0.0, &sink->m_csv); !s) return s;
  *out = std::move(sink);
  return Status::Ok();
}

Status ProbeSink::OnStart(Simulation& simulation) {
  if (Status s = simulation.Solver().SetProbes(m_config.set); !s) return Status::Error("--probes " + m_path + ": " + s.message());
  m_csv->StartAt(simulation.Solver().Time());
  return Status::Ok();
}

Status ProbeSink::OnStep(Simulation& simulation, const sim::StepInfo&) {
  return m_csv->Add(simulation.Solver().LastProbes());
}

Status ProbeSink::Finish(Simulation&, bool) { return m_csv->Flush(); }

}  // namespace sphxr::app
