#pragma once
// Paddles: a hand (hand.h) drives a kinematic rigid body that pushes the fluid as boundary particles
// and feels it push back.
//
//   hand pose at the display time --(limits: speed, teleport, tracking loss)--> commanded pose
//     --> sim::Solver::SetBodyTarget (the solver interpolates it over its substeps: position linear,
//         rotation slerp; each boundary particle carries v + w x r)
//     --> per step: the fluid's force and torque on the body (sum of the boundary particles' reactions)
//     --> low-pass filtered --> haptic amplitude 0..1 per hand
//
// The rules for the commanded pose (docs/dev/paddles.md):
// - it moves towards the hand at most `maxSpeed` (m/s) and `maxAngularSpeed` (rad/s);
// - teleport: a hand pose further than `teleportDistance` from the commanded pose (beyond what the
//   hand's own measured velocity explains over the frame) is not followed at once: the paddle glides
//   there at `reentrySpeed` until it has caught up, so a jump never becomes a huge velocity;
// - tracking loss: the paddle holds its last pose for `holdTime`, then rises straight up out of the
//   water at `withdrawSpeed` to `withdrawClearance` above the tank's top; when tracking returns after
//   that, the paddle re-enters at `reentrySpeed` (a hand-held paddle starts withdrawn, so its first
//   tracked frame is such a return).
#include <memory>
#include <string>
#include <vector>

#include "sphxr/common/status.h"
#include "sphxr/interaction/hand.h"
#include "sphxr/interaction/trajectory.h"
#include "sphxr/sim/params.h"
#include "sphxr/sim/rigid.h"
#include "sphxr/sim/solver.h"

namespace sphxr::interaction {

/// Who holds a paddle.
enum class Holder { kLeftHand, kRightHand, kScript };
const char* HolderName(Holder holder);

struct PaddleLimits {
  float maxSpeed = 8.0f;           // m/s of the paddle origin
  float maxAngularSpeed = 40.0f;   // rad/s
  float teleportDistance = 0.3f;   // m: a larger jump in one frame is a teleport
  float reentrySpeed = 1.0f;       // m/s while catching up after a teleport
  float holdTime = 0.5f;           // s a lost hand's paddle holds still
  float withdrawSpeed = 1.0f;      // m/s when leaving the water after the hold
  float withdrawClearance = 0.05f; // m between the paddle's lowest point and the tank's top when withdrawn
};

struct HapticParams {
  float fullScaleForce = 20.0f;  // N of filtered force that gives amplitude 1
  float timeConstant = 0.05f;    // s, first-order low-pass on force and torque
};

struct PaddleDesc {
  std::string name = "paddle";
  Holder holder = Holder::kScript;
  std::vector<sim::ShapePrimitive> shapes;  // body frame; the origin is where the hand holds it
  float viscosity = -1.0f;                  // alpha fluid-paddle; < 0: solver.boundary_viscosity
  PaddleLimits limits;
  HapticParams haptics;
  Trajectory trajectory;                    // kScript: the scripted hand (must have keys)
};

/// The default paddle: a blade (box) on a round handle (capsule), origin at the grip, blade below it.
/// Sizes in m: handle `handleLength` long, blade `bladeWidth` x `bladeLength` x `bladeThickness`.
std::vector<sim::ShapePrimitive> BladeOnHandle(float handleLength = 0.15f, float handleRadius = 0.012f,
                                               float bladeWidth = 0.1f, float bladeLength = 0.15f,
                                               float bladeThickness = 0.012f);

/// Boundary particles of a union of primitives, body frame: one sheet per primitive half a spacing
/// inside its surface (where the next fluid layer would be, as for the tank's walls), on a lattice of
/// about `spacing`; points buried inside another primitive are dropped. A box thinner than a spacing
/// along an axis becomes one sheet at its mid-plane; a capsule thinner than a spacing becomes a row of
/// points along its axis.
std::vector<sim::Vec3> SamplePaddle(const std::vector<sim::ShapePrimitive>& shapes, float spacing);

/// What a paddle is doing (for the panel, the log and the tests).
enum class PaddleMode { kFollowing, kReentering, kHolding, kWithdrawing };
const char* PaddleModeName(PaddleMode mode);

struct PaddleState {
  PaddleMode mode = PaddleMode::kFollowing;
  Pose commanded;                 // where the paddle is told to be at the last frame's display time
  sim::Vec3 force, torque;        // fluid on the paddle, filtered (N, N m about the paddle origin)
  sim::Vec3 rawForce;             // the last step's, unfiltered
  float haptic = 0.0f;            // 0..1
  int64_t teleports = 0;
};

/// A paddle's own state beyond its body's motion, for a restart (a state file).
struct PaddleRestart {
  PaddleState state;
  bool lost = false;
  double lostSince = 0.0;     // while lost: the time tracking was last seen
  double lastFrame = 0.0;     // the display time of the last frame that drove it
};

class PaddleSystem {
 public:
  /// Checks the descriptions against the scene (spacing, tank) and samples the shapes.
  static Status Create(std::vector<PaddleDesc> paddles, const sim::SceneSetup& scene, std::unique_ptr<PaddleSystem>* out);

  /// Appends one rigid body per paddle to the scene (before sim::Solver::Create). Scripted paddles start
  /// at their trajectory's first pose, hand-held ones withdrawn above the tank's centre.
  void AddBodies(sim::SceneSetup* scene);
  /// Binds to the solver created from that scene.
  Status Attach(sim::Solver* solver);

  /// One display frame: the hands' poses for `displayTime` (index 0 left, 1 right; missing hands are
  /// untracked; scripted paddles sample their trajectory) become the paddles' targets at that time.
  /// The frame clock that calls it is the caller's (app::Simulation::AdvanceFrame); the paddles never
  /// step the solver.
  Status BeginFrame(double displayTime, const std::vector<HandInput>& hands = {});
  /// After every solver step: reads and filters the fluid's load on each paddle.
  void AfterStep();

  /// Paddle k's state for a restart, and setting it back (after Attach, which resets it).
  PaddleRestart Restart(int k) const { return m_paddles[k]; }
  void Restore(int k, const PaddleRestart& r) { static_cast<PaddleRestart&>(m_paddles[k]) = r; }

  int Count() const { return static_cast<int>(m_paddles.size()); }
  const PaddleDesc& Desc(int k) const { return m_paddles[k].desc; }
  const PaddleState& State(int k) const { return m_paddles[k].state; }
  int BodyIndex(int k) const { return m_firstBody + k; }
  /// Haptic amplitude 0..1 of the paddle a hand holds (0 when it holds none).
  float HapticAmplitude(Holder hand) const;
  /// Number of boundary particles of paddle k.
  int ParticleCount(int k) const { return static_cast<int>(m_paddles[k].points.size()); }

 private:
  // The state that changes (PaddleRestart: what a restart saves) and the fixed description.
  struct Paddle : PaddleRestart {
    PaddleDesc desc;
    std::vector<sim::Vec3> points;
    float lowest = 0.0f;        // lowest body-frame y of the solid (for the withdraw height)
  };
  Pose Withdrawn(const Paddle& p, const Pose& from) const;
  Status Drive(Paddle& p, int body, const HandInput& hand, double displayTime);

  std::vector<Paddle> m_paddles;
  sim::SceneSetup m_scene;  // spacing, tank
  sim::Solver* m_solver = nullptr;
  int m_firstBody = 0;
};

}  // namespace sphxr::interaction
