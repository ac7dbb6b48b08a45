#pragma once
// One description of every tunable scene parameter (key, group, unit, help, range, default), read by
// the scene loader, the command line (--set) and the desktop panel, from sim's own tables
// (sim::SolverParamInfos() and sim::ReuseParamInfos(), which sim also validates against).
#include <span>
#include <string>

#include "sphxr/common/status.h"
#include "sphxr/sim/params.h"

namespace sphxr::app {

struct ParamDesc {
  std::string key;    // as in a scene file: "solver.stiffness", "reuse.threshold"
  std::string name;   // the key inside its section: "stiffness"
  std::string group;  // "solver" | "reuse"
  std::string unit;
  std::string help;
  double min = 0.0, max = 0.0;  // inclusive valid range
  double defaultValue = 0.0;
  bool integer = false;
  float sim::SolverParams::*solverMember = nullptr;  // group "solver"
  float sim::ReuseParams::*reuseFloat = nullptr;     // group "reuse", float
  int sim::ReuseParams::*reuseInt = nullptr;         // group "reuse", integer

  double Get(const sim::SceneSetup& s) const;
  void Set(sim::SceneSetup* s, double v) const;
};

std::span<const ParamDesc> ParamRegistry();
/// By full key ("reuse.idle") or, for solver parameters, by bare name ("stiffness").
const ParamDesc* FindParam(const std::string& key);
/// Checks `value` (integer, range) and stores it. Errors name `where` and the range.
Status SetParam(const ParamDesc& p, double value, const std::string& where, sim::SceneSetup* s);

}  // namespace sphxr::app
