// The simulated headset runtime: loader negotiation, instance, system, session state machine,
// frame timing, reference spaces and views. Actions are in actions.cpp, swapchains in swapchain.cpp.
#include "runtime.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

#include <openxr/openxr_reflection.h>

// The loader's negotiation interface (loader_interfaces.h, absent from Debian's loader 1.0.20
// package): declared here exactly as the OpenXR loader documentation gives it.
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_CREATE_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_NEXT_INFO,
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
__attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* runtimeRequest);
}

namespace sphxr::xr::simrt {
namespace {

constexpr uint32_t kLoaderRuntimeInterfaceVersion = 1;
constexpr XrSystemId kSystemId = 1;
constexpr uint32_t kViewCount = 2;
const Fov kEyeFov{-0.80f, 0.75f, 0.80f, -0.85f};  // a little asymmetric, like real lenses

const char* kRuntimeName = "sphxr simulated headset";

Instance* g_instance = nullptr;  // one instance at a time

std::string Env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

XrResult ReadConfig(Config* c, std::string* error) {
  auto num = [&](const char* name, double lo, double hi, auto* out) {
    std::string v = Env(name);
    if (v.empty()) return true;
    char* end = nullptr;
    double d = std::strtod(v.c_str(), &end);
    if (end == v.c_str() || *end != '\0' || d < lo || d > hi) {
      *error = std::string(name) + "='" + v + "' is not a number in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "]";
      return false;
    }
    *out = static_cast<std::remove_pointer_t<decltype(out)>>(d);
    return true;
  };
  if (!num("SPHXR_SIM_XR_RATE_HZ", 1.0, 1000.0, &c->rateHz) ||
      !num("SPHXR_SIM_XR_IPD", 0.0, 0.2, &c->ipdMetres) ||
      !num("SPHXR_SIM_XR_CAPTURE_EVERY", 1, 1e9, &c->captureEvery) ||
      !num("SPHXR_SIM_XR_EXIT_AFTER_FRAMES", 0, 1e12, &c->exitAfterFrames) ||
      !num("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", 0, 1e12, &c->loseSessionAfterFrames) ||
      !num("SPHXR_SIM_XR_LOSE_INSTANCE_AFTER_FRAMES", 0, 1e12, &c->loseInstanceAfterFrames))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (std::string size = Env("SPHXR_SIM_XR_EYE_SIZE"); !size.empty()) {
    if (std::sscanf(size.c_str(), "%dx%d", &c->eyeWidth, &c->eyeHeight) != 2 || c->eyeWidth < 1 ||
        c->eyeHeight < 1 || c->eyeWidth > 8192 || c->eyeHeight > 8192) {
      *error = "SPHXR_SIM_XR_EYE_SIZE='" + size + "' is not WIDTHxHEIGHT (1..8192)";
      return XR_ERROR_INITIALIZATION_FAILED;
    }
  }
  if (std::string p = Env("SPHXR_SIM_XR_PROFILE"); !p.empty())
    c->profile = p.rfind("/interaction_profiles/", 0) == 0 ? p : "/interaction_profiles/" + p;
  c->poseScriptPath = Env("SPHXR_SIM_XR_POSES");
  c->captureDir = Env("SPHXR_SIM_XR_CAPTURE_DIR");
  c->hapticsLogPath = Env("SPHXR_SIM_XR_HAPTICS_LOG");
  c->failSessionCreate = Env("SPHXR_SIM_XR_FAIL_SESSION") == "1";
  return XR_SUCCESS;
}

void PushEvent(Instance* inst, const void* event, size_t size) {
  XrEventDataBuffer buffer{};
  std::memcpy(&buffer, event, size);
  inst->events.push_back(buffer);
}

bool SpaceWorldPose(Space* space, XrTime time, Pose* out) {
  Session* s = space->session;
  Pose base;
  if (space->isAction) {
    if (!ActionPose(s, space->action, space->subaction, time, &base)) return false;
  } else if (space->referenceType == XR_REFERENCE_SPACE_TYPE_VIEW) {
    DeviceSample head = s->instance->script.Sample(Device::kHead, ScriptSeconds(s, time));
    if (!head.tracked) return false;
    base = head.pose;
  }  // LOCAL and STAGE share the world origin: the floor under the user's starting point.
  *out = base * space->offset;
  return true;
}

bool Lost(Instance* inst) { return inst->lost; }

#define SIMRT_INSTANCE(handle, var)                             \
  Instance* var = Check<Instance>(handle, Tag::kInstance);      \
  if (!var) return XR_ERROR_HANDLE_INVALID;                     \
  if (Lost(var)) return XR_ERROR_INSTANCE_LOST
#define SIMRT_SESSION(handle, var)                                        \
  Session* var = Check<Session>(handle, Tag::kSession);                   \
  if (!var) return XR_ERROR_HANDLE_INVALID;                               \
  if (Lost(var->instance)) return XR_ERROR_INSTANCE_LOST;                 \
  if (var->lost) return XR_ERROR_SESSION_LOST

// ---- instance --------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL EnumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity,
                                                                    uint32_t* count, XrExtensionProperties* props) {
  if (layerName) return XR_ERROR_API_LAYER_NOT_PRESENT;
  return TwoCall(capacity, count, 1, [&](uint32_t i) {
    std::strncpy(props[i].extensionName, XR_KHR_OPENGL_ENABLE_EXTENSION_NAME, XR_MAX_EXTENSION_NAME_SIZE);
    props[i].extensionVersion = XR_KHR_opengl_enable_SPEC_VERSION;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateInstance(const XrInstanceCreateInfo* info, XrInstance* out) {
  std::lock_guard lock(Lock());
  if (!info || !out || info->type != XR_TYPE_INSTANCE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (XR_VERSION_MAJOR(info->applicationInfo.apiVersion) != 1 ||
      XR_VERSION_MINOR(info->applicationInfo.apiVersion) != 0)
    return XR_ERROR_API_VERSION_UNSUPPORTED;
  for (uint32_t i = 0; i < info->enabledExtensionCount; ++i)
    if (std::strcmp(info->enabledExtensionNames[i], XR_KHR_OPENGL_ENABLE_EXTENSION_NAME) != 0)
      return XR_ERROR_EXTENSION_NOT_PRESENT;
  if (g_instance) return XR_ERROR_LIMIT_REACHED;
  auto inst = std::make_unique<Instance>();
  std::string error;
  if (ReadConfig(&inst->config, &error) != XR_SUCCESS) {
    std::fprintf(stderr, "sphxr simulated headset: %s\n", error.c_str());
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  inst->script = PoseScript::Default();
  if (!inst->config.poseScriptPath.empty() &&
      !PoseScript::Load(inst->config.poseScriptPath, &inst->script, &error)) {
    std::fprintf(stderr, "sphxr simulated headset: %s\n", error.c_str());
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  if (!inst->config.hapticsLogPath.empty()) {
    inst->hapticsLog = std::fopen(inst->config.hapticsLogPath.c_str(), "w");
    if (!inst->hapticsLog) {
      std::fprintf(stderr, "sphxr simulated headset: cannot write haptics log '%s'\n",
                   inst->config.hapticsLogPath.c_str());
      return XR_ERROR_INITIALIZATION_FAILED;
    }
    std::fprintf(inst->hapticsLog, "# frame time_s hand amplitude duration_ns frequency_hz\n");
    std::fflush(inst->hapticsLog);
  }
  g_instance = inst.release();
  *out = reinterpret_cast<XrInstance>(g_instance);
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL DestroyInstance(XrInstance handle) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->session) {
    inst->session->tag = Tag::kDead;
    delete inst->session;
  }
  if (inst->hapticsLog) std::fclose(inst->hapticsLog);
  inst->tag = Tag::kDead;
  delete inst;
  g_instance = nullptr;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProperties(XrInstance handle, XrInstanceProperties* props) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  props->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
  std::strncpy(props->runtimeName, kRuntimeName, XR_MAX_RUNTIME_NAME_SIZE);
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL PollEvent(XrInstance handle, XrEventDataBuffer* event) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->events.empty()) return XR_EVENT_UNAVAILABLE;  // also after loss: the loss event was delivered
  *event = inst->events.front();
  inst->events.pop_front();
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL ResultToString(XrInstance, XrResult value, char buffer[XR_MAX_RESULT_STRING_SIZE]) {
#define SIMRT_RESULT_CASE(name, val) \
  case name: std::strncpy(buffer, #name, XR_MAX_RESULT_STRING_SIZE); return XR_SUCCESS;
  switch (value) {
    XR_LIST_ENUM_XrResult(SIMRT_RESULT_CASE) default:
      std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "XR_%s_%d", value < 0 ? "UNKNOWN_FAILURE" : "UNKNOWN_SUCCESS",
                    int(value));
  }
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL StructureTypeToString(XrInstance, XrStructureType value,
                                                     char buffer[XR_MAX_STRUCTURE_NAME_SIZE]) {
#define SIMRT_TYPE_CASE(name, val) \
  case name: std::strncpy(buffer, #name, XR_MAX_STRUCTURE_NAME_SIZE); return XR_SUCCESS;
  switch (value) {
    XR_LIST_ENUM_XrStructureType(SIMRT_TYPE_CASE) default:
      std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "XR_UNKNOWN_STRUCTURE_TYPE_%d", int(value));
  }
  return XR_SUCCESS;
}

// ---- system ----------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL GetSystem(XrInstance handle, const XrSystemGetInfo* info, XrSystemId* id) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY) return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
  inst->systemQueried = true;
  *id = kSystemId;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetSystemProperties(XrInstance handle, XrSystemId id, XrSystemProperties* props) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  props->systemId = kSystemId;
  props->vendorId = 0x5350;  // "SP"
  std::strncpy(props->systemName, kRuntimeName, XR_MAX_SYSTEM_NAME_SIZE);
  props->graphicsProperties.maxSwapchainImageWidth = 8192;
  props->graphicsProperties.maxSwapchainImageHeight = 8192;
  props->graphicsProperties.maxLayerCount = XR_MIN_COMPOSITION_LAYERS_SUPPORTED;
  props->trackingProperties.orientationTracking = XR_TRUE;
  props->trackingProperties.positionTracking = XR_TRUE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateEnvironmentBlendModes(XrInstance handle, XrSystemId id,
                                                              XrViewConfigurationType type, uint32_t capacity,
                                                              uint32_t* count, XrEnvironmentBlendMode* modes) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  return TwoCall(capacity, count, 1, [&](uint32_t i) { modes[i] = XR_ENVIRONMENT_BLEND_MODE_OPAQUE; });
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateViewConfigurations(XrInstance handle, XrSystemId id, uint32_t capacity,
                                                           uint32_t* count, XrViewConfigurationType* types) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  return TwoCall(capacity, count, 1, [&](uint32_t i) { types[i] = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO; });
}

XRAPI_ATTR XrResult XRAPI_CALL GetViewConfigurationProperties(XrInstance handle, XrSystemId id,
                                                              XrViewConfigurationType type,
                                                              XrViewConfigurationProperties* props) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  props->viewConfigurationType = type;
  props->fovMutable = XR_FALSE;
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateViewConfigurationViews(XrInstance handle, XrSystemId id,
                                                               XrViewConfigurationType type, uint32_t capacity,
                                                               uint32_t* count, XrViewConfigurationView* views) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  const Config& c = inst->config;
  return TwoCall(capacity, count, kViewCount, [&](uint32_t i) {
    views[i].recommendedImageRectWidth = uint32_t(c.eyeWidth);
    views[i].recommendedImageRectHeight = uint32_t(c.eyeHeight);
    views[i].maxImageRectWidth = 8192;
    views[i].maxImageRectHeight = 8192;
    views[i].recommendedSwapchainSampleCount = 1;
    views[i].maxSwapchainSampleCount = 1;
  });
}

XRAPI_ATTR XrResult XRAPI_CALL GetOpenGLGraphicsRequirementsKHR(XrInstance handle, XrSystemId id,
                                                                XrGraphicsRequirementsOpenGLKHR* req) {
  std::lock_guard lock(Lock());
  SIMRT_INSTANCE(handle, inst);
  if (id != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  req->minApiVersionSupported = XR_MAKE_VERSION(3, 3, 0);
  req->maxApiVersionSupported = XR_MAKE_VERSION(4, 6, 0);
  inst->graphicsRequirementsQueried = true;
  return XR_SUCCESS;
}

// ---- session ---------------------------------------------------------------------------------

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

// ---- frames ----------------------------------------------------------------------------------

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
  }
  s->frameBegun = false;
  ++s->framesEnded;
  const Config& c = s->instance->config;
  if (projection && !c.captureDir.empty() && (s->framesEnded - 1) % c.captureEvery == 0) CaptureFrame(s, *projection);
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

// ---- spaces and views ------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL EnumerateReferenceSpaces(XrSession handle, uint32_t capacity, uint32_t* count,
                                                        XrReferenceSpaceType* spaces) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  static const XrReferenceSpaceType kTypes[] = {XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL,
                                                XR_REFERENCE_SPACE_TYPE_STAGE};
  return TwoCall(capacity, count, 3, [&](uint32_t i) { spaces[i] = kTypes[i]; });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateReferenceSpace(XrSession handle, const XrReferenceSpaceCreateInfo* info,
                                                    XrSpace* out) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  XrReferenceSpaceType t = info->referenceSpaceType;
  if (t != XR_REFERENCE_SPACE_TYPE_VIEW && t != XR_REFERENCE_SPACE_TYPE_LOCAL && t != XR_REFERENCE_SPACE_TYPE_STAGE)
    return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  auto space = std::make_unique<Space>();
  space->session = s;
  space->referenceType = t;
  space->offset = FromXr(info->poseInReferenceSpace);
  *out = reinterpret_cast<XrSpace>(space.get());
  s->spaces.push_back(std::move(space));
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL GetReferenceSpaceBoundsRect(XrSession handle, XrReferenceSpaceType type,
                                                           XrExtent2Df* bounds) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (type != XR_REFERENCE_SPACE_TYPE_STAGE) {
    *bounds = {0, 0};
    return XR_SPACE_BOUNDS_UNAVAILABLE;
  }
  *bounds = {3.0f, 3.0f};
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL CreateActionSpace(XrSession handle, const XrActionSpaceCreateInfo* info,
                                                 XrSpace* out) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  Action* action = Check<Action>(info->action, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  if (action->type != XR_ACTION_TYPE_POSE_INPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (info->subactionPath != XR_NULL_PATH &&
      std::find(action->subactions.begin(), action->subactions.end(), info->subactionPath) ==
          action->subactions.end())
    return XR_ERROR_PATH_UNSUPPORTED;
  auto space = std::make_unique<Space>();
  space->session = s;
  space->isAction = true;
  space->action = action;
  space->subaction = info->subactionPath;
  space->offset = FromXr(info->poseInActionSpace);
  *out = reinterpret_cast<XrSpace>(space.get());
  s->spaces.push_back(std::move(space));
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL DestroySpace(XrSpace handle) {
  std::lock_guard lock(Lock());
  Space* space = Check<Space>(handle, Tag::kSpace);
  if (!space) return XR_ERROR_HANDLE_INVALID;
  auto& list = space->session->spaces;
  space->tag = Tag::kDead;
  std::erase_if(list, [&](const std::unique_ptr<Space>& p) { return p.get() == space; });
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL LocateSpace(XrSpace spaceHandle, XrSpace baseHandle, XrTime time,
                                           XrSpaceLocation* location) {
  std::lock_guard lock(Lock());
  Space* space = Check<Space>(spaceHandle, Tag::kSpace);
  Space* base = Check<Space>(baseHandle, Tag::kSpace);
  if (!space || !base) return XR_ERROR_HANDLE_INVALID;
  if (space->session->instance->lost) return XR_ERROR_INSTANCE_LOST;
  if (space->session->lost) return XR_ERROR_SESSION_LOST;
  if (time <= 0) return XR_ERROR_TIME_INVALID;
  auto* velocity = static_cast<XrSpaceVelocity*>(location->next);
  while (velocity && velocity->type != XR_TYPE_SPACE_VELOCITY) velocity = static_cast<XrSpaceVelocity*>(velocity->next);
  Pose p, b;
  if (!SpaceWorldPose(space, time, &p) || !SpaceWorldPose(base, time, &b)) {
    location->locationFlags = 0;
    if (velocity) velocity->velocityFlags = 0;
    return XR_SUCCESS;
  }
  Pose rel = Inverse(b) * p;
  location->pose = ToXr(rel);
  location->locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
                            XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
  if (velocity) {
    // Central difference over +-1 ms of the script, expressed in the base space.
    constexpr XrTime kH = 1000000;
    Pose p0, p1, b0, b1;
    velocity->velocityFlags = 0;
    if (SpaceWorldPose(space, time - kH, &p0) && SpaceWorldPose(space, time + kH, &p1) &&
        SpaceWorldPose(base, time - kH, &b0) && SpaceWorldPose(base, time + kH, &b1)) {
      Pose r0 = Inverse(b0) * p0, r1 = Inverse(b1) * p1;
      Vec3 v = (r1.position - r0.position) * float(1e9 / (2.0 * kH));
      Quat dq = Mul(r1.orientation, Conjugate(r0.orientation));  // rotation over 2h, in the base frame
      if (dq.w < 0) dq = {-dq.x, -dq.y, -dq.z, -dq.w};
      float sinHalf = std::sqrt(dq.x * dq.x + dq.y * dq.y + dq.z * dq.z);
      float angle = 2.0f * std::atan2(sinHalf, dq.w);
      Vec3 axis = sinHalf > 1e-9f ? Vec3{dq.x / sinHalf, dq.y / sinHalf, dq.z / sinHalf} : Vec3{};
      Vec3 w = axis * float(angle * 1e9 / (2.0 * kH));
      velocity->linearVelocity = {v.x, v.y, v.z};
      velocity->angularVelocity = {w.x, w.y, w.z};
      velocity->velocityFlags = XR_SPACE_VELOCITY_LINEAR_VALID_BIT | XR_SPACE_VELOCITY_ANGULAR_VALID_BIT;
    }
  }
  return XR_SUCCESS;
}

XRAPI_ATTR XrResult XRAPI_CALL LocateViews(XrSession handle, const XrViewLocateInfo* info, XrViewState* state,
                                           uint32_t capacity, uint32_t* count, XrView* views) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (info->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  Space* space = Check<Space>(info->space, Tag::kSpace);
  if (!space) return XR_ERROR_HANDLE_INVALID;
  if (info->displayTime <= 0) return XR_ERROR_TIME_INVALID;
  DeviceSample head = s->instance->script.Sample(Device::kHead, ScriptSeconds(s, info->displayTime));
  Pose base;
  bool valid = head.tracked && SpaceWorldPose(space, info->displayTime, &base);
  state->viewStateFlags = valid ? XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT |
                                      XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT
                                : 0;
  float half = s->instance->config.ipdMetres * 0.5f;
  return TwoCall(capacity, count, kViewCount, [&](uint32_t i) {
    Pose eye = head.pose * Pose{{i == 0 ? -half : half, 0, 0}, {}};
    views[i].pose = ToXr(valid ? Inverse(base) * eye : Pose{});
    // The right eye mirrors the left eye's field of view.
    views[i].fov = i == 0 ? XrFovf{kEyeFov.angleLeft, kEyeFov.angleRight, kEyeFov.angleUp, kEyeFov.angleDown}
                          : XrFovf{-kEyeFov.angleRight, -kEyeFov.angleLeft, kEyeFov.angleUp, kEyeFov.angleDown};
  });
}

// ---- dispatch --------------------------------------------------------------------------------

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance instance, const char* name,
                                                   PFN_xrVoidFunction* function) {
  if (!name || !function) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
#define SIMRT_FN(xrName, impl)                                      \
  if (std::strcmp(name, #xrName) == 0) {                            \
    *function = reinterpret_cast<PFN_xrVoidFunction>(&impl);        \
    return XR_SUCCESS;                                              \
  }
  SIMRT_FN(xrGetInstanceProcAddr, GetInstanceProcAddr)
  SIMRT_FN(xrEnumerateInstanceExtensionProperties, EnumerateInstanceExtensionProperties)
  SIMRT_FN(xrCreateInstance, CreateInstance)
  if (instance == XR_NULL_HANDLE) return XR_ERROR_HANDLE_INVALID;
  SIMRT_FN(xrDestroyInstance, DestroyInstance)
  SIMRT_FN(xrGetInstanceProperties, GetInstanceProperties)
  SIMRT_FN(xrPollEvent, PollEvent)
  SIMRT_FN(xrResultToString, ResultToString)
  SIMRT_FN(xrStructureTypeToString, StructureTypeToString)
  SIMRT_FN(xrGetSystem, GetSystem)
  SIMRT_FN(xrGetSystemProperties, GetSystemProperties)
  SIMRT_FN(xrEnumerateEnvironmentBlendModes, EnumerateEnvironmentBlendModes)
  SIMRT_FN(xrEnumerateViewConfigurations, EnumerateViewConfigurations)
  SIMRT_FN(xrGetViewConfigurationProperties, GetViewConfigurationProperties)
  SIMRT_FN(xrEnumerateViewConfigurationViews, EnumerateViewConfigurationViews)
  SIMRT_FN(xrGetOpenGLGraphicsRequirementsKHR, GetOpenGLGraphicsRequirementsKHR)
  SIMRT_FN(xrCreateSession, CreateSession)
  SIMRT_FN(xrDestroySession, DestroySession)
  SIMRT_FN(xrBeginSession, BeginSession)
  SIMRT_FN(xrEndSession, EndSession)
  SIMRT_FN(xrRequestExitSession, RequestExitSession)
  SIMRT_FN(xrWaitFrame, WaitFrame)
  SIMRT_FN(xrBeginFrame, BeginFrame)
  SIMRT_FN(xrEndFrame, EndFrame)
  SIMRT_FN(xrLocateViews, LocateViews)
  SIMRT_FN(xrEnumerateReferenceSpaces, EnumerateReferenceSpaces)
  SIMRT_FN(xrCreateReferenceSpace, CreateReferenceSpace)
  SIMRT_FN(xrGetReferenceSpaceBoundsRect, GetReferenceSpaceBoundsRect)
  SIMRT_FN(xrCreateActionSpace, CreateActionSpace)
  SIMRT_FN(xrLocateSpace, LocateSpace)
  SIMRT_FN(xrDestroySpace, DestroySpace)
  SIMRT_FN(xrStringToPath, StringToPath)
  SIMRT_FN(xrPathToString, PathToString)
  SIMRT_FN(xrCreateActionSet, CreateActionSet)
  SIMRT_FN(xrDestroyActionSet, DestroyActionSet)
  SIMRT_FN(xrCreateAction, CreateAction)
  SIMRT_FN(xrDestroyAction, DestroyAction)
  SIMRT_FN(xrSuggestInteractionProfileBindings, SuggestInteractionProfileBindings)
  SIMRT_FN(xrAttachSessionActionSets, AttachSessionActionSets)
  SIMRT_FN(xrGetCurrentInteractionProfile, GetCurrentInteractionProfile)
  SIMRT_FN(xrGetActionStateBoolean, GetActionStateBoolean)
  SIMRT_FN(xrGetActionStateFloat, GetActionStateFloat)
  SIMRT_FN(xrGetActionStateVector2f, GetActionStateVector2f)
  SIMRT_FN(xrGetActionStatePose, GetActionStatePose)
  SIMRT_FN(xrSyncActions, SyncActions)
  SIMRT_FN(xrEnumerateBoundSourcesForAction, EnumerateBoundSourcesForAction)
  SIMRT_FN(xrGetInputSourceLocalizedName, GetInputSourceLocalizedName)
  SIMRT_FN(xrApplyHapticFeedback, ApplyHapticFeedback)
  SIMRT_FN(xrStopHapticFeedback, StopHapticFeedback)
  SIMRT_FN(xrEnumerateSwapchainFormats, EnumerateSwapchainFormats)
  SIMRT_FN(xrCreateSwapchain, CreateSwapchain)
  SIMRT_FN(xrDestroySwapchain, DestroySwapchain)
  SIMRT_FN(xrEnumerateSwapchainImages, EnumerateSwapchainImages)
  SIMRT_FN(xrAcquireSwapchainImage, AcquireSwapchainImage)
  SIMRT_FN(xrWaitSwapchainImage, WaitSwapchainImage)
  SIMRT_FN(xrReleaseSwapchainImage, ReleaseSwapchainImage)
#undef SIMRT_FN
  return XR_ERROR_FUNCTION_UNSUPPORTED;
}

}  // namespace

std::mutex& Lock() {
  static std::mutex m;
  return m;
}

XrTime Now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void PushSessionState(Session* s, XrSessionState state) {
  s->state = state;
  XrEventDataSessionStateChanged e{XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED, nullptr,
                                   reinterpret_cast<XrSession>(s), state, Now()};
  PushEvent(s->instance, &e, sizeof(e));
}

double ScriptSeconds(const Session* s, XrTime time) {
  return s->beginTime ? double(time - s->beginTime) * 1e-9 : 0.0;
}

}  // namespace sphxr::xr::simrt

extern "C" XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* loaderInfo,
                                                      XrNegotiateRuntimeRequest* request) {
  using namespace sphxr::xr::simrt;
  if (!loaderInfo || !request || loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      loaderInfo->structVersion != 1 || loaderInfo->structSize != sizeof(XrNegotiateLoaderInfo) ||
      request->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST || request->structVersion != 1 ||
      request->structSize != sizeof(XrNegotiateRuntimeRequest))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (loaderInfo->minInterfaceVersion > kLoaderRuntimeInterfaceVersion ||
      loaderInfo->maxInterfaceVersion < kLoaderRuntimeInterfaceVersion ||
      XR_VERSION_MAJOR(loaderInfo->minApiVersion) > 1 || XR_VERSION_MAJOR(loaderInfo->maxApiVersion) < 1)
    return XR_ERROR_INITIALIZATION_FAILED;
  request->runtimeInterfaceVersion = kLoaderRuntimeInterfaceVersion;
  request->runtimeApiVersion = XR_CURRENT_API_VERSION;
  request->getInstanceProcAddr = &GetInstanceProcAddr;
  return XR_SUCCESS;
}
