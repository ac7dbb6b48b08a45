#include "sphxr/app/param_registry.h"

#include <cmath>
#include <string>
#include <vector>

#include "sphxr/common/log.h"

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
  auto reuseFloat = [&](const char* name, const char* unit, const char* help, float sim::ReuseParams::*m) {
    ParamDesc p;
    p.name = name;
    p.key = std::string("reuse.") + name;
    p.group = "reuse";
    p.unit = unit;
    p.help = help;
    p.min = 0.0;
    p.max = 1e9;
    p.defaultValue = reuseDefaults.*m;
    p.reuseFloat = m;
    out.push_back(p);
  };
  reuseFloat("delta1", "", "weight of the pressure term delta1 P_i / P_pc in ACT_i (Huang et al. 2013, 3.3)",
             &sim::ReuseParams::delta1);
  reuseFloat("delta2", "", "weight of the crowding term delta2 N_CPN / N_i in ACT_i", &sim::ReuseParams::delta2);
  reuseFloat("threshold", "", "ACT_i below this makes a particle inactive (it reuses its values)",
             &sim::ReuseParams::threshold);
  reuseFloat("pressure_scale", "Pa", "P_pc; 0 = the Tait pressure at 1 % compression", &sim::ReuseParams::pressureScale);
  reuseFloat("cell_count", "", "N_CPN; 0 = the rest lattice's particles per cell", &sim::ReuseParams::cellCount);
  const auto reuseInt = [&](const char* name, const char* unit, const char* help, int lo, int hi,
                            int sim::ReuseParams::*m) {
    ParamDesc p;
    p.name = name;
    p.key = std::string("reuse.") + name;
    p.group = "reuse";
    p.unit = unit;
    p.help = help;
    p.min = lo;
    p.max = hi;
    p.defaultValue = reuseDefaults.*m;
    p.integer = true;
    p.reuseInt = m;
    out.push_back(p);
  };
  reuseInt("idle", "steps", "IDLE: consecutive steps an inactive particle reuses its density, pressure and acceleration",
           0, 1000, &sim::ReuseParams::idle);
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
  if (p.integer && value != std::floor(value)) return Status::Error(where + ": must be an integer (" + p.unit + ")");
  if (value < p.min || value > p.max) {
    return Status::Error(Format("%s: %g is out of range: must be from %g to %g%s%s (%s)", where.c_str(), value, p.min,
                                p.max, p.unit.empty() ? "" : " ", p.unit.c_str(), p.help.c_str()));
  }
  p.Set(s, value);
  return Status::Ok();
}

namespace {

// A number of the reference as a scene file would write it: %g, without "+" and leading zeros in the
// exponent (1e+10 is 1e10).
std::string Number(double v) {
  std::string text = Format("%g", v);
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
      *out += Format("| `method` | | `\"%s\"` | `\"%s\"`, `\"%s\"` | the pressure solver: weakly compressible SPH (Tait) or "
                     "divergence-free SPH (Bender & Koschier 2017), whose step follows the flow speed "
                     "([../design/dfsph.md](../design/dfsph.md)) |\n",
                     sim::SolverMethodName(sim::SolverMethod::kWcsph), sim::SolverMethodName(sim::SolverMethod::kWcsph),
                     sim::SolverMethodName(sim::SolverMethod::kDfsph));
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
  return out;
}

}  // namespace sphxr::app
