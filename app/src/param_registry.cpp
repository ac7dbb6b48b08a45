#include "sphxr/app/param_registry.h"

#include <cmath>
#include <string>
#include <vector>

#include "sphxr/app/probe_config.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {
namespace {

std::vector<ParamDesc> Build() {
  std::vector<ParamDesc> out;
  const sim::SolverParams solverDefaults;
  for (const sim::ParamInfo& info : sim::SolverParamInfos()) {
    ParamDesc p;
    p.name = info.key;
    p.key = "solver." + p.name;
    p.group = "solver";
    p.unit = info.unit;
    p.help = info.help;
    p.min = info.min;
    p.max = info.max;
    p.defaultValue = solverDefaults.*(info.member);
    p.solverMember = info.member;
    p.integer = info.integer;
    out.push_back(p);
  }
  const sim::ReuseParams reuseDefaults;
  for (const sim::ReuseParamInfo& info : sim::ReuseParamInfos()) {
    ParamDesc p;
    p.name = info.key;
    p.key = "reuse." + p.name;
    p.group = "reuse";
    p.unit = info.unit;
    p.help = info.help;
    p.min = info.min;
    p.max = info.max;
    p.defaultValue = info.count ? reuseDefaults.*(info.count) : reuseDefaults.*(info.real);
    p.reuseFloat = info.real;
    p.reuseInt = info.count;
    p.integer = info.count != nullptr;
    out.push_back(p);
  }
  return out;
}

}  // namespace

double ParamDesc::Get(const sim::SceneSetup& s) const {
  if (solverMember) return s.params.*solverMember;
  if (reuseFloat) return s.reuse.*reuseFloat;
  return s.reuse.*reuseInt;
}

void ParamDesc::Set(sim::SceneSetup* s, double v) const {
  if (solverMember) s->params.*solverMember = static_cast<float>(v);
  if (reuseFloat) s->reuse.*reuseFloat = static_cast<float>(v);
  if (reuseInt) s->reuse.*reuseInt = static_cast<int>(std::lround(v));
}

std::span<const ParamDesc> ParamRegistry() {
  static const std::vector<ParamDesc> registry = Build();
  return registry;
}

const ParamDesc* FindParam(const std::string& key) {
  for (const ParamDesc& p : ParamRegistry()) {
    if (p.key == key || (p.group == "solver" && p.name == key)) return &p;
  }
  return nullptr;
}

Status SetParam(const ParamDesc& p, double value, const std::string& where, sim::SceneSetup* s) {
  if (!std::isfinite(value)) return Status::Error(where + ": must be finite");
  if (value < p.min || value > p.max) {
    return Status::Error(Format("%s: %s is out of range: must be from %s to %s%s%s (%s)", where.c_str(),
                                ShowNumber(value).c_str(), ShowNumber(p.min).c_str(), ShowNumber(p.max).c_str(),
                                p.unit.empty() ? "" : " ", p.unit.c_str(), p.help.c_str()));
  }
  if (p.integer && value != std::floor(value)) {
    return Status::Error(where + ": must be an integer" + (p.unit.empty() ? "" : " (" + p.unit + ")"));
  }
  p.Set(s, value);
  return Status::Ok();
}

namespace {

// A number of the reference as a scene file would write it: %g, without "+" and leading zeros in the
// exponent (1e+10 is 1e10).
std::string Number(double v) {
  // The fewest significant digits (6 at least) that read back as the same float: 1/90 s is 0.011111111.
  std::string text = Format("%g", v);
  for (int digits = 7; digits <= 9 && static_cast<float>(std::stod(text)) != static_cast<float>(v); ++digits) {
    text = Format("%.*g", digits, v);
  }
  const size_t e = text.find('e');
  if (e == std::string::npos) return text;
  std::string exponent = text.substr(e + 1);
  const bool negative = exponent[0] == '-';
  exponent = exponent.substr(exponent[0] == '+' || exponent[0] == '-' ? 1 : 0);
  exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
  return text.substr(0, e) + "e" + (negative ? "-" : "") + exponent;
}

void Table(const char* group, std::string* out) {
  *out += "| key | unit | default | range | meaning |\n|---|---|---|---|---|\n";
  for (const ParamDesc& p : ParamRegistry()) {
    if (p.group != group) continue;
    *out += "| `" + p.name + "` | " + p.unit + " | " + Number(p.defaultValue) + " | " + Number(p.min) + " – " +
            Number(p.max) + " | " + p.help + " |\n";
    if (p.name == "fixed_dt") {  // the one solver key that is a name, not a number (sim::SolverMethod)
      // `method`'s row from the solver table: its names and each method's one-line summary.
      std::string names, meaning = "the pressure solver:";
      for (const sim::SolverInfo& row : sim::SolverTable()) {
        names += std::string(names.empty() ? "" : ", ") + "`\"" + row.name + "\"`";
        meaning += std::string(" `") + row.name + "`, " + row.summary + ";";
      }
      meaning.back() = ' ';
      *out += Format("| `method` | | `\"%s\"` | %s | %s|\n", sim::SolverMethodName(sim::SceneSetup{}.method), names.c_str(),
                     meaning.c_str());
      *out += "| `density` | | `\"summation\"` | `\"summation\"`, `\"delta_sph\"` | wcsph: how a particle's density is "
              "found: summed over its neighbours every step (Becker & Teschner 2007), or integrated by the continuity "
              "equation with delta-SPH density diffusion (Molteni & Colagrossi 2009, Antuono et al. 2010; Fourtakas et "
              "al. 2019's hydrostatic correction); reuse needs `\"summation\"` and is switched off with one warning "
              "otherwise; dfsph ignores it ([../dev/physics.md](../dev/physics.md)) |\n";
    }
  }
}

}  // namespace

std::string SceneParameterReference() {
  std::string out = "### `solver`\n\n";
  Table("solver", &out);
  out += "\n### `reuse`\n\n";
  out += "Besides `enabled` (true or false) and `preset` (" + std::string(sim::ReusePresetNames()) +
         ": applied first, the section's other keys override it):\n\n";
  Table("reuse", &out);
  out += "\n### Limits\n\n";
  out += "What one scene may hold; a longer list is refused before any of it is read, and every check of a scene "
         "takes time in proportion to these counts (or n log n).\n\n| list | at most | what |\n|---|---:|---|\n";
  for (const sim::SceneLimitInfo& l : sim::SceneLimits()) out += Format("| `%s` | %d | %s |\n", l.key, l.limit, l.why);
  out += Format("| `probes.every` | at least %s s | and at most %lld rows in one step: every row is written |\n",
                Number(kMinProbeInterval).c_str(), static_cast<long long>(kMaxProbeRowsPerStep));
  return out;
}

}  // namespace sphxr::app
