// The solver's moving bodies (kinematic rigid bodies: paddles): their boundary particles' volumes, the
// target segments they move along, and a restart's motion. The per-step stages are stages/bodies.h.
#include <algorithm>
#include <cmath>

#include "backend.h"
#include "sampling.h"
#include "sphxr/sim/host_grid.h"
#include "sphxr/common/log.h"
#include "sphxr/sim/solver.h"

namespace sphxr::sim {

void Solver::HoldBody(BodyMotion* b, const Pose& pose, double time) {
  b->pose = b->from = b->to = pose;
  b->fromTime = b->toTime = time;
  b->velocity = b->angular = Vec3{};
}

std::vector<BodyState> Solver::StartBodyMotion(float dt) {
  std::vector<BodyState> states;
  if (m_bodies.empty()) return states;
  // Each body moves from its pose now to its interpolated pose at the end of the step; its particles
  // carry the rigid velocity that takes them there.
  const double end = m_last.time + dt;
  size_t firstShape = 0;
  for (BodyMotion& b : m_bodies) {
    const Pose to = BodyPoseAt(b, end);
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
  return states;
}

void Solver::EndBodyMotion(const std::vector<BodyState>& states) {
  if (m_bodies.empty()) return;
  m_backend->BodyLoads(&m_bodyLoads);
  for (size_t k = 0; k < m_bodies.size(); ++k) {
    m_bodies[k].pose = Pose{states[k].endPosition, states[k].endOrientation};
    m_bodies[k].velocity = states[k].velocity;
    m_bodies[k].angular = states[k].angular;
  }
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
    m.pose = Pose{setup.pose.position, Normalized(setup.pose.orientation)};
    m.from = m.to = m.pose;
    m.boundRadius = radius;
    m.shapes = setup.shapes;
    m_bodies.push_back(m);
  }
  m_bodyLoads.assign(m_bodies.size(), BodyLoad{});
  m_backend->InitBodies(local, bodyOf, alpha, shapes);
}

Pose Solver::BodyPoseAt(const BodyMotion& body, double time) const {
  if (time >= body.toTime || body.toTime <= body.fromTime) return body.to;
  const float u = static_cast<float>(std::max(0.0, (time - body.fromTime) / (body.toTime - body.fromTime)));
  return Pose{body.from.position + (body.to.position - body.from.position) * u,
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
  for (Pose* p : {&unit.pose, &unit.from, &unit.to}) {
    const Quat q = p->orientation;
    if (std::abs(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z - 1.0f) > 1e-4f) p->orientation = Normalized(q);
  }
  static_cast<BodyMotionState&>(m_bodies[body]) = unit;
  return Status::Ok();
}

Status Solver::SetBodyTarget(int body, const Pose& target, double targetTime) {
  if (body < 0 || body >= BodyCount()) return Status::Error(Format("SetBodyTarget: no body %d (%d bodies)", body, BodyCount()));
  if (!Finite(target.position) || !Finite(target.orientation) || !std::isfinite(targetTime)) {
    return Status::Error(Format("SetBodyTarget: non-finite target for body %d", body));
  }
  BodyMotion& b = m_bodies[body];
  const Pose to{target.position, Normalized(target.orientation)};
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

}  // namespace sphxr::sim
