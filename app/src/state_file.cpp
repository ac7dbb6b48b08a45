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

#include "state_check.h"
#include "state_format.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver_table.h"

namespace sphxr::app {
namespace {

using state_format::kByteOrder;
using state_format::kMagic;
using state_format::kOldestVersion;
using state_format::kVersion;
using state_format::Reader;
using state_format::Writer;

// A paddle's restart state is used as it is (nothing downstream checks it, unlike a body's motion, which
// Solver::SetBodyMotion does): a NaN here would become the paddle's target pose, or the controller's
// buzz amplitude.
bool Sound(const interaction::PaddleRestart& p) {
  return Finite(p.state.commanded.position) && Finite(p.state.commanded.orientation) && Finite(p.state.force) &&
         Finite(p.state.torque) && Finite(p.state.rawForce) &&
         p.state.haptic >= 0.0f && p.state.haptic <= 1.0f && p.state.teleports >= 0 && std::isfinite(p.lostSince) &&
         std::isfinite(p.lastFrame);
}

}  // namespace

namespace {

// The file is written beside its place and renamed over it, which would replace whatever is there: a
// device or a pipe (--save-state /dev/null, as root, would replace the system's /dev/null) is refused,
// and a symbolic link is followed, so the link stays and its target gets the state.
Status PlaceOfStateFile(const std::string& path, std::string* target) {
  std::error_code linkError;
  *target = path;
  if (std::filesystem::is_symlink(path, linkError)) {
    const std::filesystem::path resolved = std::filesystem::canonical(path, linkError);
    if (!linkError) *target = resolved.string();
  }
  std::error_code ignored;
  const auto st = std::filesystem::status(*target, ignored);
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
    return Status::Error(path + ": not a regular file (a directory, device or pipe): a state file needs a file of its own");
  }
  return Status::Ok();
}

// The header, the clock, the counts, the scene's name and the method (the file's first part).
void WriteHead(Writer& w, const sim::Solver& solver, const std::string& sceneName, int64_t stepsBefore) {
  const sim::SolverClock clock = solver.Clock();
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
}

// The bodies' motion and the paddles' restart states, then the paddle clock.
void WriteBodies(Writer& w, const sim::Solver& solver, const interaction::PaddleSystem* paddles, double paddleClock) {
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
}

// Every field of the one field list, by name and element size, then the diffuse particles.
void WriteParticles(Writer& w, const sim::Solver& solver) {
  sim::HostFluid fluid;
  solver.Download(&fluid);
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
}

// `tmp` on the disk, then renamed over `target`: a crash after the rename cannot leave it empty.
Status SyncAndReplace(const std::string& path, const std::string& tmp, const std::string& target) {
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

}  // namespace

Status WriteStateFile(const std::string& path, const sim::Solver& solver, const std::string& sceneName,
                      const interaction::PaddleSystem* paddles, double paddleClock, int64_t stepsBefore) {
  std::string target;
  if (Status s = PlaceOfStateFile(path, &target); !s) return s;
  const std::string tmp = target + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return Status::Error(path + ": cannot open " + tmp + " for writing: " + std::strerror(errno));
    Writer w(&out);
    WriteHead(w, solver, sceneName, stepsBefore);
    WriteBodies(w, solver, paddles, paddleClock);
    WriteParticles(w, solver);
    out.close();  // errors reported only at close (quota, network filesystems) count too
    if (out.fail()) {
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      return Status::Error(path + ": write failed (disk full?); an earlier file there is unchanged");
    }
  }
  return SyncAndReplace(path, tmp, target);
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

namespace {

Status Truncated(const std::string& path, const Reader& r) {
  return Status::Error(Format("%s: truncated at byte %zu: not a whole state file", path.c_str(), r.At()));
}

// The head: byte order, version, clock, step count, spacing, counts, the scene's name and the method.
Status ParseHead(Reader& r, const std::string& path, uint32_t* version, StateFile* out) {
  char magic[sizeof(kMagic)];
  r.Bytes(magic, sizeof(magic));  // checked by the caller
  uint32_t order = 0;
  if (!r.Get(&order) || !r.Get(version)) return Truncated(path, r);
  if (order != kByteOrder) return Status::Error(path + ": written on a machine of the other byte order");
  if (*version < kOldestVersion || *version > kVersion) {
    return Status::Error(Format("%s: state file version %u; this build reads versions %u to %u", path.c_str(), *version,
                                kOldestVersion, kVersion));
  }
  int32_t fluid = 0, boundary = 0;
  if (!r.Get(&out->clock.time) || !r.Get(&out->clock.lastMaxSpeed) || !r.Get(&out->clock.lastMaxAccel)) return Truncated(path, r);
  out->step = -1;  // version 1 has no step count
  if (*version >= 2) {
    if (!r.Get(&out->step)) return Truncated(path, r);
    // (Below -1, or past 1e15 steps, a thousand years of steps at 30 us: damage, e.g. a flipped high bit.)
    if (out->step < -1 || out->step > 1000000000000000LL) {
      return Status::Error(Format("%s: step count %lld: the file is damaged", path.c_str(), static_cast<long long>(out->step)));
    }
  }
  // The impulse hold's schedule continues in step with the saved run (unknown: from 0, a one-off shift).
  out->clock.steps = out->step < 0 ? 0 : out->step;
  if (!r.Get(&out->spacing) || !r.Get(&fluid) || !r.Get(&boundary) || !r.String(&out->scene, 4096)) return Truncated(path, r);
  if (fluid < 0 || boundary < 0) return Status::Error(path + ": negative particle counts: the file is damaged");
  out->fluidCount = fluid;
  out->boundaryCount = boundary;
  out->method = sim::SolverMethod::kWcsph;  // versions 1 and 2: the only method there was
  if (*version >= 3) {
    std::string method;
    if (!r.String(&method, 64)) return Truncated(path, r);
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
  return Status::Ok();
}

// The bodies' motion, the paddles' restart states and the paddle clock.
Status ParseBodies(Reader& r, const std::string& path, StateFile* out) {
  uint32_t bodies = 0;
  if (!r.Get(&bodies)) return Truncated(path, r);
  if (bodies > 1024) return Status::Error(Format("%s: %u bodies: the file is damaged", path.c_str(), bodies));
  // A body's motion is checked where it is used (Solver::SetBodyMotion, SetBodyTarget refuse non-finite
  // values), as the fluid's is (Solver::Restore).
  for (uint32_t k = 0; k < bodies; ++k) {
    sim::BodyMotionState m;
    if (!r.Get(&m.pose) || !r.Get(&m.from) || !r.Get(&m.to) || !r.Get(&m.fromTime) || !r.Get(&m.toTime) ||
        !r.Get(&m.velocity) || !r.Get(&m.angular)) {
      return Truncated(path, r);
    }
    out->bodies.push_back(m);
  }
  uint32_t paddleCount = 0;
  if (!r.Get(&paddleCount)) return Truncated(path, r);
  if (paddleCount > bodies) return Status::Error(Format("%s: %u paddles for %u bodies: the file is damaged", path.c_str(), paddleCount, bodies));
  for (uint32_t k = 0; k < paddleCount; ++k) {
    interaction::PaddleRestart p;
    int32_t mode = 0;
    uint8_t lost = 0;
    if (!r.Get(&mode) || !r.Get(&p.state.commanded.position) || !r.Get(&p.state.commanded.orientation) ||
        !r.Get(&p.state.force) || !r.Get(&p.state.torque) || !r.Get(&p.state.rawForce) || !r.Get(&p.state.haptic) ||
        !r.Get(&p.state.teleports) || !r.Get(&lost) || !r.Get(&p.lostSince) || !r.Get(&p.lastFrame)) {
      return Truncated(path, r);
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
  if (!r.Get(&out->paddleClock)) return Truncated(path, r);
  if (!std::isfinite(out->paddleClock)) return Status::Error(path + ": non-finite paddle clock: the file is damaged");
  return Status::Ok();
}

// The fields, each by name and element size: every field of this build, once, and no other.
Status ParseFields(Reader& r, const std::string& path, StateFile* out) {
  const int32_t fluid = out->fluidCount;
  uint32_t fields = 0;
  if (!r.Get(&fields)) return Truncated(path, r);
  // The fields' bytes must be there before anything is allocated (a damaged count must not ask for
  // gigabytes).
  uint64_t perParticle = 0;
#define SPHXR_FIELD_BYTES(type, name) perParticle += sizeof(type);
  SPHXR_FLUID_FIELDS(SPHXR_FIELD_BYTES)
#undef SPHXR_FIELD_BYTES
  if (static_cast<uint64_t>(fluid) * perParticle > r.Left()) return Truncated(path, r);
  out->fluid.resize(static_cast<size_t>(fluid));
  std::vector<std::string> seen;
  for (uint32_t f = 0; f < fields; ++f) {
    std::string name;
    uint32_t element = 0;
    if (!r.String(&name, 256) || !r.Get(&element)) return Truncated(path, r);
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
    if (!r.Bytes(out->fluid.fieldName.data(), static_cast<size_t>(fluid) * sizeof(type))) return Truncated(path, r);   \
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
  return Status::Ok();
}

Status ParseDiffuse(Reader& r, const std::string& path, StateFile* out) {
  uint32_t diffuse = 0;
  if (!r.Get(&diffuse)) return Truncated(path, r);
  if (static_cast<uint64_t>(diffuse) * 2 * sizeof(sim::Vec4) > r.Left()) return Truncated(path, r);
  out->diffuse.resize(static_cast<int>(diffuse));
  if (!r.Bytes(out->diffuse.position.data(), diffuse * sizeof(sim::Vec4)) ||
      !r.Bytes(out->diffuse.velocity.data(), diffuse * sizeof(sim::Vec4))) {
    return Truncated(path, r);
  }
  return Status::Ok();
}

}  // namespace

Status ParseStateFile(std::vector<char> data, const std::string& path, StateFile* out) {
  *out = StateFile{};
  out->path = path;
  if (data.size() < sizeof(kMagic) || std::memcmp(data.data(), kMagic, sizeof(kMagic)) != 0) {
    return Status::Error(path + ": not an sphxr state file (written by sphxr --save-state)");
  }
  Reader r(std::move(data));
  uint32_t version = 0;
  if (Status s = ParseHead(r, path, &version, out); !s) return s;
  if (Status s = ParseBodies(r, path, out); !s) return s;
  if (Status s = ParseFields(r, path, out); !s) return s;
  if (version >= 4) {  // (older files have none: the run starts without)
    if (Status s = ParseDiffuse(r, path, out); !s) return s;
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
