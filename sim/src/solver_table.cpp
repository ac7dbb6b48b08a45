// The solver table (sphxr/sim/solver_table.h): one row per pressure solver.
#include "sphxr/sim/solver_table.h"

#include <array>

#include "solvers/dfsph/dfsph_rules.h"
#include "solvers/pbf/pbf_rules.h"
#include "solvers/wcsph/wcsph_rules.h"
#include "sphxr/common/assert.h"

namespace sphxr::sim {
namespace {

// One row per method; the functions a row names live in the method's folder (solvers/<method>/).
const std::array<SolverInfo, 3> kSolvers = {{
    {SolverMethod::kWcsph, "wcsph", "Becker & Teschner 2007 (weakly compressible SPH, Tait equation of state)",
     "weakly compressible SPH: explicit pressure from the Tait equation, a step bounded by the sound speed",
     /*wallDensity=*/true, /*deltaSph=*/true, /*reuse=*/true, ContactUse::kEveryParticle, /*acoustic=*/true,
     WcsphStableDt, /*columns=*/{}, WcsphBytes, /*speedCapParam=*/nullptr, /*warnAtStart=*/nullptr,
     /*paramsForSpacing=*/nullptr},
    {SolverMethod::kDfsph, "dfsph", "Bender & Koschier 2015, 2017 (divergence-free SPH)",
     "divergence-free SPH: implicit pressure from two Jacobi solves, a step that follows the flow speed "
     "([../design/dfsph.md](../design/dfsph.md))",
     false, false, false, ContactUse::kBelowRestDensity, false, DfsphStableDt, kDfsphColumns, DfsphBytes, nullptr,
     nullptr, nullptr},
    {SolverMethod::kPbf, "pbf", "Macklin & Müller 2013 (position based fluids)",
     "position-based fluids: a fixed number of Jacobi iterations of the density constraint per step, one step "
     "per displayed frame, so its cost per frame is fixed ([../design/pbf.md](../design/pbf.md))",
     false, false, false, ContactUse::kNone, false, PbfStableDt, kPbfColumns, PbfBytes,
     /*speedCapParam=*/"pbf_max_speed",  // the prediction's and the corrections' velocity are capped
     PbfWarnAtStart, PbfParamsForSpacing, PbfListMargin},
}};

}  // namespace

std::span<const SolverInfo> SolverTable() { return kSolvers; }

const SolverInfo& SolverInfoOf(SolverMethod method) {
  for (const SolverInfo& s : kSolvers) {
    if (s.method == method) return s;
  }
  SPHXR_ASSERT(false && "every SolverMethod has a row");
  return kSolvers[0];
}

const SolverInfo* FindSolver(const std::string& name) {
  for (const SolverInfo& s : kSolvers) {
    if (name == s.name) return &s;
  }
  return nullptr;
}

std::string SolverNames() {
  std::string out;
  for (const SolverInfo& s : kSolvers) out += (out.empty() ? "" : ", ") + std::string(s.name);
  return out;
}

const char* SolverMethodName(SolverMethod method) { return SolverInfoOf(method).name; }

bool ParseSolverMethod(const std::string& text, SolverMethod* out) {
  const SolverInfo* s = FindSolver(text);
  if (s) *out = s->method;
  return s != nullptr;
}

}  // namespace sphxr::sim
