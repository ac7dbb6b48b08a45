// Scene validation before a solver is built (every value of a SceneSetup, the grid, the particle
// counts and the memory they need), and the warnings about settings that run but will not give usable
// water.
#include "scene_check.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "backend.h"
#include "morton.h"
#include "sampling.h"
#include "sphxr/common/host_memory.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::sim {
namespace {

// Gravity above this (about 100 g) only makes the force step condition shrink dt towards nothing.
constexpr double kMaxGravity = 1000.0;
constexpr double kMaxFluidSpeed = 1000.0;  // m/s of a fluid block's start velocity

std::string Str(Vec3 v) { return Format("[%g, %g, %g]", v.x, v.y, v.z); }

Status ValidateBox(const Aabb& b, const std::string& key) {
  if (!Finite(b.min) || !Finite(b.max)) return Status::Error(key + ": min/max must be finite numbers");
  if (!(b.min.x < b.max.x && b.min.y < b.max.y && b.min.z < b.max.z)) {
    return Status::Error(key + ": min " + Str(b.min) + " must be below max " + Str(b.max) + " on every axis");
  }
  return Status::Ok();
}

bool Contains(const Aabb& outer, const Aabb& inner, float slack) {
  return inner.min.x >= outer.min.x - slack && inner.min.y >= outer.min.y - slack &&
         inner.min.z >= outer.min.z - slack && inner.max.x <= outer.max.x + slack &&
         inner.max.y <= outer.max.y + slack && inner.max.z <= outer.max.z + slack;
}

Status ValidateBodies(const SceneSetup& scene) {
  if (scene.bodies.size() > static_cast<size_t>(kMaxBodies)) {
    return Status::Error(Format("%zu moving bodies: at most %d", scene.bodies.size(), kMaxBodies));
  }
  const float tankSize = Length(scene.tank.max - scene.tank.min);
  for (size_t k = 0; k < scene.bodies.size(); ++k) {
    const RigidBodySetup& b = scene.bodies[k];
    const std::string key = Format("body %zu", k);
    if (b.shapes.empty()) return Status::Error(key + ": has no shape");
    if (b.shapes.size() > static_cast<size_t>(kMaxBodyShapes)) {
      return Status::Error(Format("%s: %zu shapes, at most %d", key.c_str(), b.shapes.size(), kMaxBodyShapes));
    }
    if (b.points.empty()) return Status::Error(key + ": has no boundary particles (its shapes are too small to sample)");
    for (const ShapePrimitive& p : b.shapes) {
      const bool box = p.kind == ShapePrimitive::Kind::kBox;
      if (!Finite(p.a) || !Finite(p.b) || !std::isfinite(p.radius)) return Status::Error(key + ": non-finite shape");
      if (box && !(p.b.x > 0.0f && p.b.y > 0.0f && p.b.z > 0.0f)) {
        return Status::Error(key + ": a box needs positive half extents, got " + Str(p.b));
      }
      if (!box && !(p.radius > 0.0f)) return Status::Error(Format("%s: a capsule needs a positive radius, got %g", key.c_str(), p.radius));
    }
    for (const Vec3& x : b.points) {
      if (!Finite(x)) return Status::Error(key + ": non-finite boundary particle");
    }
    if (!std::isfinite(b.viscosity) || b.viscosity > 10.0f) {
      return Status::Error(Format("%s: viscosity = %g is invalid: must be from 0 to 10 (negative: the walls')", key.c_str(), b.viscosity));
    }
    if (!Finite(b.pose.position) || !Finite(b.pose.orientation)) return Status::Error(key + ": non-finite pose");
    // A body larger than the whole tank cannot stir it, and its sampling would dwarf the water's.
    float reach = 0.0f;
    for (const Vec3& x : b.points) reach = std::max(reach, Length(x));
    if (reach > tankSize) {
      return Status::Error(Format("%s: its shapes reach %g m from its origin, more than the tank's %g m diagonal",
                                  key.c_str(), reach, tankSize));
    }
  }
  return Status::Ok();
}

// The first pair (i, j < i, the smallest i, then the smallest j: what a loop over all pairs finds
// first) of blocks overlapping by more than half a spacing on every axis. Each block, shrunk by a
// quarter spacing on every side, goes into the cells of a uniform grid of about one cell per block that
// it touches; only blocks sharing a cell are compared. Interior-disjoint blocks touch a few cells each,
// so the check is linear in the count (a pairwise loop is quadratic in it). A grid that would
// take more than kBudget entries (blocks spanning many cells) is made coarser.
Status CheckBlocksApart(const SceneSetup& scene) {
  const size_t n = scene.fluid.size();
  if (n < 2) return Status::Ok();
  const float q = 0.25f * scene.params.spacing;
  std::vector<Aabb> shrunk(n);
  for (size_t i = 0; i < n; ++i) shrunk[i] = Aabb{scene.fluid[i].box.min + Vec3{q, q, q}, scene.fluid[i].box.max - Vec3{q, q, q}};
  auto overlap = [&](size_t i, size_t j) {
    const Aabb& a = shrunk[i];
    const Aabb& b = shrunk[j];
    return a.min.x < b.max.x && b.min.x < a.max.x && a.min.y < b.max.y && b.min.y < a.max.y && a.min.z < b.max.z &&
           b.min.z < a.max.z;
  };
  const Aabb& t = scene.tank;
  const size_t kBudget = 16 * n + (size_t{1} << 20);
  int cells = std::clamp(static_cast<int>(std::ceil(std::cbrt(static_cast<double>(n)))), 1, 128);
  std::vector<uint32_t> start, entries;
  std::vector<int> lo(3 * n), hi(3 * n);
  for (;; cells = std::max(1, cells / 2)) {
    const float span[3] = {t.max.x - t.min.x, t.max.y - t.min.y, t.max.z - t.min.z};
    const float origin[3] = {t.min.x, t.min.y, t.min.z};
    auto cell = [&](float x, int a) {
      return std::clamp(static_cast<int>(std::floor((x - origin[a]) / span[a] * cells)), 0, cells - 1);
    };
    size_t total = 0;
    for (size_t i = 0; i < n; ++i) {
      const float mn[3] = {shrunk[i].min.x, shrunk[i].min.y, shrunk[i].min.z};
      const float mx[3] = {shrunk[i].max.x, shrunk[i].max.y, shrunk[i].max.z};
      size_t count = 1;
      for (int a = 0; a < 3; ++a) {
        lo[3 * i + a] = cell(mn[a], a);
        hi[3 * i + a] = mn[a] < mx[a] ? cell(mx[a], a) : lo[3 * i + a] - 1;  // empty: thinner than half a spacing
        count *= static_cast<size_t>(std::max(0, hi[3 * i + a] - lo[3 * i + a] + 1));
      }
      total += count;
    }
    if (total > kBudget && cells > 1) continue;
    // Counting sort of (cell, block) entries: start[c] .. start[c + 1] are the blocks in cell c, in order.
    const size_t cellCount = static_cast<size_t>(cells) * cells * cells;
    start.assign(cellCount + 1, 0);
    auto each = [&](size_t i, auto&& f) {
      for (int x = lo[3 * i]; x <= hi[3 * i]; ++x)
        for (int y = lo[3 * i + 1]; y <= hi[3 * i + 1]; ++y)
          for (int z = lo[3 * i + 2]; z <= hi[3 * i + 2]; ++z) f((static_cast<size_t>(x) * cells + y) * cells + z);
    };
    for (size_t i = 0; i < n; ++i) each(i, [&](size_t c) { ++start[c + 1]; });
    for (size_t c = 0; c < cellCount; ++c) start[c + 1] += start[c];
    entries.assign(total, 0);
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t i = 0; i < n; ++i) each(i, [&](size_t c) { entries[fill[c]++] = static_cast<uint32_t>(i); });
    break;
  }
  size_t bestI = n, bestJ = n;
  for (size_t c = 0; c + 1 < start.size(); ++c) {
    for (uint32_t a = start[c]; a < start[c + 1]; ++a) {
      const size_t i = entries[a];
      if (i > bestI) break;  // entries ascend within a cell
      for (uint32_t b = start[c]; b < a; ++b) {
        const size_t j = entries[b];
        if ((i < bestI || j < bestJ) && overlap(i, j)) {
          bestI = i;
          bestJ = j;
          break;  // the smallest j for this i in this cell
        }
      }
    }
  }
  if (bestI == n) return Status::Ok();
  const Aabb& a = scene.fluid[bestI].box;
  const Aabb& b = scene.fluid[bestJ].box;
  return Status::Error(Format("fluid[%zu] %s to %s overlaps fluid[%zu] %s to %s: their particles would sit on top of "
                              "each other; make the blocks touch, not overlap",
                              bestI, Str(a.min).c_str(), Str(a.max).c_str(), bestJ, Str(b.min).c_str(), Str(b.max).c_str()));
}

/// The solver's parameters (each within its registry range, whole where it must be), reuse's, and the
/// ones that must be ordered.
Status ValidateParams(const SceneSetup& scene) {
  for (const ParamInfo& p : SolverParamInfos()) {
    const float v = scene.params.*p.member;
    // Compared as floats: the value is stored as one, so the limit typed exactly (cfl 0.01) must pass.
    if (!std::isfinite(v) || v < static_cast<float>(p.min) || v > static_cast<float>(p.max)) {
      return Status::Error(Format("solver.%s = %g is invalid: must be a number from %g to %g%s%s (%s)", p.key, v, p.min,
                                  p.max, p.unit[0] ? " " : "", p.unit, p.help));
    }
    if (p.integer && v != std::floor(v)) return Status::Error(Format("solver.%s = %g is invalid: must be a whole number", p.key, v));
  }
  if (Status s = ValidateReuse(scene.reuse); !s) return s;
  if (scene.params.minIterations > scene.params.maxIterations) {
    return Status::Error(Format("solver.min_iterations = %g is above solver.max_iterations = %g",
                                scene.params.minIterations, scene.params.maxIterations));
  }
  if (scene.params.maxDivergenceIterations > 0 &&
      scene.params.minDivergenceIterations > scene.params.maxDivergenceIterations) {
    return Status::Error(Format("solver.min_divergence_iterations = %g is above solver.max_divergence_iterations = %g",
                                scene.params.minDivergenceIterations, scene.params.maxDivergenceIterations));
  }
  {
    // The diffuse particles' potential ranges (Ihmsen et al. 2012, eq. 1 divides by max - min).
    const SolverParams& p = scene.params;
    const struct {
      const char* name;
      float lo, hi;
    } ranges[] = {{"trapped_air", p.diffuseTrappedAirMin, p.diffuseTrappedAirMax},
                  {"wave_crest", p.diffuseWaveCrestMin, p.diffuseWaveCrestMax},
                  {"energy", p.diffuseEnergyMin, p.diffuseEnergyMax}};
    for (const auto& r : ranges) {
      if (!(r.lo < r.hi)) {
        return Status::Error(Format("solver.diffuse_%s_min = %g must be below solver.diffuse_%s_max = %g", r.name, r.lo,
                                    r.name, r.hi));
      }
    }
    if (p.diffuseSprayBelow > p.diffuseBubbleAbove + 1.0f) {
      return Status::Error(Format("solver.diffuse_spray_below = %g is above solver.diffuse_bubble_above + 1 = %g: a "
                                  "particle would be spray and a bubble at once",
                                  p.diffuseSprayBelow, p.diffuseBubbleAbove + 1.0f));
    }
  }
  return Status::Ok();
}

Status ValidateGravity(const SceneSetup& scene) {
  if (!Finite(scene.gravity)) return Status::Error("gravity must be three finite numbers");
  const double gx = scene.gravity.x, gy = scene.gravity.y, gz = scene.gravity.z;
  const double g = std::sqrt(gx * gx + gy * gy + gz * gz);  // in double: a float Length overflows at 2e19
  if (g > kMaxGravity) {
    return Status::Error(Format("gravity = %s has magnitude %g m/s^2: at most %g (%.0f g) is supported",
                                Str(scene.gravity).c_str(), g, kMaxGravity, kMaxGravity / 9.81));
  }
  return Status::Ok();
}

Status ValidateTank(const SceneSetup& scene) {
  if (scene.boundaryLayers < 1 || scene.boundaryLayers > 4) {
    return Status::Error(Format("tank.boundary_layers = %d is invalid: must be 1 to 4", scene.boundaryLayers));
  }
  return ValidateBox(scene.tank, "tank");
}

/// A block's start speed: within what is supported, below the sound speed of an acoustic method, and
/// not above the speed a method caps every particle to (its row's speedCapParam).
Status ValidateBlockSpeed(const SceneSetup& scene, size_t i, const SolverInfo& method, float soundSpeed) {
  const std::string key = Format("fluid[%zu]", i);
  // (Far past any water: refused here with the key named, before the first step's CFL limit would
  // collapse with a message about instability.)
  const Vec3 v = scene.fluid[i].velocity;
  const double speed = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  if (speed > kMaxFluidSpeed) {
    return Status::Error(Format("%s.velocity = %s has speed %g m/s: at most %g m/s is supported", key.c_str(),
                                Str(v).c_str(), speed, kMaxFluidSpeed));
  }
  // A weakly compressible fluid faster than its own sound speed is not water: its step resolves the
  // pressure waves, and the block outruns them (the speeds and compression explode within steps). The
  // methods that solve for the density are not bound by it (the row's `acoustic`, solver_table.h).
  if (method.acoustic && speed > soundSpeed) {
    return Status::Error(Format("%s.velocity: %g m/s is %.3gx the sound speed %.3g m/s of solver.method %s, whose "
                                "step cannot resolve it: lower the speed below %.3g m/s (0.1x for 1 %% density "
                                "error) or raise solver.stiffness",
                                key.c_str(), speed, speed / soundSpeed, soundSpeed, method.name, soundSpeed));
  }
  // A method that caps every speed would start the block slower than the scene says, silently.
  if (const ParamInfo* cap = method.speedCapParam ? FindSolverParam(method.speedCapParam) : nullptr;
      cap && speed > scene.params.*cap->member) {
    return Status::Error(Format("%s.velocity: %g m/s is above the %g m/s that solver.method %s holds every particle "
                                "to: lower the speed or raise solver.%s",
                                key.c_str(), speed, scene.params.*cap->member, method.name, cap->key));
  }
  return Status::Ok();
}

/// The fluid blocks: how many, each box, its velocity and its place in the tank; no two overlapping.
Status ValidateFluidBlocks(const SceneSetup& scene) {
  const float slack = 1e-5f * scene.params.spacing;
  if (scene.fluid.size() > static_cast<size_t>(kMaxFluidBlocks)) {
    return Status::Error(Format("fluid: %zu blocks, at most %d: merge blocks that touch", scene.fluid.size(),
                                kMaxFluidBlocks));
  }
  const SolverInfo& method = SolverInfoOf(scene.method);
  const float soundSpeed = std::sqrt(scene.params.exponent * scene.params.stiffness / scene.params.restDensity);
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const std::string key = Format("fluid[%zu]", i);
    if (Status s = ValidateBox(scene.fluid[i].box, key); !s) return s;
    if (!Finite(scene.fluid[i].velocity)) return Status::Error(key + ".velocity must be three finite numbers");
    if (Status s = ValidateBlockSpeed(scene, i, method, soundSpeed); !s) return s;
    if (!Contains(scene.tank, scene.fluid[i].box, slack)) {
      return Status::Error(key + ": the block " + Str(scene.fluid[i].box.min) + " to " + Str(scene.fluid[i].box.max) +
                           " is not inside the tank " + Str(scene.tank.min) + " to " + Str(scene.tank.max));
    }
  }
  // Overlapping blocks would put particles on top of each other (where their lattices share points,
  // exactly: such twins have no force between them and never separate) or closer than the spacing.
  // Blocks may touch; less than half a spacing of overlap is rounding.
  if (Status s = CheckBlocksApart(scene); !s) return s;
  return Status::Ok();
}

Status ValidateObstacles(const SceneSetup& scene) {
  const float slack = 1e-5f * scene.params.spacing;
  if (scene.obstacles.size() > static_cast<size_t>(kMaxObstacles)) {
    return Status::Error(Format("obstacles: %zu boxes given, at most %d are supported (each is checked for fluid "
                                "inside it every step): merge touching boxes",
                                scene.obstacles.size(), kMaxObstacles));
  }
  for (size_t i = 0; i < scene.obstacles.size(); ++i) {
    const std::string key = Format("obstacles[%zu]", i);
    if (Status s = ValidateBox(scene.obstacles[i], key); !s) return s;
    if (!Contains(scene.tank, scene.obstacles[i], slack)) {
      return Status::Error(key + ": the box is not inside the tank " + Str(scene.tank.min) + " to " +
                           Str(scene.tank.max));
    }
  }
  return Status::Ok();
}

/// Room for the walls' mass at the support factor, and a neighbour grid within the supported size.
Status ValidateWallsAndGrid(const SceneSetup& scene) {
  const float gamma = WallDensityCorrection(CubicSpline::Make(scene.params.spacing * scene.params.supportFactor),
                                            scene.params.spacing, scene.boundaryLayers);
  if (!(gamma > 0.0f)) {
    return Status::Error(Format("solver.support_factor = %g with %d boundary layer(s) leaves no room for the walls' "
                                "mass (the fluid lattice alone is over-dense): use a support factor of 2 or more",
                                scene.params.supportFactor, scene.boundaryLayers));
  }
  const GridShape grid = MakeGridShape(scene);
  const int dims[3] = {grid.nx, grid.ny, grid.nz};
  for (int a = 0; a < 3; ++a) {
    if (dims[a] > kMaxGridDim) {
      return Status::Error(Format("solver.spacing = %g makes the neighbour grid %d cells wide along %c; at most %d are "
                                  "supported: use a larger spacing or a smaller tank",
                                  scene.params.spacing, dims[a], "xyz"[a], kMaxGridDim));
    }
  }
  return Status::Ok();
}

/// The particles the scene samples and the memory they need, within what is supported and available.
Status ValidateParticleBudget(const SceneSetup& scene) {
  const GridShape grid = MakeGridShape(scene);
  // The CPU's SIMD stages gather a particle's Vec4 fields with 32-bit offsets of 4 floats per particle.
  constexpr int64_t kMaxParticles = int64_t{1} << 29;
  if (!scene.obstacles.empty() || !scene.bodies.empty()) {
    // CountParticles walks the fluid lattice when obstacles or bodies take part of it (slow for a fine
    // lattice): the lattice without them, a closed form, is checked first. Its memory is an upper
    // bound, so a scene refused here says "up to".
    SceneSetup open;
    open.params = scene.params;
    open.fluid = scene.fluid;
    ParticleCounts bound;
    bound.fluid = SampleFluid(open, nullptr);
    bound.boundary = SampleBoundary(scene, nullptr);
    bound.gridCells = grid.Cells();
    bound.neighbourSlots = NeighbourCapacity(scene.params.supportFactor);
    for (const RigidBodySetup& b : scene.bodies) bound.bodyParticles += static_cast<int64_t>(b.points.size());
    bound.reuse = scene.reuse.enabled;
    bound.wallDensity = scene.wallPressure == SceneSetup::WallPressure::kWallDensity;
    const double needBound = static_cast<double>(EstimateMemoryBytes(bound));
    if (bound.fluid >= kMaxParticles || needBound > static_cast<double>(AvailableHostBytes())) {
      return Status::Error(Format("solver.spacing = %g gives up to %lld fluid particles (%.1f GiB) before the obstacles "
                                  "and paddles take their room; at most %lld and %.1f GiB: use a larger spacing",
                                  scene.params.spacing, static_cast<long long>(bound.fluid), needBound / 1073741824.0,
                                  static_cast<long long>(kMaxParticles - 1), AvailableHostBytes() / 1073741824.0));
    }
  }
  const ParticleCounts counts = CountParticles(scene);
  if (counts.fluid >= kMaxParticles || counts.boundary >= kMaxParticles) {
    return Status::Error(Format("solver.spacing = %g gives %lld fluid and %lld boundary particles; at most %lld of each "
                                "are supported: use a larger spacing",
                                scene.params.spacing, static_cast<long long>(counts.fluid),
                                static_cast<long long>(counts.boundary), static_cast<long long>(kMaxParticles - 1)));
  }
  const int64_t need = EstimateMemoryBytes(counts);
  const int64_t have = AvailableHostBytes();
  if (need > have) {
    return Status::Error(Format("solver.spacing = %g gives %lld fluid and %lld boundary particles, needing about %.1f GiB; "
                                "this machine allows %.1f GiB: use a larger spacing",
                                scene.params.spacing, static_cast<long long>(counts.fluid),
                                static_cast<long long>(counts.boundary), need / 1073741824.0, have / 1073741824.0));
  }
  return Status::Ok();
}

}  // namespace

Status ValidateReuse(const ReuseParams& r) {
  for (const ReuseParamInfo& p : ReuseParamInfos()) {
    if (p.count) {
      const int v = r.*p.count;
      if (v < p.min || v > p.max) {
        return Status::Error(Format("reuse.%s = %d is invalid: must be %g to %g %s", p.key, v, p.min, p.max, p.unit));
      }
      continue;
    }
    const float v = r.*p.real;
    // Compared as floats, as the solver parameters are (ValidateScene).
    if (!std::isfinite(v) || v < static_cast<float>(p.min) || v > static_cast<float>(p.max)) {
      return Status::Error(Format("reuse.%s = %g is invalid: must be a number from %g to %g", p.key, v, p.min, p.max));
    }
  }
  return Status::Ok();
}

Status ValidateScene(const SceneSetup& scene) {
  for (auto check : {ValidateParams, ValidateGravity, ValidateTank, ValidateFluidBlocks, ValidateObstacles,
                     ValidateBodies, ValidateWallsAndGrid, ValidateParticleBudget}) {
    if (Status s = check(scene); !s) return s;
  }
  return Status::Ok();
}

// Reuse settings measured unstable are named when they are set (at start-up and by SetReuse).
void WarnAboutReuse(const ReuseParams& reuse) {
  constexpr int kStableIdle = 3;
  if (reuse.enabled && reuse.idle > kStableIdle) {
    // Measured (docs/design/impulse_hold.md): at the CFL step the deep tank and dam_break_1m blew up at
    // IDLE 5 with the impulse hold (and the deep tank at IDLE 7 before).
    SPHXR_LOG_WARN("reuse.idle = %d: IDLE above %d was measured unstable at the CFL step "
                   "(the held kick outruns the pressure waves); use IDLE <= %d or a smaller cfl",
                   reuse.idle, kStableIdle, kStableIdle);
  }
}

static void WarnAboutBlocks(const SceneSetup& scene, const SolverInfo& method, float soundSpeed);

// Settings that run but will not give usable water are named at start-up, once.
void WarnAboutSettings(const SceneSetup& scene, int64_t seeded, float soundSpeed) {
  // Fluid is not seeded inside the moving bodies at their start poses: say how much that leaves out (a
  // paddle larger than the water can leave most of it out). `seeded`: the particles Create made; the
  // count without the bodies is a closed form unless there are obstacles.
  if (!scene.bodies.empty()) {
    SceneSetup without = scene;
    without.bodies.clear();
    const int64_t all = SampleFluid(without, nullptr);
    if (seeded < all) {
      const bool most = 2 * seeded < all;
      Log(most ? LogLevel::kWarn : LogLevel::kInfo,
          "the paddles at their start poses leave %lld of the %lld fluid lattice sites empty%s",
          static_cast<long long>(all - seeded), static_cast<long long>(all), most ? ": most of the water" : "");
    }
  }
  const float g = Length(scene.gravity);
  float height = 0.0f;
  for (const FluidBlock& b : scene.fluid) height = std::max(height, b.box.max.y - scene.tank.min.y);
  const float vRef = std::sqrt(2.0f * g * height);
  // What the method supports and what bounds it: its row of the solver table.
  const SolverInfo& method = SolverInfoOf(scene.method);
  if (method.acoustic && vRef > 0.0f && soundSpeed < 5.0f * vRef) {
    const float needB = scene.params.restDensity * 100.0f * vRef * vRef / scene.params.exponent;
    SPHXR_LOG_WARN("sound speed %.3g m/s is only %.1fx the expected flow speed sqrt(2gH) = %.3g m/s: expect density "
                   "errors above 1%% (WCSPH wants 10x); solver.stiffness >= %.3g Pa would give that",
                   soundSpeed, soundSpeed / vRef, vRef, needB);
  }
  if (method.warnAtStart) method.warnAtStart(scene, height);  // the method's own (its row)
  const bool deltaSph = scene.density == DensityModel::kDeltaSph;
  if (!method.deltaSph && deltaSph) {
    SPHXR_LOG_WARN("solver.density delta_sph is not a model of solver.method %s, which sums the density (the setting "
                   "is ignored)", method.name);
  }
  if (!method.wallDensity && scene.wallPressure == SceneSetup::WallPressure::kWallDensity) {
    SPHXR_LOG_WARN("tank.wall_pressure wall_density is not a model of solver.method %s (the walls' particles take "
                   "Akinci's volumes)", method.name);
  }
  if (method.reuse && deltaSph && scene.reuse.enabled) {
    SPHXR_LOG_WARN("reuse is off under solver.density delta_sph: an integrated density cannot skip steps (use "
                   "\"summation\" for reuse)");
  } else if (method.reuse) {
    WarnAboutReuse(scene.reuse);
  } else if (scene.reuse.enabled) {
    SPHXR_LOG_WARN("reuse is a WCSPH scheme and is off under solver.method %s", method.name);
  }
  WarnAboutBlocks(scene, method, soundSpeed);
}

// One line for each kind of warning about the fluid blocks, naming the first block and counting the
// others (a scene may hold tens of thousands of blocks).
static void WarnAboutBlocks(const SceneSetup& scene, const SolverInfo& method, float soundSpeed) {
  size_t thin = 0, fast = 0, firstThin = 0, firstFast = 0;
  float thinnest = 0.0f, fastest = 0.0f;
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const Aabb& b = scene.fluid[i].box;
    const float t = std::min({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
    if (t < 3.0f * scene.params.spacing) {
      if (thin++ == 0) firstThin = i, thinnest = t;
    }
    // Weak compressibility holds below Mach 0.1 (about 1 % compression).
    const float speed = Length(scene.fluid[i].velocity);
    if (method.acoustic && speed > 0.1f * soundSpeed) {
      if (fast++ == 0) firstFast = i, fastest = speed;
    }
  }
  const std::string thinOthers = thin > 1 ? Format(" (and %zu more blocks)", thin - 1) : std::string();
  const std::string fastOthers = fast > 1 ? Format(" (and %zu more blocks)", fast - 1) : std::string();
  if (thin > 0) {
    SPHXR_LOG_WARN("fluid[%zu] is only %.1f spacings thick%s: too coarse to behave like water", firstThin,
                   thinnest / scene.params.spacing, thinOthers.c_str());
  }
  if (fast > 0) {
    SPHXR_LOG_WARN("fluid[%zu].velocity: %.3g m/s is %.2gx the sound speed %.3g m/s%s: expect large density errors "
                   "(WCSPH wants below 0.1x; raise solver.stiffness or lower the speed)",
                   firstFast, fastest, fastest / soundSpeed, soundSpeed, fastOthers.c_str());
  }
}

}  // namespace sphxr::sim
