// The simulated headset's instance and system: its settings read from the environment, the
// instance (pose script, haptics log), the event queue, result and structure names, the one HMD
// system with its stereo view configuration and OpenGL requirements.
#include <openxr/openxr_reflection.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <type_traits>

#include "runtime.h"

namespace sphxr::xr::simrt {
namespace {

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
    if (end == v.c_str() || *end != '\0' || !std::isfinite(d) || d < lo || d > hi) {
      *error = std::string(name) + "='" + Shown(v) + "' is not a number in [" + std::to_string(lo) + ", " +
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
    char tail = 0;
    if (std::sscanf(size.c_str(), "%dx%d%c", &c->eyeWidth, &c->eyeHeight, &tail) != 2 || c->eyeWidth < 1 ||
        c->eyeHeight < 1 || c->eyeWidth > 8192 || c->eyeHeight > 8192) {
      *error = "SPHXR_SIM_XR_EYE_SIZE='" + Shown(size) + "' is not WIDTHxHEIGHT (1..8192)";
      return XR_ERROR_INITIALIZATION_FAILED;
    }
  }
  if (std::string p = Env("SPHXR_SIM_XR_PROFILE"); !p.empty())
    c->profile = p.rfind("/interaction_profiles/", 0) == 0 ? p : "/interaction_profiles/" + p;
  c->poseScriptPath = Env("SPHXR_SIM_XR_POSES");
  c->captureDir = Env("SPHXR_SIM_XR_CAPTURE_DIR");
  // A capture folder that cannot take the pictures is one line here, not one a frame.
  if (struct stat st{}; !c->captureDir.empty() && (stat(c->captureDir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) ||
                                                   access(c->captureDir.c_str(), W_OK) != 0)) {
    *error = "SPHXR_SIM_XR_CAPTURE_DIR='" + Shown(c->captureDir) + "' is not a folder this process can write";
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  c->hapticsLogPath = Env("SPHXR_SIM_XR_HAPTICS_LOG");
  // A FIFO would block the instance's creation until a reader came; a device is no log.
  if (struct stat st{};
      !c->hapticsLogPath.empty() && stat(c->hapticsLogPath.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    *error = "SPHXR_SIM_XR_HAPTICS_LOG='" + Shown(c->hapticsLogPath) + "' is not a regular file";
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  c->failSessionCreate = Env("SPHXR_SIM_XR_FAIL_SESSION") == "1";
  return XR_SUCCESS;
}

}  // namespace

void PushEvent(Instance* inst, const void* event, size_t size) {
  XrEventDataBuffer buffer{};
  std::memcpy(&buffer, event, size);
  inst->events.push_back(buffer);
}

XRAPI_ATTR XrResult XRAPI_CALL EnumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity,
                                                                    uint32_t* count, XrExtensionProperties* props) {
  if (layerName) return XR_ERROR_API_LAYER_NOT_PRESENT;
  return TwoCall(capacity, count, 2, [&](uint32_t i) {
    if (i == 0) {
      std::strncpy(props[i].extensionName, XR_KHR_OPENGL_ENABLE_EXTENSION_NAME, XR_MAX_EXTENSION_NAME_SIZE);
      props[i].extensionVersion = XR_KHR_opengl_enable_SPEC_VERSION;
    } else {
      std::strncpy(props[i].extensionName, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME, XR_MAX_EXTENSION_NAME_SIZE);
      props[i].extensionVersion = XR_KHR_composition_layer_depth_SPEC_VERSION;
    }
  });
}

XRAPI_ATTR XrResult XRAPI_CALL CreateInstance(const XrInstanceCreateInfo* info, XrInstance* out) {
  std::lock_guard lock(Lock());
  if (!info || !out || info->type != XR_TYPE_INSTANCE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (XR_VERSION_MAJOR(info->applicationInfo.apiVersion) != 1 ||
      XR_VERSION_MINOR(info->applicationInfo.apiVersion) != 0)
    return XR_ERROR_API_VERSION_UNSUPPORTED;
  bool depthLayers = false;
  for (uint32_t i = 0; i < info->enabledExtensionCount; ++i) {
    if (std::strcmp(info->enabledExtensionNames[i], XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME) == 0) {
      depthLayers = true;
    } else if (std::strcmp(info->enabledExtensionNames[i], XR_KHR_OPENGL_ENABLE_EXTENSION_NAME) != 0) {
      return XR_ERROR_EXTENSION_NOT_PRESENT;
    }
  }
  if (g_instance) return XR_ERROR_LIMIT_REACHED;
  auto inst = std::make_unique<Instance>();
  inst->depthLayersEnabled = depthLayers;
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

}  // namespace sphxr::xr::simrt
