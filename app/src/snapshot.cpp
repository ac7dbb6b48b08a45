#include "sphxr/app/snapshot.h"

#include <chrono>

namespace sphxr::app {

sim::Vec3 PaddleWorkingPoint(const std::vector<sim::ShapePrimitive>& shapes) {
  sim::Vec3 best{0, 0, 0};
  float lowest = 1e30f;
  for (const sim::ShapePrimitive& s : shapes) {
    const bool box = s.kind == sim::ShapePrimitive::Kind::kBox;
    const float low = box ? s.a.y - s.b.y : std::min(s.a.y, s.b.y) - s.radius;
    if (low < lowest) {
      lowest = low;
      best = box ? s.a : (s.a + s.b) * 0.5f;
    }
  }
  return best;
}

const char* SurfacePathName(SurfacePath path) {
  return path == SurfacePath::kInterop ? "CUDA-GL interop" : "host copy";
}

SurfacePath ChooseSurfacePath(sim::Device activeDevice) {
  return activeDevice == sim::Device::kCuda ? SurfacePath::kInterop : SurfacePath::kHostCopy;
}

ParticleCopy ParticlesFor(SurfacePath path, const SurfaceRequest& surface) {
  return path == SurfacePath::kInterop && surface.enabled ? ParticleCopy::kNone : ParticleCopy::kAll;
}

Status CaptureSnapshot(sim::Solver& solver, const interaction::PaddleSystem* paddles, const SurfaceRequest& surface,
                       SimSnapshot* out, SurfacePath path, ParticleCopy particles) {
  if (particles == ParticleCopy::kAll) {
    solver.Download(&out->fluid);
  } else {
    out->fluid = {};
  }
  solver.DownloadDiffuse(&out->diffuse);
  out->last = solver.LastStep();
  out->steps = solver.GetTotals().steps;
  out->fluidCount = solver.FluidCount();
  out->boundaryCount = solver.BoundaryCount();
  out->paddles.clear();
  out->haptic[0] = out->haptic[1] = 0.0f;
  if (paddles) {
    for (int k = 0; k < paddles->Count(); ++k) {
      const interaction::PaddleDesc& d = paddles->Desc(k);
      const interaction::PaddleState& st = paddles->State(k);
      const sim::Pose pose = solver.BodyPose(paddles->BodyIndex(k));
      PaddlePose p;
      p.shapes = d.shapes;
      p.pose.position = pose.position;
      p.pose.orientation = {pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z};
      p.hand = d.holder == interaction::Holder::kLeftHand ? 0 : d.holder == interaction::Holder::kRightHand ? 1 : -1;
      p.mode = st.mode;
      p.force = st.force;
      p.haptic = st.haptic;
      out->paddles.push_back(std::move(p));
    }
    out->haptic[0] = paddles->HapticAmplitude(interaction::Holder::kLeftHand);
    out->haptic[1] = paddles->HapticAmplitude(interaction::Holder::kRightHand);
  }
  out->surfaceFresh = false;
  out->surfaceOnDevice = false;
  out->surfaceVertices = 0;
  if (!surface.enabled) {
    out->surface = {};
    out->surfaceMs = 0.0;
    return Status::Ok();
  }
  const auto t0 = std::chrono::steady_clock::now();
  sim::SurfaceStats stats;
  if (path == SurfacePath::kInterop) {
    out->surface = {};  // the mesh stays in the solver until the GL thread writes it (WriteSurface)
    if (Status s = solver.BuildSurface(surface.params, &stats); !s) return s;
    out->surfaceOnDevice = true;
    out->surfaceVertices = stats.vertices;
  } else if (Status s = solver.ExtractSurface(surface.params, &out->surface, &stats); !s) {
    return s;
  }
  out->surfaceMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  out->surfaceCellSize = stats.grid.cellSize;
  out->surfaceFresh = true;
  return Status::Ok();
}

}  // namespace sphxr::app
