// The simulated headset's frame timing: xrWaitFrame's fixed lattice of display slots at the
// configured rate, begin and end with their checks of the submitted layers, the capture of submitted
// eyes, the state steps to VISIBLE and FOCUSED, and the scripted exit and losses after N frames.
#include <chrono>
#include <thread>

#include "runtime.h"

namespace sphxr::xr::simrt {

XRAPI_ATTR XrResult XRAPI_CALL WaitFrame(XrSession handle, const XrFrameWaitInfo*, XrFrameState* state) {
  XrTime wakeAt = 0;
  {
    std::lock_guard lock(Lock());
    SIMRT_SESSION(handle, s);
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    XrTime now = Now();
    // Display slots are a fixed lattice lastDisplay + k * period. The application is woken one
    // period before its slot; a late application gets the first slot it can still make.
    XrTime display = s->lastDisplayTime ? s->lastDisplayTime + s->periodNs : now + s->periodNs;
    while (display - s->periodNs < now - s->periodNs / 2) display += s->periodNs;
    s->lastDisplayTime = display;
    wakeAt = display - s->periodNs;
    s->frameWaited = true;
    state->predictedDisplayTime = display;
    state->predictedDisplayPeriod = s->periodNs;
    if (s->state == XR_SESSION_STATE_READY) PushSessionState(s, XR_SESSION_STATE_SYNCHRONIZED);
    state->shouldRender =
        (s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED) ? XR_TRUE : XR_FALSE;
  }
  std::this_thread::sleep_until(std::chrono::steady_clock::time_point(std::chrono::nanoseconds(wakeAt)));
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL BeginFrame(XrSession handle, const XrFrameBeginInfo*) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->frameWaited) return XR_ERROR_CALL_ORDER_INVALID;
  s->frameWaited = false;
  if (s->frameBegun) return XR_FRAME_DISCARDED;  // the previous frame was never ended
  s->frameBegun = true;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL EndFrame(XrSession handle, const XrFrameEndInfo* info) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->frameBegun) return XR_ERROR_CALL_ORDER_INVALID;
  if (info->displayTime != s->lastDisplayTime) return XR_ERROR_TIME_INVALID;
  if (info->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE)
    return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
  if (info->layerCount > XR_MIN_COMPOSITION_LAYERS_SUPPORTED) return XR_ERROR_LAYER_LIMIT_EXCEEDED;
  const XrCompositionLayerProjection* projection = nullptr;
  bool depthViews[2] = {false, false};
  for (uint32_t i = 0; i < info->layerCount; ++i) {
    const XrCompositionLayerBaseHeader* layer = info->layers[i];
    if (!layer) return XR_ERROR_LAYER_INVALID;
    if (layer->type != XR_TYPE_COMPOSITION_LAYER_PROJECTION) continue;  // quads: accepted, not composited
    projection = reinterpret_cast<const XrCompositionLayerProjection*>(layer);
    if (projection->viewCount != kViewCount) return XR_ERROR_VALIDATION_FAILURE;
    if (!Check<Space>(projection->space, Tag::kSpace)) return XR_ERROR_HANDLE_INVALID;
    for (uint32_t v = 0; v < kViewCount; ++v) {
      auto* sc = Check<Swapchain>(projection->views[v].subImage.swapchain, Tag::kSwapchain);
      if (!sc) return XR_ERROR_HANDLE_INVALID;
      if (sc->lastReleased < 0) return XR_ERROR_LAYER_INVALID;
      const XrRect2Di& r = projection->views[v].subImage.imageRect;
      if (r.offset.x < 0 || r.offset.y < 0 || r.extent.width <= 0 || r.extent.height <= 0 ||
          uint32_t(r.offset.x + r.extent.width) > sc->width || uint32_t(r.offset.y + r.extent.height) > sc->height)
        return XR_ERROR_SWAPCHAIN_RECT_INVALID;
    }
    if (XrResult d = CheckDepthLayers(s, *projection, depthViews); d != XR_SUCCESS) return d;
  }
  s->frameBegun = false;
  ++s->framesEnded;
  const Config& c = s->instance->config;
  for (int v = 0; v < 2; ++v) s->depthLayersReceived[v] += depthViews[v];
  if (projection && !c.captureDir.empty() && !s->instance->captureFailed && (s->framesEnded - 1) % c.captureEvery == 0) {
    CaptureFrame(s, *projection);
    if (!s->instance->captureFailed) RecordDepthLayers(s, *projection, depthViews);
  }
  if (s->state == XR_SESSION_STATE_SYNCHRONIZED && !s->exitRequested) {
    PushSessionState(s, XR_SESSION_STATE_VISIBLE);
    PushSessionState(s, XR_SESSION_STATE_FOCUSED);
  }
  if (s->framesEnded == c.exitAfterFrames && !s->exitRequested) {
    s->exitRequested = true;
    Stop(s);
  }
  if (s->framesEnded == c.loseSessionAfterFrames) {
    PushSessionState(s, XR_SESSION_STATE_LOSS_PENDING);
    s->lost = true;
  }
  if (s->framesEnded == c.loseInstanceAfterFrames) {
    XrEventDataInstanceLossPending e{XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING, nullptr, Now()};
    PushEvent(s->instance, &e, sizeof(e));
    s->instance->lost = true;
  }
  return XR_SUCCESS;
}

}  // namespace sphxr::xr::simrt
