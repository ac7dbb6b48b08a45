#include "sphxr/app/state_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {
namespace {

constexpr char kMagic[8] = {'S', 'P', 'H', 'X', 'R', 'S', 'T', '1'};
constexpr uint32_t kByteOrder = 0x01020304u;
// 2: the step count after the clock; 3: the solver method after the scene name; 4: the diffuse particles
// after the fields
constexpr uint32_t kVersion = 4;
constexpr uint32_t kOldestVersion = 1;
static_assert(sizeof(sim::Vec3) == 12 && sizeof(sim::Quat) == 16 && sizeof(sim::Pose) == 28,
              "state files write these structs as their bytes: they must have no padding");

class Writer {
 public:
  explicit Writer(std::ofstream* out) : m_out(out) {}
  void Bytes(const void* p, size_t n) {
    if (n > 0) m_out->write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
  }
  template <class T>
  void Put(const T& v) {
    Bytes(&v, sizeof(T));
  }
  void String(const std::string& s) {
    Put(static_cast<uint32_t>(s.size()));
    Bytes(s.data(), s.size());
  }

 private:
  std::ofstream* m_out;
};

// A paddle's restart state is used as it is (nothing downstream checks it, unlike a body's motion, which
// Solver::SetBodyMotion does): a NaN here would become the paddle's target pose, or the controller's
// buzz amplitude.
bool Sound(const interaction::PaddleRestart& p) {
  return Finite(p.state.commanded.position) && Finite(p.state.commanded.orientation) && Finite(p.state.force) &&
         Finite(p.state.torque) && Finite(p.state.rawForce) &&
         p.state.haptic >= 0.0f && p.state.haptic <= 1.0f && p.state.teleports >= 0 && std::isfinite(p.lostSince) &&
         std::isfinite(p.lastFrame);
}

class Reader {
 public:
  explicit Reader(std::vector<char> data) : m_data(std::move(data)) {}
  bool Bytes(void* p, size_t n) {
    if (n == 0) return true;  // (no memcpy with an empty field's null pointer)
    if (n > m_data.size() - m_at) return false;
    std::memcpy(p, m_data.data() + m_at, n);
    m_at += n;
    return true;
  }
  template <class T>
  bool Get(T* v) {
    return Bytes(v, sizeof(T));
  }
  bool String(std::string* s, uint32_t limit) {
    uint32_t n = 0;
    if (!Get(&n) || n > limit || n > m_data.size() - m_at) return false;
    s->assign(m_data.data() + m_at, n);
    m_at += n;
    return true;
  }
  size_t At() const { return m_at; }
  size_t Left() const { return m_data.size() - m_at; }

 private:
  std::vector<char> m_data;
  size_t m_at = 0;
};

// A state file is checked as a scene is (sim's ValidateScene): finite is not enough. Every particle
// outside the tank was clamped back in (a density error of 127,229 %), a body at y = 1e9 m moved at
// 3.5e9 m/s in its first step, and particles with one id are not one particle's history.
constexpr double kMaxFluidSpeed = 1000.0;  // m/s: a scene's fluid block may start at most this fast

// The smallest step a state may ask for: the smallest solver.max_dt a scene may set.
constexpr double kMinResolvedStep = 1e-7;  // s

Status CheckAgainstScene(const StateFile& state, const sim::SceneSetup& scene) {
  // The clock's last maxima set the first step (its CFL and force conditions): a saved maximum speed of
  // 1e30 m/s or |a| of 3.4e38 m/s^2 was restored, and the run then stopped with "the time step
  // collapsed to 4e-33 s", naming neither the file nor the value.
  const double speed = state.clock.lastMaxSpeed, accel = state.clock.lastMaxAccel;
  if (!(speed <= kMaxFluidSpeed)) {
    return Status::Error(Format("the clock's last maximum speed %g m/s is beyond the %g m/s a fluid may have: damaged",
                                speed, kMaxFluidSpeed));
  }
  // WCSPH's force condition, dt = 0.25 sqrt(h / a), with the state's smoothing length h.
  const double h = 0.5 * scene.params.spacing * scene.params.supportFactor;
  const double maxAccel = h * std::pow(0.25 / kMinResolvedStep, 2.0);
  if (!(accel <= maxAccel)) {
    return Status::Error(Format("the clock's last maximum acceleration %g m/s^2 asks for a step below %g s (at most "
                                "%.3g m/s^2 at spacing %g m): damaged",
                                accel, kMinResolvedStep, maxAccel, scene.params.spacing));
  }
  const sim::HostFluid& f = state.fluid;
  const float slack = scene.params.spacing;  // the domain clamp keeps particles inside the walls
  const sim::Aabb& t = scene.tank;
  for (size_t i = 0; i < f.size(); ++i) {
    const sim::Vec4 p = f.position[i];
    const float top = t.max.y + slack;  // (an open tank's domain ends at its rim too)
    if (!(p.x >= t.min.x - slack && p.x <= t.max.x + slack && p.y >= t.min.y - slack && p.y <= top &&
          p.z >= t.min.z - slack && p.z <= t.max.z + slack)) {
      return Status::Error(Format("particle %zu (id %u) at [%g %g %g] is outside the tank [%g %g %g] to [%g %g %g]: "
                                  "saved from another scene, or damaged",
                                  i, f.id[i], p.x, p.y, p.z, t.min.x, t.min.y, t.min.z, t.max.x, t.max.y, t.max.z));
    }
    const sim::Vec4 v = f.velocity[i];
    const double speed = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
    if (!(speed <= kMaxFluidSpeed)) {
      return Status::Error(Format("particle %zu (id %u) moves at %g m/s; at most %g m/s is supported: damaged", i,
                                  f.id[i], speed, kMaxFluidSpeed));
    }
  }
  std::vector<uint32_t> ids(f.id);
  std::sort(ids.begin(), ids.end());
  if (const auto twin = std::adjacent_find(ids.begin(), ids.end()); twin != ids.end()) {
    return Status::Error(Format("particle id %u appears twice: damaged", *twin));
  }
  // Bodies (paddles) may be withdrawn above the water, not far away: within the tank's diagonal of it.
  const double reach = Length(t.max - t.min);
  auto near = [&](const sim::Vec3& x) {
    const double dx = std::max({double(t.min.x) - x.x, 0.0, double(x.x) - t.max.x});
    const double dy = std::max({double(t.min.y) - x.y, 0.0, double(x.y) - t.max.y});
    const double dz = std::max({double(t.min.z) - x.z, 0.0, double(x.z) - t.max.z});
    return std::sqrt(dx * dx + dy * dy + dz * dz) <= reach;
  };
  for (size_t k = 0; k < state.bodies.size(); ++k) {
    const sim::BodyMotionState& m = state.bodies[k];
    for (const sim::Pose* pose : {&m.pose, &m.from, &m.to}) {
      if (!Finite(pose->position) || !near(pose->position)) {
        return Status::Error(Format("body %zu's pose [%g %g %g] is more than the tank's diagonal (%g m) from the tank: "
                                    "damaged",
                                    k, pose->position.x, pose->position.y, pose->position.z, reach));
      }
    }
    const double speed = Finite(m.velocity) ? double(Length(m.velocity)) : HUGE_VAL;
    if (!(speed <= kMaxFluidSpeed)) {
      return Status::Error(Format("body %zu moves at %g m/s; at most %g m/s is supported: damaged", k, speed, kMaxFluidSpeed));
    }
  }
  for (size_t k = 0; k < state.paddles.size(); ++k) {
    if (!near(state.paddles[k].state.commanded.position)) {
      return Status::Error(Format("paddle %zu's commanded pose is more than the tank's diagonal from the tank: damaged", k));
    }
  }
  return Status::Ok();
}

}  // namespace

Status WriteStateFile(const std::string& path, const sim::Solver& solver, const std::string& sceneName,
                      const interaction::PaddleSystem* paddles, double paddleClock, int64_t stepsBefore) {
  // The file is written beside its place and renamed over it, which would replace whatever is there: a
  // device or a pipe (--save-state /dev/null, as root, replaced the system's /dev/null) is refused, and
  // a symbolic link is followed, so the link stays and its target gets the state.
  std::error_code linkError;
  std::string target = path;
  if (std::filesystem::is_symlink(path, linkError)) {
    const std::filesystem::path resolved = std::filesystem::canonical(path, linkError);
    if (!linkError) target = resolved.string();
  }
  {
    std::error_code ignored;
    const auto st = std::filesystem::status(target, ignored);
    if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
      return Status::Error(path + ": not a regular file (a directory, device or pipe): a state file needs a file of its own");
    }
  }
  sim::HostFluid fluid;
  solver.Download(&fluid);
  const sim::SolverClock clock = solver.Clock();
  const std::string tmp = target + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return Status::Error(path + ": cannot open " + tmp + " for writing: " + std::strerror(errno));
    Writer w(&out);
    w.Bytes(kMagic, sizeof(kMagic));
    w.Put(kByteOrder);
    w.Put(kVersion);
    w.Put(clock.time);
    w.Put(clock.lastMaxSpeed);
    w.Put(clock.lastMaxAccel);
    w.Put(static_cast<int64_t>(stepsBefore < 0 ? -1 : stepsBefore + solver.GetTotals().steps));  // -1: unknown
    w.Put(solver.Scene().params.spacing);
    w.Put(static_cast<int32_t>(solver.FluidCount()));
    w.Put(static_cast<int32_t>(solver.BoundaryCount()));
    w.String(sceneName);
    w.String(sim::SolverMethodName(solver.Method()));
    w.Put(static_cast<uint32_t>(solver.BodyCount()));
    for (int k = 0; k < solver.BodyCount(); ++k) {
      const sim::BodyMotionState m = solver.BodyMotionOf(k);
      for (const sim::Pose& p : {m.pose, m.from, m.to}) w.Put(p);
      w.Put(m.fromTime);
      w.Put(m.toTime);
      w.Put(m.velocity);
      w.Put(m.angular);
    }
    const int paddleCount = paddles ? paddles->Count() : 0;
    w.Put(static_cast<uint32_t>(paddleCount));
    for (int k = 0; k < paddleCount; ++k) {
      const interaction::PaddleRestart r = paddles->Restart(k);
      w.Put(static_cast<int32_t>(r.state.mode));
      w.Put(r.state.commanded.position);
      w.Put(r.state.commanded.orientation);
      w.Put(r.state.force);
      w.Put(r.state.torque);
      w.Put(r.state.rawForce);
      w.Put(r.state.haptic);
      w.Put(r.state.teleports);
      w.Put(static_cast<uint8_t>(r.lost ? 1 : 0));
      w.Put(r.lostSince);
      w.Put(r.lastFrame);
    }
    w.Put(paddleCount > 0 ? paddleClock : 0.0);  // only meaningful with paddles
    uint32_t fields = 0;
#define SPHXR_COUNT_FIELD(type, name) ++fields;
    SPHXR_FLUID_FIELDS(SPHXR_COUNT_FIELD)
#undef SPHXR_COUNT_FIELD
    w.Put(fields);
#define SPHXR_WRITE_FIELD(type, name)                                   \
  w.String(#name);                                                      \
  w.Put(static_cast<uint32_t>(sizeof(type)));                           \
  w.Bytes(fluid.name.data(), fluid.name.size() * sizeof(type));
    SPHXR_FLUID_FIELDS(SPHXR_WRITE_FIELD)
#undef SPHXR_WRITE_FIELD
    sim::HostDiffuse diffuse;
    solver.DownloadDiffuse(&diffuse);
    w.Put(static_cast<uint32_t>(diffuse.count));
    w.Bytes(diffuse.position.data(), diffuse.position.size() * sizeof(sim::Vec4));
    w.Bytes(diffuse.velocity.data(), diffuse.velocity.size() * sizeof(sim::Vec4));
    out.close();  // errors reported only at close (quota, network filesystems) count too
    if (out.fail()) {
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      return Status::Error(path + ": write failed (disk full?); an earlier file there is unchanged");
    }
  }
  // On the disk before it replaces an earlier file, so a crash after the rename cannot leave it empty.
  const int fd = ::open(tmp.c_str(), O_RDONLY);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  std::error_code ec;
  if (!synced) {
    std::filesystem::remove(tmp, ec);
    return Status::Error(path + ": cannot sync " + tmp + " to the disk; an earlier file there is unchanged");
  }
  std::filesystem::rename(tmp, target, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    return Status::Error(path + ": cannot move " + tmp + " into place: " + ec.message());
  }
  return Status::Ok();
}

Status ReadStateFile(const std::string& path, StateFile* out) {
  *out = StateFile{};
  out->path = path;
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) return Status::Error(path + ": cannot open: no such file");
  if (std::filesystem::is_directory(status)) return Status::Error(path + ": is a directory, not a state file");
  if (!std::filesystem::is_regular_file(status)) return Status::Error(path + ": not a regular file, not a state file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open: " + std::strerror(errno));
  // The magic first, so that a large file given by mistake is not read whole.
  char head[sizeof(kMagic)] = {};
  in.read(head, sizeof(head));
  if (in.gcount() != static_cast<std::streamsize>(sizeof(head)) || std::memcmp(head, kMagic, sizeof(kMagic)) != 0) {
    return Status::Error(path + ": not an sphxr state file (written by sphxr --save-state)");
  }
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return Status::Error(path + ": cannot read its size: " + ec.message());
  std::vector<char> data(static_cast<size_t>(size));
  std::memcpy(data.data(), head, sizeof(head));
  in.read(data.data() + sizeof(head), static_cast<std::streamsize>(size - sizeof(head)));
  if (in.gcount() != static_cast<std::streamsize>(size - sizeof(head))) {
    return Status::Error(path + ": read failed: the file changed while it was read");
  }
  return ParseStateFile(std::move(data), path, out);
}

Status ParseStateFile(std::vector<char> data, const std::string& path, StateFile* out) {
  *out = StateFile{};
  out->path = path;
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0) {
    return Status::Error(path + ": not an sphxr state file (written by sphxr --save-state)");
  }
  Reader r(std::move(data));
  auto truncated = [&]() { return Status::Error(Format("%s: truncated at byte %zu: not a whole state file", path.c_str(), r.At())); };
  char magic[sizeof(kMagic)];
  r.Bytes(magic, sizeof(magic));  // checked above
  uint32_t order = 0, version = 0;
  if (!r.Get(&order) || !r.Get(&version)) return truncated();
  if (order != kByteOrder) return Status::Error(path + ": written on a machine of the other byte order");
  if (version < kOldestVersion || version > kVersion) {
    return Status::Error(Format("%s: state file version %u; this build reads versions %u to %u", path.c_str(), version,
                                kOldestVersion, kVersion));
  }
  int32_t fluid = 0, boundary = 0;
  if (!r.Get(&out->clock.time) || !r.Get(&out->clock.lastMaxSpeed) || !r.Get(&out->clock.lastMaxAccel)) return truncated();
  out->step = -1;  // version 1 has no step count
  if (version >= 2) {
    if (!r.Get(&out->step)) return truncated();
    // (Below -1, or past 1e15 steps, a thousand years of steps at 30 us: damage, e.g. a flipped high bit.)
    if (out->step < -1 || out->step > 1000000000000000LL) {
      return Status::Error(Format("%s: step count %lld: the file is damaged", path.c_str(), static_cast<long long>(out->step)));
    }
  }
  // The impulse hold's schedule continues in step with the saved run (unknown: from 0, a one-off shift).
  out->clock.steps = out->step < 0 ? 0 : out->step;
  if (!r.Get(&out->spacing) || !r.Get(&fluid) || !r.Get(&boundary) || !r.String(&out->scene, 4096)) return truncated();
  if (fluid < 0 || boundary < 0) return Status::Error(path + ": negative particle counts: the file is damaged");
  out->method = sim::SolverMethod::kWcsph;  // versions 1 and 2: the only method there was
  if (version >= 3) {
    std::string method;
    if (!r.String(&method, 64)) return truncated();
    if (!sim::ParseSolverMethod(method, &out->method)) {
      return Status::Error(path + ": its solver method is not one of " + sim::SolverNames() +
                           ": the file is damaged or from a newer build");
    }
  }
  // The scene's name is shown in messages and the log: control characters (a damaged file, or a name
  // with terminal escapes) become '?'.
  for (char& c : out->scene) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  const sim::ParamInfo* spacing = sim::FindSolverParam("spacing");
  if (!std::isfinite(out->spacing) || out->spacing < spacing->min || out->spacing > spacing->max) {
    return Status::Error(Format("%s: spacing %g m is outside %g to %g m: the file is damaged", path.c_str(), out->spacing,
                                spacing->min, spacing->max));
  }
  uint32_t bodies = 0;
  if (!r.Get(&bodies)) return truncated();
  if (bodies > 1024) return Status::Error(Format("%s: %u bodies: the file is damaged", path.c_str(), bodies));
  // A body's motion is checked where it is used (Solver::SetBodyMotion, SetBodyTarget refuse non-finite
  // values), as the fluid's is (Solver::Restore).
  for (uint32_t k = 0; k < bodies; ++k) {
    sim::BodyMotionState m;
    if (!r.Get(&m.pose) || !r.Get(&m.from) || !r.Get(&m.to) || !r.Get(&m.fromTime) || !r.Get(&m.toTime) ||
        !r.Get(&m.velocity) || !r.Get(&m.angular)) {
      return truncated();
    }
    out->bodies.push_back(m);
  }
  uint32_t paddleCount = 0;
  if (!r.Get(&paddleCount)) return truncated();
  if (paddleCount > bodies) return Status::Error(Format("%s: %u paddles for %u bodies: the file is damaged", path.c_str(), paddleCount, bodies));
  for (uint32_t k = 0; k < paddleCount; ++k) {
    interaction::PaddleRestart p;
    int32_t mode = 0;
    uint8_t lost = 0;
    if (!r.Get(&mode) || !r.Get(&p.state.commanded.position) || !r.Get(&p.state.commanded.orientation) ||
        !r.Get(&p.state.force) || !r.Get(&p.state.torque) || !r.Get(&p.state.rawForce) || !r.Get(&p.state.haptic) ||
        !r.Get(&p.state.teleports) || !r.Get(&lost) || !r.Get(&p.lostSince) || !r.Get(&p.lastFrame)) {
      return truncated();
    }
    if (mode < 0 || mode > static_cast<int32_t>(interaction::PaddleMode::kWithdrawing)) {
      return Status::Error(Format("%s: paddle %u has mode %d: the file is damaged", path.c_str(), k, mode));
    }
    p.state.mode = static_cast<interaction::PaddleMode>(mode);
    p.lost = lost != 0;
    if (!Sound(p)) {
      return Status::Error(Format("%s: paddle %u has a non-finite pose, load or time, or a buzz outside 0..1: the file is "
                                  "damaged", path.c_str(), k));
    }
    out->paddles.push_back(p);
  }
  if (!r.Get(&out->paddleClock)) return truncated();
  if (!std::isfinite(out->paddleClock)) return Status::Error(path + ": non-finite paddle clock: the file is damaged");
  out->fluidCount = fluid;
  out->boundaryCount = boundary;
  uint32_t fields = 0;
  if (!r.Get(&fields)) return truncated();
  // The fields' bytes must be there before anything is allocated (a damaged count must not ask for
  // gigabytes).
  uint64_t perParticle = 0;
#define SPHXR_FIELD_BYTES(type, name) perParticle += sizeof(type);
  SPHXR_FLUID_FIELDS(SPHXR_FIELD_BYTES)
#undef SPHXR_FIELD_BYTES
  if (static_cast<uint64_t>(fluid) * perParticle > r.Left()) return truncated();
  out->fluid.resize(static_cast<size_t>(fluid));
  std::vector<std::string> seen;
  for (uint32_t f = 0; f < fields; ++f) {
    std::string name;
    uint32_t element = 0;
    if (!r.String(&name, 256) || !r.Get(&element)) return truncated();
    // (Named in messages: a damaged name must not put control characters or a newline on the terminal.)
    const bool identifier = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    });
    if (!identifier) return Status::Error(Format("%s: field %u has no name: the file is damaged", path.c_str(), f));
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) {
      return Status::Error(path + ": field '" + name + "' appears twice: the file is damaged");
    }
    seen.push_back(name);
    bool known = false;
#define SPHXR_READ_FIELD(type, fieldName)                                                                       \
  if (name == #fieldName) {                                                                                     \
    known = true;                                                                                               \
    if (element != sizeof(type)) {                                                                              \
      return Status::Error(Format("%s: field '%s' has %u-byte elements; this build's have %zu", path.c_str(),   \
                                  name.c_str(), element, sizeof(type)));                                        \
    }                                                                                                           \
    if (!r.Bytes(out->fluid.fieldName.data(), static_cast<size_t>(fluid) * sizeof(type))) return truncated();   \
  }
    SPHXR_FLUID_FIELDS(SPHXR_READ_FIELD)
#undef SPHXR_READ_FIELD
    if (!known) return Status::Error(path + ": field '" + name + "' is not one this build knows (saved by another version)");
  }
#define SPHXR_CHECK_SEEN(type, name)                                                                        \
  if (std::find(seen.begin(), seen.end(), #name) == seen.end()) {                                           \
    return Status::Error(path + ": field '" #name "' of this build is not in the file (saved by another version)"); \
  }
  SPHXR_FLUID_FIELDS(SPHXR_CHECK_SEEN)
#undef SPHXR_CHECK_SEEN
  if (version >= 4) {  // (older files have none: the run starts without)
    uint32_t diffuse = 0;
    if (!r.Get(&diffuse)) return truncated();
    if (static_cast<uint64_t>(diffuse) * 2 * sizeof(sim::Vec4) > r.Left()) return truncated();
    out->diffuse.resize(static_cast<int>(diffuse));
    if (!r.Bytes(out->diffuse.position.data(), diffuse * sizeof(sim::Vec4)) ||
        !r.Bytes(out->diffuse.velocity.data(), diffuse * sizeof(sim::Vec4))) {
      return truncated();
    }
  }
  if (r.Left() != 0) return Status::Error(Format("%s: %zu bytes after the last field: the file is damaged", path.c_str(), r.Left()));
  return Status::Ok();
}

bool RestorePaddles(const StateFile& state, const sim::Solver& solver, interaction::PaddleSystem* paddles,
                    double* paddleClock) {
  if (!paddles || state.paddles.empty() || static_cast<int>(state.paddles.size()) != paddles->Count() ||
      static_cast<int>(state.bodies.size()) != solver.BodyCount()) {
    return false;
  }
  for (int k = 0; k < paddles->Count(); ++k) paddles->Restore(k, state.paddles[k]);
  *paddleClock = state.paddleClock;
  return true;
}

Status ReadStartState(const std::string& path, float spacingOption, const std::string& sceneName,
                      sim::SceneSetup* setup, std::shared_ptr<const StateFile>* out) {
  out->reset();
  if (path.empty()) return Status::Ok();
  auto state = std::make_shared<StateFile>();
  if (Status s = ReadStateFile(path, state.get()); !s) return Status::Error("--load-state " + s.message());
  if (spacingOption > 0.0f && spacingOption != state->spacing) {
    return Status::Error(Format("--load-state %s: saved at spacing %g m; the command line asks for %g m, another "
                                "particle count (another --spacing)",
                                path.c_str(), state->spacing, spacingOption));
  }
  // Only the particle counts and the spacing must match (RestoreState): a renamed scene is still the
  // same scene. Another name may be another scene of the same size, though, so it is said.
  if (state->scene != sceneName) {
    SPHXR_LOG_WARN("--load-state %s was saved from scene '%s', this scene is '%s': it is used if its particle counts "
                   "and spacing match",
                   path.c_str(), ShowText(state->scene).c_str(), sceneName.c_str());
  }
  setup->params.spacing = state->spacing;
  if (state->method != setup->method) {
    SPHXR_LOG_WARN("--load-state %s was saved under solver.method %s; this run uses %s (the scene or --set): the water "
                   "continues under the other solver",
                   path.c_str(), sim::SolverMethodName(state->method), sim::SolverMethodName(setup->method));
  }
  *out = std::move(state);
  return Status::Ok();
}

Status RestoreState(const StateFile& state, sim::Solver* solver) {
  const std::string& path = state.path;
  const float spacing = solver->Scene().params.spacing;
  if (state.fluidCount != solver->FluidCount() || state.boundaryCount != solver->BoundaryCount() ||
      state.spacing != spacing) {
    return Status::Error(Format("%s: saved from '%s' with %d fluid and %d boundary particles at spacing %g m; this scene "
                                "has %d and %d at %g m (another scene, or another --spacing)",
                                path.c_str(), ShowText(state.scene).c_str(), state.fluidCount, state.boundaryCount, state.spacing,
                                solver->FluidCount(), solver->BoundaryCount(), spacing));
  }
  if (Status s = CheckAgainstScene(state, solver->Scene()); !s) return Status::Error(path + ": " + s.message());
  if (Status s = solver->Restore(state.fluid, state.clock); !s) return Status::Error(path + ": " + s.message());
  if (Status s = solver->RestoreDiffuse(state.diffuse); !s) return Status::Error(path + ": " + s.message());
  if (static_cast<int>(state.bodies.size()) == solver->BodyCount()) {  // the same bodies: their whole motion
    for (int k = 0; k < solver->BodyCount(); ++k) {
      if (Status s = solver->SetBodyMotion(k, state.bodies[k]); !s) return Status::Error(path + ": " + s.message());
    }
    return Status::Ok();
  }
  // The scene's paddles come first in every mode; the window and --xr append their hand paddles after
  // them. So the file's poses belong to the first bodies, as many as both have.
  const int common = std::min(static_cast<int>(state.bodies.size()), solver->BodyCount());
  for (int k = 0; k < common; ++k) {  // a target time not after now: relocated, at rest (poses checked on reading)
    if (Status s = solver->SetBodyTarget(k, state.bodies[k].pose, solver->Time()); !s) return Status::Error(path + ": " + s.message());
  }
  if (static_cast<int>(state.bodies.size()) < solver->BodyCount()) {
    SPHXR_LOG_INFO("%s: %zu paddle pose(s) saved for %d paddles here: the others start at their scene poses", path.c_str(),
                   state.bodies.size(), solver->BodyCount());
  } else if (static_cast<int>(state.bodies.size()) > solver->BodyCount()) {
    SPHXR_LOG_INFO("%s: %zu paddle poses saved, %d paddle(s) here: the first %d are used", path.c_str(),
                   state.bodies.size(), solver->BodyCount(), common);
  }
  return Status::Ok();
}

}  // namespace sphxr::app
