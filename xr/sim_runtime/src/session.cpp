// The simulated headset's session lifecycle: creation with the app's GLX binding (IDLE then READY),
// begin, end (every stop is an exit: the headset never becomes ready again), the exit request, and
// the state-change events. The frame loop that moves READY on to FOCUSED is in frame.cpp.
#include "runtime.h"

namespace sphxr::xr::simrt {

XRAPI_ATTR XrResult XRAPI_CALL CreateSession(XrInstance handle, const XrSessionCreateInfo* info, XrSession* out) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (info->systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (!inst->graphicsRequirementsQueried) return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
  const auto* binding = static_cast<const XrGraphicsBindingOpenGLXlibKHR*>(info->next);
  while (binding && binding->type != XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR)
    binding = static_cast<const XrGraphicsBindingOpenGLXlibKHR*>(binding->next);
  if (!binding) return XR_ERROR_GRAPHICS_DEVICE_INVALID;
  if (!binding->xDisplay || !binding->glxContext || !binding->glxDrawable) return XR_ERROR_GRAPHICS_DEVICE_INVALID;
  if (inst->session) return XR_ERROR_LIMIT_REACHED;
  if (inst->config.failSessionCreate) return XR_ERROR_RUNTIME_FAILURE;
  auto* s = new Session;
  s->instance = inst;
  s->binding = *binding;
  s->binding.next = nullptr;
  s->periodNs = XrTime(1e9 / inst->config.rateHz + 0.5);
  inst->session = s;
  *out = reinterpret_cast<XrSession>(s);
  PushSessionState(s, XR_SESSION_STATE_IDLE);
  PushSessionState(s, XR_SESSION_STATE_READY);
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL DestroySession(XrSession handle) {
  std::lock_guard lock(Lock());
  Session* s = Check<Session>(handle, Tag::kSession);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  Instance* inst = s->instance;
  for (auto& sc : s->swapchains) sc->tag = Tag::kDead;  // textures die with the app's GL context
  for (auto& sp : s->spaces) sp->tag = Tag::kDead;
  // Drop this session's pending events: their handle is gone.
  std::erase_if(inst->events, [&](const XrEventDataBuffer& e) {
    return e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED &&
           reinterpret_cast<const XrEventDataSessionStateChanged&>(e).session == handle;
  });
  s->tag = Tag::kDead;
  delete s;
  inst->session = nullptr;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL BeginSession(XrSession handle, const XrSessionBeginInfo* info) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (info->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (s->running) return XR_ERROR_SESSION_RUNNING;
  if (s->state != XR_SESSION_STATE_READY) return XR_ERROR_SESSION_NOT_READY;
  s->running = true;
  s->beginTime = Now();
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL EndSession(XrSession handle) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (s->state != XR_SESSION_STATE_STOPPING) return XR_ERROR_SESSION_NOT_STOPPING;
  s->running = false;
  s->frameWaited = s->frameBegun = false;
  PushSessionState(s, XR_SESSION_STATE_IDLE);
  // The simulated headset never becomes ready again: every stop is an exit.
  PushSessionState(s, XR_SESSION_STATE_EXITING);
  return XR_SUCCESS;
}

void Stop(Session* s) {
  if (s->state == XR_SESSION_STATE_FOCUSED) PushSessionState(s, XR_SESSION_STATE_VISIBLE);
  if (s->state == XR_SESSION_STATE_VISIBLE) PushSessionState(s, XR_SESSION_STATE_SYNCHRONIZED);
  PushSessionState(s, XR_SESSION_STATE_STOPPING);
}

XRAPI_ATTR XrResult XRAPI_CALL RequestExitSession(XrSession handle) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->exitRequested) {
    s->exitRequested = true;
    Stop(s);
  }
  return XR_SUCCESS;
}

void PushSessionState(Session* s, XrSessionState state) {
  s->state = state;
  XrEventDataSessionStateChanged e{XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED, nullptr,
                                   reinterpret_cast<XrSession>(s), state, Now()};
  PushEvent(s->instance, &e, sizeof(e));
}

}  // namespace sphxr::xr::simrt
