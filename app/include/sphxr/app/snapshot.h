#pragma once
// One published state of a running simulation: what every picture of it is drawn from (the desktop
// window, the headset, headless PNGs). Plain host data, copied out of the solver between steps, so a
// frame can be drawn from it on another thread while the solver goes on.
#include <cstdint>
#include <vector>

#include "sphxr/app/probe_history.h"
#include "sphxr/common/status.h"
#include "sphxr/interaction/paddle.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/solver.h"
#include "sphxr/sim/surface.h"

namespace sphxr::app {

/// A paddle as it is drawn: its solid in the body frame at the body's pose in the solver.
struct PaddlePose {
  std::vector<sim::ShapePrimitive> shapes;  // body frame
  interaction::Pose pose;                   // where the solver has the body now (world)
  int hand = -1;                            // 0 left, 1 right, -1 scripted
  interaction::PaddleMode mode = interaction::PaddleMode::kFollowing;
  sim::Vec3 force;                          // fluid on the paddle, filtered, N
  float haptic = 0.0f;                      // 0..1
};

struct SimSnapshot {
  sim::HostFluid fluid;
  /// Spray, foam and bubbles (sphxr/sim/diffuse.h), oldest first; empty when solver.diffuse is off.
  sim::HostDiffuse diffuse;
  sim::SceneSetup setup;
  sim::StepInfo last;
  int64_t steps = 0;
  double stageMs[static_cast<int>(sim::Stage::kCount)] = {};  // of the steps since the last snapshot
  double stepMs = 0.0;                                         // mean wall ms per step since the last snapshot
  double stepsPerSecond = 0.0;                                 // measured over the last half second
  double simSecondsPerWallSecond = 0.0;                        // measured over the last half second
  int fluidCount = 0, boundaryCount = 0;

  /// The water surface (HPMC, sim/include/sphxr/sim/surface.h) of this state; empty when extraction
  /// is off (particle mode) or nothing was extracted yet.
  sim::SurfaceMesh surface;
  double surfaceMs = 0.0;        // wall ms of the extraction that made `surface`
  float surfaceCellSize = 0.0f;  // m, the cell size it was extracted with
  bool surfaceFresh = false;     // extracted for this state (else the previous state's mesh, kept to save time)
  /// GPU path (SurfacePath::kInterop): the mesh was built in the solver (BuildSurface) and not copied:
  /// `surface` is empty, the mesh has `surfaceVertices` vertices and the GL thread writes it into its
  /// render::InteropMesh (SimWorker::WriteSurfaceInto). `surfaceBuild` numbers the worker's builds.
  /// `surfaceVertices` is the solver's last write report (Solver::LastSurfaceWrite): the mesh of an
  /// earlier build on the CUDA device, where the count is not read back.
  bool surfaceOnDevice = false;
  int64_t surfaceVertices = 0;
  uint64_t surfaceBuild = 0;
  int64_t SurfaceTriangles() const { return (surfaceOnDevice ? surfaceVertices : surface.VertexCount()) / 3; }

  /// Paddles (interaction::PaddleSystem) and what the hands feel: haptic amplitude 0..1 per hand
  /// (index 0 left, 1 right; PaddleSystem::HapticAmplitude).
  std::vector<PaddlePose> paddles;
  float haptic[2] = {0.0f, 0.0f};
  /// The scene's probes over the last seconds (probe_history.h), for the panels' plots.
  std::vector<ProbeTrace> probes;
};

/// The body-frame point a mouse places: the centre of the paddle's lowest primitive (the blade).
sim::Vec3 PaddleWorkingPoint(const std::vector<sim::ShapePrimitive>& shapes);

/// What to extract for a snapshot's surface.
struct SurfaceRequest {
  bool enabled = true;
  sim::SurfaceParams params;  // cellSize 0: the particle spacing
};

/// How the water surface reaches GL. kHostCopy: the mesh is copied into each snapshot and uploaded
/// every frame (the CPU backend, where the mesh is in host memory anyway). kInterop: the solver only
/// builds the mesh (field + pyramid) and the GL thread has it written straight into mapped GL buffers
/// (CUDA-GL interop, no host copy).
enum class SurfacePath { kHostCopy, kInterop };
const char* SurfacePathName(SurfacePath path);
/// kInterop exactly when the solver runs on the CUDA device (Solver::ActiveDevice()).
SurfacePath ChooseSurfacePath(sim::Device activeDevice);

/// Which of the fluid's particles a snapshot's reader uses. kAll: pictures, particle mode, water drawn
/// from a host mesh or as sprites. kNone: water drawn from the mesh written in place (SurfacePath::kInterop
/// in water mode), where nothing reads them: `fluid` stays empty and nothing of it is copied back.
enum class ParticleCopy { kAll, kNone };
/// The snapshot's reader on `path` with the surface request `surface`: kNone exactly for the water mode
/// of the interop path.
ParticleCopy ParticlesFor(SurfacePath path, const SurfaceRequest& surface);

/// Copies the solver's state into `out` (fluid unless `particles` is kNone, diffuse particles, step info,
/// counts), the paddles' poses and loads (`paddles` may be null) and, when `surface.enabled`, extracts the
/// surface (timed): a host copy, or with SurfacePath::kInterop only BuildSurface (`out->surfaceOnDevice`;
/// `out->surfaceVertices` is then the solver's last write report, which reads nothing back).
Status CaptureSnapshot(sim::Solver& solver, const interaction::PaddleSystem* paddles, const SurfaceRequest& surface,
                       SimSnapshot* out, SurfacePath path = SurfacePath::kHostCopy,
                       ParticleCopy particles = ParticleCopy::kAll);

}  // namespace sphxr::app
