#include "sphxr/interaction/paddle.h"

#include <algorithm>
#include <cmath>

#include "pose_math.h"
#include "sphxr/common/log.h"

namespace sphxr::interaction {
namespace {

using sim::ShapePrimitive;
using sim::Vec3;

constexpr float kPi = 3.14159265358979f;

bool Positive(float v) { return std::isfinite(v) && v > 0.0f; }

// One sheet on the surface of the box shrunk by half a spacing, on a lattice fitted to it exactly.
void SampleBox(const ShapePrimitive& s, float dx, std::vector<Vec3>* out) {
  const float e[3] = {std::max(0.0f, s.b.x - 0.5f * dx), std::max(0.0f, s.b.y - 0.5f * dx),
                      std::max(0.0f, s.b.z - 0.5f * dx)};
  int n[3];
  bool flat = false;
  for (int a = 0; a < 3; ++a) {
    n[a] = static_cast<int>(std::lround(2.0f * e[a] / dx));
    flat = flat || n[a] == 0;
  }
  auto coord = [&](int a, int k) { return n[a] == 0 ? 0.0f : -e[a] + 2.0f * e[a] * static_cast<float>(k) / n[a]; };
  for (int kz = 0; kz <= n[2]; ++kz)
    for (int ky = 0; ky <= n[1]; ++ky)
      for (int kx = 0; kx <= n[0]; ++kx) {
        const bool face = flat || (n[0] > 0 && (kx == 0 || kx == n[0])) || (n[1] > 0 && (ky == 0 || ky == n[1])) ||
                          (n[2] > 0 && (kz == 0 || kz == n[2]));
        if (face) out->push_back(s.a + Vec3{coord(0, kx), coord(1, ky), coord(2, kz)});
      }
}

// One sheet on the capsule shrunk by half a spacing: rings along the cylinder, latitude rings on the caps.
void SampleCapsule(const ShapePrimitive& s, float dx, std::vector<Vec3>* out) {
  const Vec3 ab = s.b - s.a;
  const float length = Length(ab);
  const Vec3 axis = length > 0.0f ? ab * (1.0f / length) : Vec3{0.0f, 1.0f, 0.0f};
  const Vec3 c = std::fabs(axis.x) < 0.9f ? Vec3{1.0f, 0.0f, 0.0f} : Vec3{0.0f, 1.0f, 0.0f};
  Vec3 u = Cross(axis, c);
  u = u * (1.0f / Length(u));
  const Vec3 w = Cross(axis, u);
  const float r = s.radius - 0.5f * dx;
  const int m = std::max(1, static_cast<int>(std::lround(length / dx)));
  if (r < 0.25f * dx) {  // thinner than a spacing: a row of points on the axis
    for (int j = 0; j <= m; ++j) out->push_back(s.a + ab * (static_cast<float>(j) / m));
    return;
  }
  auto ring = [&](Vec3 centre, float radius) {
    const int count = std::max(1, static_cast<int>(std::lround(2.0f * kPi * radius / dx)));
    if (radius < 0.25f * dx || count == 1) {
      out->push_back(centre);
      return;
    }
    for (int k = 0; k < count; ++k) {
      const float phi = 2.0f * kPi * static_cast<float>(k) / count;
      out->push_back(centre + u * (radius * std::cos(phi)) + w * (radius * std::sin(phi)));
    }
  };
  if (length > 0.0f) {
    for (int j = 0; j <= m; ++j) ring(s.a + ab * (static_cast<float>(j) / m), r);
  } else {
    ring(s.a, r);
  }
  const int lat = std::max(1, static_cast<int>(std::lround(0.5f * kPi * r / dx)));
  for (int i = 1; i <= lat; ++i) {
    const float theta = 0.5f * kPi * static_cast<float>(i) / lat;  // from the equator
    const float radius = i == lat ? 0.0f : r * std::cos(theta);
    const float offset = r * std::sin(theta);
    ring(s.b + axis * offset, radius);
    ring(s.a - axis * offset, radius);
  }
}

}  // namespace

const char* HolderName(Holder holder) {
  switch (holder) {
    case Holder::kLeftHand: return "left";
    case Holder::kRightHand: return "right";
    case Holder::kScript: return "script";
  }
  return "?";
}

const char* PaddleModeName(PaddleMode mode) {
  switch (mode) {
    case PaddleMode::kFollowing: return "following";
    case PaddleMode::kReentering: return "re-entering";
    case PaddleMode::kHolding: return "holding";
    case PaddleMode::kWithdrawing: return "withdrawing";
  }
  return "?";
}

std::vector<ShapePrimitive> BladeOnHandle(float handleLength, float handleRadius, float bladeWidth, float bladeLength,
                                          float bladeThickness) {
  ShapePrimitive handle;
  handle.kind = ShapePrimitive::Kind::kCapsule;
  handle.a = Vec3{0.0f, 0.0f, 0.0f};
  handle.b = Vec3{0.0f, -handleLength, 0.0f};
  handle.radius = handleRadius;
  ShapePrimitive blade;
  blade.kind = ShapePrimitive::Kind::kBox;
  blade.a = Vec3{0.0f, -handleLength - 0.5f * bladeLength, 0.0f};
  blade.b = Vec3{0.5f * bladeWidth, 0.5f * bladeLength, 0.5f * bladeThickness};
  return {handle, blade};
}

std::vector<Vec3> SamplePaddle(const std::vector<ShapePrimitive>& shapes, float spacing) {
  std::vector<Vec3> out;
  for (size_t k = 0; k < shapes.size(); ++k) {
    std::vector<Vec3> pts;
    if (shapes[k].kind == ShapePrimitive::Kind::kBox) SampleBox(shapes[k], spacing, &pts);
    else SampleCapsule(shapes[k], spacing, &pts);
    for (const Vec3& p : pts) {
      // A sheet point well inside another primitive's sheet is buried in the solid: drop it.
      bool buried = false;
      for (size_t j = 0; j < shapes.size() && !buried; ++j) {
        Vec3 n;
        buried = j != k && sim::ShapeDistance(shapes[j], p, &n) < -0.75f * spacing;
      }
      if (!buried) out.push_back(p);
    }
  }
  return out;
}

Status PaddleSystem::Create(std::vector<PaddleDesc> paddles, const sim::SceneSetup& scene,
                            std::unique_ptr<PaddleSystem>* out) {
  out->reset();
  auto system = std::unique_ptr<PaddleSystem>(new PaddleSystem());
  system->m_scene = scene;
  system->m_scene.bodies.clear();
  system->m_scene.fluid.clear();
  const float dx = scene.params.spacing;
  for (size_t k = 0; k < paddles.size(); ++k) {
    PaddleDesc& d = paddles[k];
    const std::string key = Format("paddles[%zu] (%s)", k, d.name.c_str());
    if (d.shapes.empty()) return Status::Error(key + ": no shapes");
    const PaddleLimits& l = d.limits;
    const float limits[] = {l.maxSpeed, l.maxAngularSpeed, l.teleportDistance, l.reentrySpeed, l.withdrawSpeed};
    const char* names[] = {"max_speed", "max_angular_speed", "teleport_distance", "reentry_speed", "withdraw_speed"};
    for (int i = 0; i < 5; ++i) {
      if (!Positive(limits[i])) return Status::Error(Format("%s: %s = %g must be positive", key.c_str(), names[i], limits[i]));
    }
    if (!std::isfinite(l.holdTime) || l.holdTime < 0.0f) return Status::Error(key + ": hold_time must be 0 or more");
    if (!std::isfinite(l.withdrawClearance) || l.withdrawClearance < 0.0f) {
      return Status::Error(key + ": withdraw_clearance must be 0 or more");
    }
    if (!Positive(d.haptics.fullScaleForce) || !Positive(d.haptics.timeConstant)) {
      return Status::Error(key + ": haptic_force and haptic_time_constant must be positive");
    }
    if (d.holder == Holder::kScript && d.trajectory.Keys().empty()) {
      return Status::Error(key + ": a scripted paddle needs a trajectory");
    }
    for (const ShapePrimitive& s : d.shapes) {
      const bool box = s.kind == ShapePrimitive::Kind::kBox;
      if (box && !(Positive(s.b.x) && Positive(s.b.y) && Positive(s.b.z))) {
        return Status::Error(key + ": a box needs positive half extents");
      }
      if (!box && !Positive(s.radius)) return Status::Error(key + ": a capsule needs a positive radius");
    }
    // Sized from closed forms before anything is sampled (a capsule of radius 100 m asked for 8.9 GB of
    // boundary particles before sim's ValidateBodies saw it): the reach ValidateBodies allows, and a
    // particle count a sheet over the shapes' surfaces cannot exceed by much.
    const float tankSize = Length(scene.tank.max - scene.tank.min);
    double reach = 0.0, area = 0.0;
    for (const ShapePrimitive& s : d.shapes) {
      if (s.kind == ShapePrimitive::Kind::kBox) {
        const double x = std::fabs(s.a.x) + s.b.x, y = std::fabs(s.a.y) + s.b.y, z = std::fabs(s.a.z) + s.b.z;
        reach = std::max(reach, std::sqrt(x * x + y * y + z * z));
        area += 8.0 * (double(s.b.x) * s.b.y + double(s.b.y) * s.b.z + double(s.b.x) * s.b.z);
      } else {
        const double length = Length(s.b - s.a);
        reach = std::max(reach, std::max<double>(Length(s.a), Length(s.b)) + s.radius);
        area += 2.0 * kPi * s.radius * length + 4.0 * kPi * double(s.radius) * s.radius;
      }
    }
    reach -= 0.5 * dx;  // the sheet lies half a spacing inside the surface
    if (!std::isfinite(reach) || reach > tankSize) {
      return Status::Error(Format("%s: its shapes reach %g m from its origin, more than the tank's %g m diagonal",
                                  key.c_str(), reach, tankSize));
    }
    constexpr double kMaxPaddleParticles = double(1 << 26);
    const double estimate = area / (double(dx) * dx);
    if (estimate > kMaxPaddleParticles) {
      return Status::Error(Format("%s: its shapes need about %.3g boundary particles at spacing %g m; at most %.3g "
                                  "are supported: use a larger spacing or smaller shapes",
                                  key.c_str(), estimate, dx, kMaxPaddleParticles));
    }
    Paddle p;
    p.desc = std::move(d);
    p.points = SamplePaddle(p.desc.shapes, dx);
    if (p.points.empty()) return Status::Error(key + ": the shapes gave no boundary particles");
    system->m_paddles.push_back(std::move(p));
  }
  *out = std::move(system);
  return Status::Ok();
}

Pose PaddleSystem::Withdrawn(const Paddle& p, const Pose& from) const {
  float radius = 0.0f;
  for (const Vec3& x : p.points) radius = std::max(radius, Length(x));
  for (const ShapePrimitive& s : p.desc.shapes) {
    radius = std::max(radius, s.kind == ShapePrimitive::Kind::kBox
                                  ? Length(s.a) + Length(s.b)
                                  : std::max(Length(s.a), Length(s.b)) + s.radius);
  }
  Pose out = from;
  out.position.y = m_scene.tank.max.y + p.desc.limits.withdrawClearance + radius;
  return out;
}

void PaddleSystem::AddBodies(sim::SceneSetup* scene) {
  m_firstBody = static_cast<int>(scene->bodies.size());
  const sim::Aabb& tank = m_scene.tank;
  for (Paddle& p : m_paddles) {
    Pose start;
    if (p.desc.holder == Holder::kScript) {
      const HandInput h = p.desc.trajectory.Sample(0.0);
      start = h.pose;
      if (!h.tracked) start = Withdrawn(p, start);
    } else {  // a hand that has not been seen yet: out of the water, entering when it is tracked
      start.position = (tank.min + tank.max) * 0.5f;
      start = Withdrawn(p, start);
      p.state.mode = PaddleMode::kWithdrawing;
      p.lost = true;
      p.lostSince = -1e9;
    }
    p.state.commanded = start;
    sim::RigidBodySetup body;
    body.shapes = p.desc.shapes;
    body.points = p.points;
    body.viscosity = p.desc.viscosity;
    body.pose = start;
    scene->bodies.push_back(std::move(body));
  }
}

Status PaddleSystem::Attach(sim::Solver* solver) {
  if (solver->BodyCount() < m_firstBody + Count()) {
    return Status::Error(Format("paddles: the solver has %d bodies; %d expected (call AddBodies on its scene)",
                                solver->BodyCount(), m_firstBody + Count()));
  }
  m_solver = solver;
  // The commanded pose starts where the solver's body is: the scene's start pose, or the pose a restart
  // from a state file put it at (app/src/state_file.cpp).
  for (int k = 0; k < Count(); ++k) {
    Paddle& p = m_paddles[k];
    p.lastFrame = solver->Time();
    p.state.commanded = solver->BodyPose(m_firstBody + k);
  }
  return Status::Ok();
}

Status PaddleSystem::Drive(Paddle& p, int body, const HandInput& hand, double displayTime) {
  const double frame = displayTime - p.lastFrame;
  if (!(frame > 0.0)) return Status::Ok();  // a repeated or late frame changes nothing
  const double previous = p.lastFrame;
  p.lastFrame = displayTime;
  const PaddleLimits& l = p.desc.limits;
  PaddleState& st = p.state;
  const Pose cmd = st.commanded;
  Pose target = cmd;
  float speed = l.maxSpeed;
  if (hand.tracked) {
    p.lost = false;
    target = hand.pose;
    const float jump = Length(target.position - cmd.position);
    const float allowance =
        l.teleportDistance + (hand.hasVelocity ? Length(hand.linearVelocity) * static_cast<float>(frame) : 0.0f);
    // Re-tracking after a withdrawal is a teleport whatever the distance: the paddle re-enters gently.
    const bool returning = st.mode == PaddleMode::kWithdrawing;
    if (st.mode != PaddleMode::kReentering && (jump > allowance || returning)) {
      st.mode = PaddleMode::kReentering;
      if (++st.teleports <= 5) {
        SPHXR_LOG_INFO("paddle %s: the hand jumped %.3g m in one frame (teleport or re-tracking): gliding there at %g m/s%s",
                       p.desc.name.c_str(), jump, l.reentrySpeed, st.teleports == 5 ? " (not logged again)" : "");
      }
    } else if (st.mode != PaddleMode::kReentering) {
      st.mode = PaddleMode::kFollowing;
    }
    if (st.mode == PaddleMode::kReentering) speed = l.reentrySpeed;
  } else {
    if (!p.lost) {
      p.lost = true;
      p.lostSince = previous;
    }
    if (displayTime - p.lostSince < l.holdTime) {
      st.mode = PaddleMode::kHolding;
      target = cmd;
    } else {
      st.mode = PaddleMode::kWithdrawing;
      target = Withdrawn(p, cmd);
      speed = l.withdrawSpeed;
    }
  }
  // Move towards the target within the speed limits.
  Pose next = target;
  const Vec3 delta = target.position - cmd.position;
  const float dist = Length(delta);
  // The solver may already be past the previous frame (its steps do not end on frame times): the motion
  // spans from its time to this frame's, so the limit applies to that span.
  const double span = std::min(frame, displayTime - m_solver->Time());
  const double reach = span > 0.0 ? span : frame;
  const float maxStep = speed * static_cast<float>(reach);
  if (dist > maxStep) next.position = cmd.position + delta * (maxStep / dist);
  const float angle = AngleBetween(cmd.orientation, target.orientation);
  const float maxAngle = l.maxAngularSpeed * static_cast<float>(reach);
  if (angle > maxAngle) next.orientation = Interpolate(cmd, target, maxAngle / angle).orientation;
  if (st.mode == PaddleMode::kReentering && dist <= maxStep) st.mode = PaddleMode::kFollowing;  // caught up
  st.commanded = next;
  double when = displayTime;
  if (when <= m_solver->Time()) when = m_solver->Time() + frame;  // never a relocation: always a motion
  return m_solver->SetBodyTarget(body, next, when);
}

Status PaddleSystem::BeginFrame(double displayTime, const std::vector<HandInput>& hands) {
  if (!m_solver) return Status::Error("paddles: BeginFrame before Attach");
  for (int k = 0; k < Count(); ++k) {
    Paddle& p = m_paddles[k];
    HandInput hand;  // untracked
    if (p.desc.holder == Holder::kScript) {
      hand = p.desc.trajectory.Sample(displayTime);
    } else {
      const size_t side = p.desc.holder == Holder::kLeftHand ? 0 : 1;
      if (side < hands.size()) hand = hands[side];
    }
    if (Status s = Drive(p, BodyIndex(k), hand, displayTime); !s) return s;
  }
  return Status::Ok();
}

void PaddleSystem::AfterStep() {
  if (!m_solver) return;
  const float dt = m_solver->LastStep().dt;
  for (int k = 0; k < Count(); ++k) {
    Paddle& p = m_paddles[k];
    const sim::BodyLoad& load = m_solver->LastBodyLoad(BodyIndex(k));
    // First-order low-pass, exact for any step: a = 1 - exp(-dt / tau).
    const float a = 1.0f - std::exp(-dt / p.desc.haptics.timeConstant);
    PaddleState& st = p.state;
    st.rawForce = load.force;
    st.force += (load.force - st.force) * a;
    st.torque += (load.torque - st.torque) * a;
    st.haptic = std::min(1.0f, Length(st.force) / p.desc.haptics.fullScaleForce);
  }
}

float PaddleSystem::HapticAmplitude(Holder hand) const {
  float amplitude = 0.0f;
  for (const Paddle& p : m_paddles) {
    if (p.desc.holder == hand) amplitude = std::max(amplitude, p.state.haptic);
  }
  return amplitude;
}

}  // namespace sphxr::interaction
