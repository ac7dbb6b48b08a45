#include "sphxr/sim/solver.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <cmath>
#include <limits>

#include "backend.h"
#include "morton.h"
#include "sampling.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/host_grid.h"

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

int64_t AvailableHostBytes() {
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long pageSize = sysconf(_SC_PAGE_SIZE);
  int64_t have = std::numeric_limits<int64_t>::max();
  if (pages > 0 && pageSize > 0) have = static_cast<int64_t>(pages) * pageSize * 3 / 4;  // a quarter to the OS and renderer
  // A process limit (ulimit -v) is a harder ceiling; half of it, as the program and its libraries
  // (OpenGL, OpenMP stacks) map a lot of address space of their own.
  struct rlimit limit;
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    have = std::min<int64_t>(have, static_cast<int64_t>(limit.rlim_cur / 2));
  }
  // In a container the memory cgroup's limit is the real one (past it the OOM killer ends the process,
  // instead of this friendly refusal): v2's memory.max ("max": none), v1's limit_in_bytes (a huge
  // number: none). Three quarters of it, as of the physical memory.
  // (v2: also the process's own cgroup, from /proc/self/cgroup's "0::/path": systemd and batch
  // schedulers set the limit there, not at the root.)
  std::vector<std::string> limits = {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"};
  {
    std::ifstream cgroup("/proc/self/cgroup");
    std::string line;
    while (std::getline(cgroup, line)) {
      if (line.rfind("0::/", 0) == 0 && line.size() > 4) limits.push_back("/sys/fs/cgroup" + line.substr(3) + "/memory.max");
    }
  }
  for (const std::string& path : limits) {
    std::ifstream in(path);
    long long bytes = 0;
    if (in >> bytes && bytes > 0) have = std::min<int64_t>(have, bytes / 4 * 3);
  }
  return have;
}

Status ValidateReuse(const ReuseParams& r) {
  const float values[] = {r.delta1, r.delta2, r.threshold, r.pressureScale, r.cellCount};
  const char* names[] = {"delta1", "delta2", "threshold", "pressure_scale", "cell_count"};
  for (int k = 0; k < 5; ++k) {
    if (!std::isfinite(values[k]) || values[k] < 0.0f || values[k] > 1e9f) {
      return Status::Error(Format("reuse.%s = %g is invalid: must be a number from 0 to 1e9", names[k], values[k]));
    }
  }
  if (r.idle < 0 || r.idle > 1000) {
    return Status::Error(Format("reuse.idle = %d is invalid: must be 0 to 1000 steps", r.idle));
  }
  return Status::Ok();
}


Status ValidateBodies(const SceneSetup& scene) {
  if (scene.bodies.size() > 64) return Status::Error(Format("%zu moving bodies: at most 64", scene.bodies.size()));
  const float tankSize = Length(scene.tank.max - scene.tank.min);
  for (size_t k = 0; k < scene.bodies.size(); ++k) {
    const RigidBodySetup& b = scene.bodies[k];
    const std::string key = Format("body %zu", k);
    if (b.shapes.empty()) return Status::Error(key + ": has no shape");
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

Status ValidateScene(const SceneSetup& scene) {
  for (const ParamInfo& p : SolverParamInfos()) {
    const float v = scene.params.*p.member;
    // Compared as floats: the value is stored as one, so the limit typed exactly (cfl 0.01) must pass.
    if (!std::isfinite(v) || v < static_cast<float>(p.min) || v > static_cast<float>(p.max)) {
      return Status::Error(Format("solver.%s = %g is invalid: must be a number from %g to %g%s%s (%s)", p.key, v, p.min,
                                  p.max, p.unit[0] ? " " : "", p.unit, p.help));
    }
    if (p.integer && v != std::floor(v)) return Status::Error(Format("solver.%s = %g is invalid: must be a whole number", p.key, v));
  }
  if (!std::isfinite(scene.floorViscosity) || scene.floorViscosity > 10.0f) {
    return Status::Error(Format("tank.floor_viscosity = %g is invalid: must be from 0 to 10", scene.floorViscosity));
  }
  if (Status s = ValidateReuse(scene.reuse); !s) return s;
  if (scene.params.minIterations > scene.params.maxIterations) {
    return Status::Error(Format("solver.min_iterations = %g is above solver.max_iterations = %g",
                                scene.params.minIterations, scene.params.maxIterations));
  }
  if (!Finite(scene.gravity)) return Status::Error("gravity must be three finite numbers");
  {
    const double gx = scene.gravity.x, gy = scene.gravity.y, gz = scene.gravity.z;
    const double g = std::sqrt(gx * gx + gy * gy + gz * gz);  // in double: a float Length overflows at 2e19
    if (g > kMaxGravity) {
      return Status::Error(Format("gravity = %s has magnitude %g m/s^2: at most %g (%.0f g) is supported",
                                  Str(scene.gravity).c_str(), g, kMaxGravity, kMaxGravity / 9.81));
    }
  }
  if (scene.boundaryLayers < 1 || scene.boundaryLayers > 4) {
    return Status::Error(Format("tank.boundary_layers = %d is invalid: must be 1 to 4", scene.boundaryLayers));
  }
  if (Status s = ValidateBox(scene.tank, "tank"); !s) return s;
  const float slack = 1e-5f * scene.params.spacing;
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const std::string key = Format("fluid[%zu]", i);
    if (Status s = ValidateBox(scene.fluid[i].box, key); !s) return s;
    if (!Finite(scene.fluid[i].velocity)) return Status::Error(key + ".velocity must be three finite numbers");
    {
      // (Far past any water: at 1e30 m/s the first step's CFL limit collapsed with a message about
      // instability, not about the key.)
      const Vec3 v = scene.fluid[i].velocity;
      const double speed = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
      if (speed > kMaxFluidSpeed) {
        return Status::Error(Format("%s.velocity = %s has speed %g m/s: at most %g m/s is supported", key.c_str(),
                                    Str(v).c_str(), speed, kMaxFluidSpeed));
      }
    }
    if (!Contains(scene.tank, scene.fluid[i].box, slack)) {
      return Status::Error(key + ": the block " + Str(scene.fluid[i].box.min) + " to " + Str(scene.fluid[i].box.max) +
                           " is not inside the tank " + Str(scene.tank.min) + " to " + Str(scene.tank.max));
    }
  }
  // Overlapping blocks would put particles on top of each other (where their lattices share points,
  // exactly: such twins have no force between them and never separate) or closer than the spacing.
  // Blocks may touch.
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      const Aabb& a = scene.fluid[i].box;
      const Aabb& b = scene.fluid[j].box;
      const float d = scene.params.spacing * 0.5f;  // less than half a spacing of overlap is rounding
      if (a.min.x < b.max.x - d && b.min.x < a.max.x - d && a.min.y < b.max.y - d && b.min.y < a.max.y - d &&
          a.min.z < b.max.z - d && b.min.z < a.max.z - d) {
        return Status::Error(Format("fluid[%zu] %s to %s overlaps fluid[%zu] %s to %s: their particles would sit on "
                                    "top of each other; make the blocks touch, not overlap",
                                    i, Str(a.min).c_str(), Str(a.max).c_str(), j, Str(b.min).c_str(),
                                    Str(b.max).c_str()));
      }
    }
  }
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
  if (Status s = ValidateBodies(scene); !s) return s;
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
  // The CPU's SIMD stages gather a particle's Vec4 fields with 32-bit offsets of 4 floats per particle.
  constexpr int64_t kMaxParticles = int64_t{1} << 29;
  if (!scene.obstacles.empty() || !scene.bodies.empty()) {
    // CountParticles walks the fluid lattice when obstacles or bodies take part of it (1.1e9 sites took
    // 20 s before a refusal): the lattice without them, a closed form, is checked first. Its memory is
    // an upper bound, so a scene refused here says "up to".
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

// Settings that run but will not give usable water are named at start-up, once.
void WarnAboutSettings(const SceneSetup& scene, int64_t seeded, float soundSpeed) {
  // Fluid is not seeded inside the moving bodies at their start poses: say how much that leaves out (a
  // paddle larger than the water removed 1,484 of 1,575 particles without a word). `seeded`: the
  // particles Create made; the count without the bodies is a closed form unless there are obstacles.
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
  const bool wcsph = scene.method == SolverMethod::kWcsph;
  if (wcsph && vRef > 0.0f && soundSpeed < 5.0f * vRef) {
    const float needB = scene.params.restDensity * 100.0f * vRef * vRef / scene.params.exponent;
    SPHXR_LOG_WARN("sound speed %.3g m/s is only %.1fx the expected flow speed sqrt(2gH) = %.3g m/s: expect density "
                   "errors above 1%% (WCSPH wants 10x); solver.stiffness >= %.3g Pa would give that",
                   soundSpeed, soundSpeed / vRef, vRef, needB);
  }
  const bool deltaSph = scene.density == DensityModel::kDeltaSph;
  if (!wcsph && deltaSph) {
    SPHXR_LOG_WARN("solver.density delta_sph is a WCSPH model; DFSPH sums the density (the setting is ignored)");
  }
  if (wcsph && deltaSph && scene.reuse.enabled) {
    SPHXR_LOG_WARN("reuse is off under solver.density delta_sph: an integrated density cannot skip steps (use "
                   "\"summation\" for reuse)");
  } else if (wcsph) {
    WarnAboutReuse(scene.reuse);
  } else if (scene.reuse.enabled) {
    SPHXR_LOG_WARN("reuse is a WCSPH scheme and is off under solver.method dfsph (docs/design/dfsph.md)");
  }
  for (size_t i = 0; i < scene.fluid.size(); ++i) {
    const Aabb& b = scene.fluid[i].box;
    const float thin = std::min({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
    if (thin < 3.0f * scene.params.spacing) {
      SPHXR_LOG_WARN("fluid[%zu] is only %.1f spacings thick: too coarse to behave like water", i,
                     thin / scene.params.spacing);
    }
    // Weak compressibility holds below Mach 0.1 (about 1 % compression); a block started at 1,000 m/s
    // compressed by 885 % without a word.
    const float speed = Length(scene.fluid[i].velocity);
    if (speed > 0.1f * soundSpeed) {
      SPHXR_LOG_WARN("fluid[%zu].velocity: %.3g m/s is %.2gx the sound speed %.3g m/s: expect large density errors "
                     "(WCSPH wants below 0.1x; raise solver.stiffness or lower the speed)",
                     i, speed, speed / soundSpeed, soundSpeed);
    }
  }
}

Physics MakePhysics(const SceneSetup& scene) {
  const SolverParams& p = scene.params;
  Physics ph;
  const float support = p.spacing * p.supportFactor;
  ph.kernel = CubicSpline::Make(support);
  ph.mass = p.restDensity * p.spacing * p.spacing * p.spacing;
  ph.restDensity = p.restDensity;
  ph.invRestDensity = 1.0f / p.restDensity;
  ph.boundaryGamma = WallDensityCorrection(ph.kernel, p.spacing, scene.boundaryLayers);
  ph.boundaryGradScale = WallGradientCorrection(ph.kernel, p.spacing, scene.boundaryLayers) / ph.boundaryGamma;
  // DFSPH's solve gives every wall its pressure (the boundary term of the Jacobi update): the walls' own
  // density is a WCSPH model.
  ph.dfsph = scene.method == SolverMethod::kDfsph;
  ph.wallDensity = scene.wallPressure == SceneSetup::WallPressure::kWallDensity && !ph.dfsph;
  ph.maxNeighbours = NeighbourCapacity(p.supportFactor);
  // Moving bodies are one-sheet shells (interaction::SamplePaddle): their own flat-wall corrections.
  ph.bodyGradScale = WallGradientCorrection(ph.kernel, p.spacing, 1) / WallDensityCorrection(ph.kernel, p.spacing, 1);
  ph.bodyClearance = 0.25f * p.spacing;
  const ReuseParams& r = scene.reuse;
  ph.continuityDensity = scene.density == DensityModel::kDeltaSph && !ph.dfsph;
  // Reuse is WCSPH's (docs/design/dfsph.md), and holds a summation density: an integrated density
  // cannot skip steps.
  ph.reuseEnabled = r.enabled && !ph.dfsph && !ph.continuityDensity;
  ph.reuseDelta1 = r.delta1;
  ph.reuseDelta2 = r.delta2;
  ph.reuseThreshold = r.threshold;
  ph.reuseIdle = r.idle;
  // P_pc: the Tait pressure at 1 % compression unless the scene sets it (our copy of the paper stops
  // before its parameter values); N_CPN: the rest lattice's particles per cell, (cell / dx)^3.
  const float pc = r.pressureScale > 0.0f ? r.pressureScale : p.stiffness * (std::pow(1.01f, p.exponent) - 1.0f);
  ph.reuseInvPressureScale = 1.0f / pc;
  ph.reuseCellCount = r.cellCount > 0.0f ? r.cellCount : p.supportFactor * p.supportFactor * p.supportFactor;
  ph.reuseSyncStep = true;  // Solver::Step sets it from the step's number
  ph.stiffness = p.stiffness;
  ph.exponent = p.exponent;
  ph.soundSpeed = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  ph.smoothing = 0.5f * support;
  ph.alpha = p.viscosity;
  ph.gravity = scene.gravity;
  // Fluid particles are kept a quarter spacing inside the walls' boundary particles.
  const float inset = 0.25f * p.spacing;
  ph.domainMin = Vec3{scene.tank.min.x + inset, scene.tank.min.y + inset, scene.tank.min.z + inset};
  ph.domainMax = Vec3{scene.tank.max.x - inset, scene.tank.max.y - inset, scene.tank.max.z - inset};
  // Obstacles are sampled like the tank (a sheet half a spacing inside each face, fluid seeded half a
  // spacing outside): the same quarter-spacing inset, outward.
  ph.obstacleCount = static_cast<int>(std::min<size_t>(scene.obstacles.size(), kMaxObstacles));
  for (int k = 0; k < kMaxObstacles; ++k) {
    const bool used = k < ph.obstacleCount;
    const Aabb o = used ? scene.obstacles[k] : Aabb{};
    ph.obstacleMin[k] = used ? Vec3{o.min.x - inset, o.min.y - inset, o.min.z - inset} : Vec3{};
    ph.obstacleMax[k] = used ? Vec3{o.max.x + inset, o.max.y + inset, o.max.z + inset} : Vec3{};
  }
  ph.volume = ph.mass / p.restDensity;
  ph.densityTolerance = 0.01f * p.densityTolerance;  // % to a fraction
  ph.divergenceTolerance = 0.01f * p.divergenceTolerance;
  ph.minIterations = static_cast<int>(p.minIterations);
  ph.maxIterations = static_cast<int>(p.maxIterations);
  ph.maxDivergenceIterations = static_cast<int>(p.maxDivergenceIterations);
  return ph;
}

struct FieldCheck {
  const char* name;
  bool (*finite)(const HostFluid&, size_t);
};

}  // namespace

const char* DeviceName(Device device) {
  switch (device) {
    case Device::kAuto: return "auto";
    case Device::kCpu: return "cpu";
    case Device::kCuda: return "cuda";
    case Device::kCpuReference: return "cpu-reference";
  }
  return "?";
}

bool ParseDevice(const std::string& text, Device* out) {
  if (text == "auto") *out = Device::kAuto;
  else if (text == "cpu") *out = Device::kCpu;
  else if (text == "cuda") *out = Device::kCuda;
  else if (text == "cpu-reference") *out = Device::kCpuReference;
  else return false;
  return true;
}

bool CudaBackendCompiled() { return CudaCompiled(); }
int CudaDeviceCount() { return CudaDevices(); }

std::string ClampSiteName(int site) {
  static const char* const kFaces[kTankFaces] = {"x- wall", "x+ wall", "floor", "top", "z- wall", "z+ wall"};
  SPHXR_ASSERT(site >= 0 && site < kClampSites);
  return site < kTankFaces ? kFaces[site] : Format("obstacles[%d]", site - kTankFaces);
}

void Solver::WarnIfWallsLeak() {
  // Judged once the run has had a thousand particle-steps per particle's worth of chances (a few steps of
  // a large scene, some hundred of a small one), then at most once per run.
  if (m_leakWarned || m_totals.particleSteps < 100000) return;
  const double rate = static_cast<double>(m_totals.clampedEvents) / static_cast<double>(m_totals.particleSteps);
  if (rate <= kLeakingClampRate) return;
  m_leakWarned = true;
  int worst = 0;
  for (int k = 1; k < kClampSites; ++k) {
    if (m_totals.clampedAt[k] > m_totals.clampedAt[worst]) worst = k;
  }
  const double share = m_totals.clampedEvents > 0 ? static_cast<double>(m_totals.clampedAt[worst]) /
                                                        static_cast<double>(m_totals.clampedEvents)
                                                  : 0.0;
  SPHXR_LOG_WARN("the walls leak: %.3g clamps per 1,000 particle-steps by t = %.3g s (a clamp is a safety net at "
                 "under %.2g), %.0f %% of them at the %s; more boundary layers (tank.boundary_layers) or a larger "
                 "sound speed hold the water (logged once)",
                 1000.0 * rate, m_last.time, 1000.0 * kLeakingClampRate, 100.0 * share, ClampSiteName(worst).c_str());
}

const char* StageName(Stage stage) {
  switch (stage) {
    case Stage::kCells: return "cells";
    case Stage::kSort: return "sort";
    case Stage::kGrid: return "grid";
    case Stage::kActivity: return "activity";
    case Stage::kDensity: return "density";
    case Stage::kForces: return "forces";
    case Stage::kIntegrate: return "integrate";
    case Stage::kBodies: return "bodies";
    case Stage::kDivergence: return "divergence";
    case Stage::kPressure: return "pressure";
    default: return "?";
  }
}

Solver::~Solver() = default;

Status Solver::Create(const SceneSetup& scene, const SolverConfig& config, std::unique_ptr<Solver>* out) {
  out->reset();
  if (Status s = ValidateScene(scene); !s) return s;
  if (config.threads < 0) return Status::Error(Format("threads = %d is invalid: must be 0 (all) or more", config.threads));

  std::unique_ptr<Solver> solver(new Solver());
  solver->m_scene = scene;
  solver->m_config = config;

  // Device choice: auto takes CUDA only when a device answers; explicit cuda without one is an error.
  Device device = config.device;
  if (device == Device::kAuto) {
    const int devices = CudaDevices();
    if (!CudaCompiled()) {
      SPHXR_LOG_INFO("device auto: CUDA backend not built, using the CPU backend");
      device = Device::kCpu;
    } else if (devices == 0) {
      SPHXR_LOG_INFO("device auto: no CUDA device found, using the CPU backend");
      device = Device::kCpu;
    } else {
      SPHXR_LOG_INFO("device auto: %d CUDA device(s) found, using the CUDA backend", devices);
      device = Device::kCuda;
    }
  }
  if (device == Device::kCuda) {
    std::string why;
    if (!CudaCompiled()) {
      MakeCudaBackend(&why);
      return Status::Error("--device cuda: " + why);
    }
    if (CudaDevices() == 0) {
      return Status::Error("--device cuda: no CUDA device available (no GPU or no driver); use --device cpu or auto");
    }
    solver->m_backend = MakeCudaBackend(&why);
  } else if (device == Device::kCpuReference) {
    solver->m_backend = MakeCpuReferenceBackend(config.threads);
  } else {
    solver->m_backend = MakeCpuBackend(config.threads, config.pairDensityBlocks);
  }
  solver->m_device = device;

  HostFluid fluid;
  std::vector<Vec4> positions;
  SampleFluid(scene, &positions);
  fluid.resize(positions.size());
  {
    size_t i = 0;
    for (const FluidBlock& block : scene.fluid) {
      // SampleFluid emits blocks in order; give each particle its block's initial velocity.
      SceneSetup one = scene;
      one.fluid = {block};
      const int64_t n = SampleFluid(one, nullptr);
      // delta_sph integrates the density from here: a hydrostatic block starts at the Tait density of
      // each particle's depth below the block's top layer (plus half a spacing), as its lattice is
      // compressed; everything else at rho0.
      const bool hydrostatic = block.hydrostatic && scene.density == DensityModel::kDeltaSph;
      float top = -std::numeric_limits<float>::infinity();
      for (int64_t k = 0; k < n; ++k) top = std::max(top, positions[i + k].y);
      top += 0.5f * scene.params.spacing;
      const SolverParams& p = scene.params;
      for (int64_t k = 0; k < n; ++k, ++i) {
        fluid.position[i] = positions[i];
        fluid.velocity[i] = MakeVec4(block.velocity);
        fluid.id[i] = static_cast<uint32_t>(i);
        fluid.density[i] = p.restDensity;
        if (hydrostatic) {
          const float head = p.restDensity * Length(scene.gravity) * (top - positions[i].y) / p.stiffness;
          fluid.density[i] = p.restDensity * std::pow(1.0f + head, 1.0f / p.exponent);
        }
        fluid.idle[i] = -1;  // every particle computes its first step
      }
    }
  }
  HostBoundary boundary;
  SampleBoundary(scene, &boundary.position, &boundary.viscosity);

  const Physics physics = MakePhysics(scene);
  if (physics.wallDensity) boundary.invReference = WallInverseReferences(scene, physics.kernel, boundary.position, 0.25f);
  if (Status s = solver->m_backend->Init(MakeGridShape(scene), physics, fluid, boundary); !s) return s;
  if (!scene.bodies.empty()) solver->InitBodies(physics);
  WarnAboutSettings(scene, static_cast<int64_t>(positions.size()), physics.soundSpeed);
  *out = std::move(solver);
  return Status::Ok();
}

int Solver::FluidCount() const { return m_backend->FluidCount(); }
int Solver::BoundaryCount() const { return m_backend->BoundaryCount(); }
float Solver::ParticleMass() const { return MakePhysics(m_scene).mass; }
float Solver::SoundSpeed() const { return MakePhysics(m_scene).soundSpeed; }

float Solver::StableDt() const {
  const SolverParams& p = m_scene.params;
  const float h = 0.5f * p.spacing * p.supportFactor;
  const float c = std::sqrt(p.exponent * p.stiffness / p.restDensity);
  float dt = p.maxDt;
  const float speed = std::max(m_last.maxSpeed, MaxBodySpeed());
  if (m_scene.method == SolverMethod::kDfsph) {
    // DFSPH's step follows the flow (Bender & Koschier 2017, sec. 5): no particle, fluid or paddle, moves
    // more than cfl * h per step. The pressure is implicit, so neither the sound speed nor the
    // acceleration limits it; the explicit viscosity still does.
    if (speed > 0.0f) dt = std::min(dt, p.cfl * h / speed);
    const float alpha = std::max({p.viscosity, p.boundaryViscosity, m_scene.floorViscosity});
    if (alpha > 0.0f) dt = std::min(dt, 0.5f * h / (alpha * c));
    return dt;
  }
  // Acoustic CFL condition (Monaghan 1992; Becker & Teschner 2007, sec. 5), with the fastest point of a
  // moving body: it then moves less than cfl * h per step, so it cannot jump over fluid particles.
  dt = std::min(dt, p.cfl * h / (c + speed));
  // Force condition: a particle must not move more than ~h/16 per step under its acceleration.
  const float accel = std::max(m_maxAccel, Length(m_scene.gravity));
  if (accel > 0.0f) dt = std::min(dt, 0.25f * std::sqrt(h / accel));
  // Viscous diffusion condition for the artificial viscosity (nu ~ alpha c h / 8).
  const float alpha = std::max({p.viscosity, p.boundaryViscosity, m_scene.floorViscosity});
  if (alpha > 0.0f) dt = std::min(dt, 0.5f * h / (alpha * c));
  return dt;
}

Status Solver::Step() {
  const auto begin = std::chrono::steady_clock::now();
  float dt = StableDt();
  const float fixedDt = m_scene.params.fixedDt;
  if (fixedDt > 0.0f) {
    if (fixedDt <= dt) {
      dt = fixedDt;
    } else {
      ++m_totals.dtClampedSteps;
      if (!m_dtClampLogged) {
        m_dtClampLogged = true;
        SPHXR_LOG_WARN("fixed_dt = %g s is above the stability limit %g s (CFL %g, sound speed %.3g m/s) at t = %.4g s: "
                       "clamped to the limit (logged once)",
                       fixedDt, dt, m_scene.params.cfl, SoundSpeed(), m_last.time);
      }
    }
  }

  // A step that cannot advance the clock would loop forever (the force condition under an exploding
  // acceleration): say so instead.
  if (!(dt > 0.0f) || !std::isfinite(dt) || m_last.time + dt == m_last.time) {
    return Status::Error(Format("the time step collapsed to %g s at t = %.6g s (largest acceleration %g m/s^2): the "
                                "simulation has become unstable",
                                dt, m_last.time, m_maxAccel));
  }
  const int64_t stepNumber = m_stepBase + m_totals.steps + 1;
  StageHook hook;
  HostFluid host;
  if (m_config.validate) {
    m_backend->Download(&host);
    for (size_t i = 0; i < host.size(); ++i) {
      if (!Finite(Xyz(host.position[i])) || !Finite(Xyz(host.velocity[i]))) {
        const char* field = Finite(Xyz(host.position[i])) ? "velocity" : "position";
        return Status::Error(Format("validate: non-finite %s of particle %u at the start of step %lld", field,
                                    host.id[i], static_cast<long long>(stepNumber)));
      }
    }
    hook = [&](Stage stage) -> Status {
      m_backend->Download(&host);
      for (size_t i = 0; i < host.size(); ++i) {
        const char* bad = nullptr;
        if (!Finite(Xyz(host.position[i]))) bad = "position";
        else if (!Finite(Xyz(host.velocity[i]))) bad = "velocity";
        else if ((stage == Stage::kForces || stage == Stage::kIntegrate) && !Finite(Xyz(host.acceleration[i])))
          bad = "acceleration";
        else if (stage >= Stage::kDensity && !std::isfinite(host.density[i])) bad = "density";
        else if (stage >= Stage::kDensity && !std::isfinite(host.pressure[i])) bad = "pressure";
        if (bad) {
          return Status::Error(Format("validate: non-finite %s of particle %u after stage '%s' in step %lld", bad,
                                      host.id[i], StageName(stage), static_cast<long long>(stepNumber)));
        }
      }
      return Status::Ok();
    };
  }

  StepReduction red;
  Physics physics = MakePhysics(m_scene);
  physics.reuseSyncStep = stepNumber % (physics.reuseIdle + 1) == 0;
  std::vector<BodyState> states;
  if (!m_bodies.empty()) {
    // Each body moves from its pose now to its interpolated pose at the end of the step; its particles
    // carry the rigid velocity that takes them there.
    const double end = m_last.time + dt;
    size_t firstShape = 0;
    for (BodyMotion& b : m_bodies) {
      const RigidPose to = BodyPoseAt(b, end);
      BodyState st{};
      st.position = b.pose.position;
      st.orientation = b.pose.orientation;
      st.velocity = (to.position - b.pose.position) * (1.0f / dt);
      st.angular = RotationVector(Mul(to.orientation, Conjugate(b.pose.orientation))) * (1.0f / dt);
      st.endPosition = to.position;
      st.endOrientation = to.orientation;
      st.boundRadius = b.boundRadius;
      st.firstShape = static_cast<int>(firstShape);
      st.shapeCount = static_cast<int>(b.shapes.size());
      firstShape += b.shapes.size();
      states.push_back(st);
    }
    m_backend->SetBodyStates(states);
  }
  if (Status s = m_backend->Step(dt, physics, &red, m_totals.stageSeconds.data(), hook); !s) return s;
  if (!m_bodies.empty()) {
    m_backend->BodyLoads(&m_bodyLoads);
    for (size_t k = 0; k < m_bodies.size(); ++k) {
      m_bodies[k].pose = RigidPose{states[k].endPosition, states[k].endOrientation};
      m_bodies[k].velocity = states[k].velocity;
      m_bodies[k].angular = states[k].angular;
    }
  }

  if (red.nonFinite > 0) {
    // Without --validate nothing else would notice: the step's maxima drop NaN, and a NaN particle
    // sits in the grid's last cell with no neighbours, exported and saved as NaN.
    return Status::Error(Format("%d fluid particles became non-finite (NaN or infinite position, velocity, acceleration "
                                "or density) in the step from t = %.6g s: the simulation has become unstable; rerun "
                                "with --validate to find the stage and particle, and lower solver.fixed_dt or raise "
                                "solver.stiffness",
                                red.nonFinite, m_last.time));
  }
  m_last.time += dt;
  m_last.dt = dt;
  m_last.maxSpeed = std::sqrt(red.maxSpeed2);
  m_maxAccel = std::sqrt(red.maxAccel2);
  const int n = FluidCount();
  m_last.meanDensityError = n > 0 ? static_cast<float>(red.sumCompression / n) : 0.0f;
  m_last.maxDensityError = red.maxDensityError;
  m_last.clamped = red.clamped;
  m_last.activeFraction = n > 0 ? static_cast<float>(red.computed) / static_cast<float>(n) : 1.0f;
  m_totals.steps += 1;
  m_totals.clampedEvents += red.clamped;
  for (int k = 0; k < kClampSites; ++k) m_totals.clampedAt[k] += red.clampedAt[k];
  m_totals.particleSteps += n;
  WarnIfWallsLeak();
  m_last.pushedOut = red.pushed;
  m_totals.pushedOutEvents += red.pushed;
  m_last.densityIterations = red.densityIterations;
  m_last.divergenceIterations = red.divergenceIterations;
  m_last.solverDensityError = red.densityError;
  m_last.solverDivergenceError = red.divergenceError;
  m_totals.densityIterations += red.densityIterations;
  m_totals.divergenceIterations += red.divergenceIterations;
  if (physics.dfsph && red.densityIterations >= physics.maxIterations && red.densityError > physics.densityTolerance) {
    // The solve stopped short: the water is more compressed than asked this step. Named with the error
    // reached, at most once per simulated second (a hard impact hits the cap for many steps in a row).
    ++m_totals.iterationCapSteps;
    if (m_iterationWarnTime < 0.0 || m_last.time >= m_iterationWarnTime + 1.0) {
      m_iterationWarnTime = m_last.time;
      SPHXR_LOG_WARN("dfsph: the density solve reached max_iterations = %d at t = %.4g s with a mean compression of "
                     "%.3g %% (density_tolerance %g %%; %lld such steps so far): raise solver.max_iterations or lower "
                     "solver.cfl",
                     physics.maxIterations, m_last.time, 100.0 * red.densityError, 100.0 * physics.densityTolerance,
                     static_cast<long long>(m_totals.iterationCapSteps));
    }
  }
  m_totals.stepSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  return Status::Ok();
}

void Solver::Download(HostFluid* out) const { m_backend->Download(out); }
void Solver::DownloadBoundary(HostBoundary* out) const { m_backend->DownloadBoundary(out); }

Status Solver::CheckFluidSizes(const HostFluid& fluid, const char* who) const {
  if (static_cast<int>(fluid.size()) != FluidCount()) {
    return Status::Error(Format("%s: %zu particles given, the solver has %d", who, fluid.size(), FluidCount()));
  }
#define SPHXR_CHECK_SIZE(type, name)                                                  \
  if (fluid.name.size() != fluid.size())                                              \
    return Status::Error(std::string(who) + ": field '" #name "' has a different size than position");
  SPHXR_FLUID_FIELDS(SPHXR_CHECK_SIZE)
#undef SPHXR_CHECK_SIZE
  return Status::Ok();
}

Status Solver::Upload(const HostFluid& fluid) {
  if (Status s = CheckFluidSizes(fluid, "Upload"); !s) return s;
  m_backend->Upload(fluid);
  return Status::Ok();
}

void Solver::HoldBody(BodyMotion* b, const RigidPose& pose, double time) {
  b->pose = b->from = b->to = pose;
  b->fromTime = b->toTime = time;
  b->velocity = b->angular = Vec3{};
}

SolverClock Solver::Clock() const {
  SolverClock c;
  c.time = m_last.time;
  c.lastMaxSpeed = m_last.maxSpeed;
  c.lastMaxAccel = m_maxAccel;
  c.steps = m_stepBase + m_totals.steps;
  return c;
}

Status Solver::Restore(const HostFluid& fluid, const SolverClock& clock) {
  if (m_totals.steps != 0) return Status::Error("restore: only before the first step (it replaces the start)");
  // A clock past 1e9 s (32 years) is damage, not a run: there a step of ~1e-4 s no longer moves a double
  // clock, and frame numbers computed from it overflow (a flipped exponent bit hung the headless runner).
  if (!std::isfinite(clock.time) || clock.time < 0.0 || clock.time > 1e9 || !std::isfinite(clock.lastMaxSpeed) ||
      clock.lastMaxSpeed < 0.0f || !std::isfinite(clock.lastMaxAccel) || clock.lastMaxAccel < 0.0f || clock.steps < 0) {
    return Status::Error(Format("restore: the clock (t = %g s, last max speed %g m/s, last max |a| %g m/s^2, %lld "
                                "steps) must be finite, not negative, and t at most 1e9 s",
                                clock.time, clock.lastMaxSpeed, clock.lastMaxAccel, static_cast<long long>(clock.steps)));
  }
  if (Status s = CheckFluidSizes(fluid, "restore"); !s) return s;
  for (size_t i = 0; i < fluid.size(); ++i) {
    // With reuse, a particle restored idle uses its saved density, pressure and pressure term in its
    // neighbours' first steps (they divide by its density): all must be sound.
    if (!Finite(Xyz(fluid.position[i])) || !Finite(Xyz(fluid.velocity[i])) || !Finite(Xyz(fluid.acceleration[i])) ||
        !(fluid.density[i] > 0.0f) || !std::isfinite(fluid.density[i]) || !std::isfinite(fluid.pressure[i]) ||
        !std::isfinite(fluid.pressureTerm[i])) {
      return Status::Error(Format("restore: particle %zu (id %u) has a non-finite position, velocity, acceleration, "
                                  "pressure or pressure term, or a density that is not a positive number",
                                  i, fluid.id[i]));
    }
  }
  // Idle counts saved under other reuse parameters (or with reuse on, now off) that this run's IDLE does
  // not allow start active, so that no particle reuses longer than IDLE steps.
  const int32_t maxIdle = m_scene.reuse.enabled ? m_scene.reuse.idle : -1;
  auto allowed = [maxIdle](int32_t ic) { return ic <= maxIdle && ic >= -2 - maxIdle; };
  if (std::all_of(fluid.idle.begin(), fluid.idle.end(), allowed)) {
    m_backend->Upload(fluid);
  } else {
    HostFluid clamped = fluid;
    for (int32_t& ic : clamped.idle) {
      if (!allowed(ic)) ic = -1;
    }
    m_backend->Upload(clamped);
  }
  m_last = StepInfo{};
  m_last.time = clock.time;
  m_last.maxSpeed = clock.lastMaxSpeed;
  m_maxAccel = clock.lastMaxAccel;
  m_totals = Totals{};
  m_stepBase = clock.steps;
  for (BodyMotion& b : m_bodies) HoldBody(&b, b.pose, clock.time);  // where it is, at rest, on the restored clock
  return Status::Ok();
}

Status Solver::Settle(double seconds, SettleReport* report, const SettleProgress& progress) {
  if (!(seconds > 0.0) || !std::isfinite(seconds)) {
    return Status::Error("settle time " + std::to_string(seconds) + " s: must be a positive number of seconds");
  }
  if (m_totals.steps != 0) return Status::Error("settle: only before the first step (it replaces the start)");
  const auto begin = std::chrono::steady_clock::now();
  const ReuseParams reuse = m_scene.reuse;
  if (reuse.enabled) {  // every particle computes while settling
    ReuseParams off = reuse;
    off.enabled = false;
    if (Status s = SetReuse(off); !s) return s;
  }
  // A failed settle still gives the scene its reuse back (the caller may go on, or save).
  struct RestoreReuse {
    Solver* solver;
    ReuseParams reuse;
    ~RestoreReuse() {
      if (reuse.enabled && !solver->m_scene.reuse.enabled) (void)solver->SetReuse(reuse);  // validated before
    }
  } restoreReuse{this, reuse};
  SettleReport r;
  m_leakWarned = true;  // the settle's steps are not the run's: it clamps what it relaxes
  double alpha = 0.1;
  int downhill = 0;
  while (m_last.time < seconds) {
    if (Status s = Step(); !s) return s;
    ++r.steps;
    // FIRE (Bitzek et al. 2006) with the solver's CFL step as its step: mix the velocities toward the
    // forces while they do work, stop everything when they do not.
    const FireSums sums = m_backend->FireReduce();
    r.maxAccel = m_maxAccel;  // this step's largest |a|, from its StepReduction
    if (!std::isfinite(sums.power) || !std::isfinite(sums.accel2)) {
      return Status::Error(Format("settle: the state became non-finite at step %lld (t = %.4g s); rerun with --validate "
                                  "to find the stage and particle",
                                  static_cast<long long>(r.steps), m_last.time));
    }
    if (sums.power > 0.0) {
      const double mix = alpha * std::sqrt(sums.speed2 / std::max(sums.accel2, 1e-30));
      m_backend->FireMix(static_cast<float>(1.0 - alpha), static_cast<float>(mix));
      if (++downhill > 5) alpha *= 0.99;
    } else {
      m_backend->FireMix(0.0f, 0.0f);
      alpha = 0.1;
      downhill = 0;
    }
    if (progress && !progress(std::min(m_last.time, seconds))) {
      r.stopped = true;
      break;
    }
  }
  m_backend->FireMix(0.0f, 0.0f);
  r.time = m_last.time;
  for (BodyMotion& b : m_bodies) HoldBody(&b, b.pose, 0.0);  // where it is, at rest, on the restarted clock
  m_last = StepInfo{};
  m_totals = Totals{};
  m_leakWarned = false;
  m_maxAccel = 0.0f;
  if (reuse.enabled) {
    if (Status s = SetReuse(reuse); !s) return s;
  }
  r.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  if (report) *report = r;
  return Status::Ok();
}

Status Solver::SetReuse(const ReuseParams& reuse) {
  if (Status s = ValidateReuse(reuse); !s) return s;
  m_scene.reuse = reuse;
  WarnAboutReuse(reuse);
  HostFluid fluid;
  m_backend->Download(&fluid);
  std::fill(fluid.idle.begin(), fluid.idle.end(), -1);
  m_backend->Upload(fluid);
  return Status::Ok();
}

void Solver::InitBodies(const Physics& physics) {
  // Boundary particles of every body with Akinci et al.'s (2012, eq. 4) volume V_b = 1 / sum_k W_bk over
  // the body's own particles (a rigid body's sampling never changes, so once), Psi_b = gamma rho0 V_b
  // with the one-sheet flat-wall correction gamma (sampling.h).
  const float dx = m_scene.params.spacing;
  const float psiScale = WallDensityCorrection(physics.kernel, dx, 1) * physics.restDensity;
  std::vector<Vec4> local;
  std::vector<uint32_t> bodyOf;
  std::vector<float> alpha;
  std::vector<ShapePrimitive> shapes;
  for (size_t k = 0; k < m_scene.bodies.size(); ++k) {
    const RigidBodySetup& setup = m_scene.bodies[k];
    const std::vector<Vec3>& pts = setup.points;
    const float a = setup.viscosity >= 0.0f ? setup.viscosity : m_scene.params.boundaryViscosity;
    float radius = 0.0f;
    std::vector<Vec4> cloud(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) cloud[i] = MakeVec4(pts[i]);
    Vec3 lo, hi;
    BoundingBox({&cloud}, &lo, &hi);
    const HostGrid near(cloud, lo, hi, physics.kernel.H);  // O(n) sums; the points are bounded by the tank
    for (size_t i = 0; i < pts.size(); ++i) {
      float sum = 0.0f;
      near.ForEachNear(pts[i], [&](uint32_t j) {
        const Vec3 d = pts[i] - pts[j];
        const float r2 = Dot(d, d);
        if (r2 < physics.kernel.H2) sum += physics.kernel.W(std::sqrt(r2));
      });
      local.push_back(MakeVec4(pts[i], psiScale / sum));
      bodyOf.push_back(static_cast<uint32_t>(k));
      alpha.push_back(a);
      radius = std::max(radius, Length(pts[i]));
    }
    for (const ShapePrimitive& p : setup.shapes) {
      const bool box = p.kind == ShapePrimitive::Kind::kBox;
      radius = std::max(radius, box ? Length(p.a) + Length(p.b) : std::max(Length(p.a), Length(p.b)) + p.radius);
      shapes.push_back(p);
    }
    BodyMotion m;
    m.pose = RigidPose{setup.pose.position, Normalized(setup.pose.orientation)};
    m.from = m.to = m.pose;
    m.boundRadius = radius;
    m.shapes = setup.shapes;
    m_bodies.push_back(m);
  }
  m_bodyLoads.assign(m_bodies.size(), BodyLoad{});
  m_backend->InitBodies(local, bodyOf, alpha, shapes);
}

RigidPose Solver::BodyPoseAt(const BodyMotion& body, double time) const {
  if (time >= body.toTime || body.toTime <= body.fromTime) return body.to;
  const float u = static_cast<float>(std::max(0.0, (time - body.fromTime) / (body.toTime - body.fromTime)));
  return RigidPose{body.from.position + (body.to.position - body.from.position) * u,
                   Slerp(body.from.orientation, body.to.orientation, u)};
}

float Solver::MaxBodySpeed() const {
  float speed = 0.0f;
  for (const BodyMotion& b : m_bodies) {
    if (m_last.time >= b.toTime || !(b.toTime > b.fromTime)) continue;  // held (BodyPoseAt: at `to`)
    const float span = static_cast<float>(b.toTime - b.fromTime);
    const float linear = Length(b.to.position - b.from.position) / span;
    const float angular = Length(RotationVector(Mul(b.to.orientation, Conjugate(b.from.orientation)))) / span;
    speed = std::max(speed, linear + angular * b.boundRadius);
  }
  return speed;
}

BodyMotionState Solver::BodyMotionOf(int body) const {
  SPHXR_ASSERT(body >= 0 && body < BodyCount());
  return m_bodies[body];
}

Status Solver::SetBodyMotion(int body, const BodyMotionState& m) {
  if (body < 0 || body >= BodyCount()) return Status::Error(Format("SetBodyMotion: no body %d (%d bodies)", body, BodyCount()));
  if (m_totals.steps != 0) return Status::Error("SetBodyMotion: only before the first step (a restart)");
  const bool finite = Finite(m.pose.position) && Finite(m.pose.orientation) && Finite(m.from.position) &&
                      Finite(m.from.orientation) && Finite(m.to.position) && Finite(m.to.orientation) &&
                      std::isfinite(m.fromTime) && std::isfinite(m.toTime) && Finite(m.velocity) && Finite(m.angular);
  if (!finite) return Status::Error(Format("SetBodyMotion: non-finite motion for body %d", body));
  // Orientations are unit quaternions up to rounding (a body's particles are placed by them): one far
  // from unit length is damage, one a little off is normalised. A segment must not end before it begins.
  auto unitish = [](Quat q) {
    const float n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
    return n2 > 0.25f && n2 < 4.0f;
  };
  if (!unitish(m.pose.orientation) || !unitish(m.from.orientation) || !unitish(m.to.orientation) ||
      m.toTime < m.fromTime) {
    return Status::Error(Format("SetBodyMotion: body %d has an orientation far from unit length, or a motion that ends "
                                "(t = %g s) before it begins (t = %g s)",
                                body, m.toTime, m.fromTime));
  }
  // (Only those visibly off: the solver's own, saved, must come back bit for bit for a continued run.)
  BodyMotionState unit = m;
  for (RigidPose* p : {&unit.pose, &unit.from, &unit.to}) {
    const Quat q = p->orientation;
    if (std::abs(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z - 1.0f) > 1e-4f) p->orientation = Normalized(q);
  }
  static_cast<BodyMotionState&>(m_bodies[body]) = unit;
  return Status::Ok();
}

Status Solver::SetBodyTarget(int body, const RigidPose& target, double targetTime) {
  if (body < 0 || body >= BodyCount()) return Status::Error(Format("SetBodyTarget: no body %d (%d bodies)", body, BodyCount()));
  if (!Finite(target.position) || !Finite(target.orientation) || !std::isfinite(targetTime)) {
    return Status::Error(Format("SetBodyTarget: non-finite target for body %d", body));
  }
  BodyMotion& b = m_bodies[body];
  const RigidPose to{target.position, Normalized(target.orientation)};
  if (targetTime <= m_last.time) {  // relocate now, at rest
    HoldBody(&b, to, m_last.time);
    return Status::Ok();
  }
  b.from = b.pose;
  b.fromTime = m_last.time;
  b.to = to;
  b.toTime = targetTime;
  return Status::Ok();
}

void Solver::DownloadBodies(std::vector<Vec4>* position, std::vector<Vec4>* velocity) const {
  if (m_bodies.empty()) {
    position->clear();
    velocity->clear();
    return;
  }
  m_backend->DownloadBodies(position, velocity);
}

float Solver::BodyDistance(int body, Vec3 point) const {
  SPHXR_ASSERT(body >= 0 && body < BodyCount());
  const BodyMotion& b = m_bodies[body];
  const Vec3 p = Rotate(Conjugate(b.pose.orientation), point - b.pose.position);
  Vec3 n;
  return UnionDistance(b.shapes.data(), static_cast<int>(b.shapes.size()), p, &n);
}

Solver::GridInfo Solver::Grid() const {
  const GridShape g = MakeGridShape(m_scene);
  return GridInfo{g.origin, g.cellSize, {g.nx, g.ny, g.nz}};
}

}  // namespace sphxr::sim
