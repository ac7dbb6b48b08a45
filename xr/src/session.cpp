// sphxr's OpenXR session: creation (instance, system, session, spaces, actions, swapchains), the
// session state machine of the specification, and the frame loop. hello_xr's shape: this file knows
// no graphics beyond binding an eye's framebuffer; the application draws in the callback.
#include "sphxr/xr/session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "action_bindings.h"
#include "gl_functions.h"
#include "graphics_binding.h"
#include "openxr_include.h"
#include "sphxr/common/log.h"

#include <openxr/openxr_reflection.h>

namespace sphxr::xr {

const char* ResultName(XrResult result) {
#define SPHXR_XR_RESULT_CASE(name, value) \
  case name: return #name;
  switch (result) {
    XR_LIST_ENUM_XrResult(SPHXR_XR_RESULT_CASE) default : return "XR_UNKNOWN_RESULT";
  }
}

Status XrFailure(const char* call, XrResult result, const char* file, int line) {
  std::string c(call);
  if (auto paren = c.find('('); paren != std::string::npos) c.resize(paren);  // "xrCreateSession"
  const char* base = std::strrchr(file, '/');
  return Status::Error(Format("OpenXR: %s failed: %s (%s:%d)", c.c_str(), ResultName(result), base ? base + 1 : file,
                              line));
}

bool GlFunctions::Load(void* (*get)(const char*), const char** missing) {
#define SPHXR_GL_LOAD(field, name)                                    \
  field = reinterpret_cast<decltype(field)>(get(name));               \
  if (!field) {                                                       \
    *missing = name;                                                  \
    return false;                                                     \
  }
  SPHXR_GL_LOAD(GenFramebuffers, "glGenFramebuffers")
  SPHXR_GL_LOAD(DeleteFramebuffers, "glDeleteFramebuffers")
  SPHXR_GL_LOAD(BindFramebuffer, "glBindFramebuffer")
  SPHXR_GL_LOAD(FramebufferTexture2D, "glFramebufferTexture2D")
  SPHXR_GL_LOAD(CheckFramebufferStatus, "glCheckFramebufferStatus")
  SPHXR_GL_LOAD(Viewport, "glViewport")
  SPHXR_GL_LOAD(GetIntegerv, "glGetIntegerv")
  SPHXR_GL_LOAD(GetString, "glGetString")
  SPHXR_GL_LOAD(GenTextures, "glGenTextures")
  SPHXR_GL_LOAD(DeleteTextures, "glDeleteTextures")
  SPHXR_GL_LOAD(BindTexture, "glBindTexture")
  SPHXR_GL_LOAD(TexImage2D, "glTexImage2D")
  SPHXR_GL_LOAD(Enable, "glEnable")
  SPHXR_GL_LOAD(Disable, "glDisable")
  SPHXR_GL_LOAD(IsEnabled, "glIsEnabled")
#undef SPHXR_GL_LOAD
  return true;
}

const char* SessionStateName(SessionState s) {
  switch (s) {
    case SessionState::kUnknown: return "UNKNOWN";
    case SessionState::kIdle: return "IDLE";
    case SessionState::kReady: return "READY";
    case SessionState::kSynchronized: return "SYNCHRONIZED";
    case SessionState::kVisible: return "VISIBLE";
    case SessionState::kFocused: return "FOCUSED";
    case SessionState::kStopping: return "STOPPING";
    case SessionState::kLossPending: return "LOSS_PENDING";
    case SessionState::kExiting: return "EXITING";
  }
  return "?";
}

namespace {

SessionState FromXr(XrSessionState s) {
  switch (s) {
    case XR_SESSION_STATE_IDLE: return SessionState::kIdle;
    case XR_SESSION_STATE_READY: return SessionState::kReady;
    case XR_SESSION_STATE_SYNCHRONIZED: return SessionState::kSynchronized;
    case XR_SESSION_STATE_VISIBLE: return SessionState::kVisible;
    case XR_SESSION_STATE_FOCUSED: return SessionState::kFocused;
    case XR_SESSION_STATE_STOPPING: return SessionState::kStopping;
    case XR_SESSION_STATE_LOSS_PENDING: return SessionState::kLossPending;
    case XR_SESSION_STATE_EXITING: return SessionState::kExiting;
    default: return SessionState::kUnknown;
  }
}

Pose FromXr(const XrPosef& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z}};
}
XrPosef ToXr(const Pose& p) {
  return {{p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w},
          {p.position.x, p.position.y, p.position.z}};
}
Vec3 FromXr(const XrVector3f& v) { return {v.x, v.y, v.z}; }

bool IsLoss(XrResult r) { return r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST; }

constexpr const char* kHandPaths[kHandCount] = {"/user/hand/left", "/user/hand/right"};

}  // namespace

struct Session::Impl {
  SessionOptions options;
  GraphicsBinding binding;
  GlFunctions gl;
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId systemId = XR_NULL_SYSTEM_ID;
  XrSession session = XR_NULL_HANDLE;
  XrReferenceSpaceType playType = XR_REFERENCE_SPACE_TYPE_STAGE;
  XrSpace playSpace = XR_NULL_HANDLE, viewSpace = XR_NULL_HANDLE;
  XrEnvironmentBlendMode blendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  XrActionSet actionSet = XR_NULL_HANDLE;
  std::array<XrAction, size_t(ActionId::kCount)> actions{};
  std::array<XrPath, kHandCount> handPaths{};
  std::array<XrSpace, kHandCount> gripSpaces{};
  struct Eye {
    XrSwapchain color = XR_NULL_HANDLE, depth = XR_NULL_HANDLE;
    std::vector<uint32_t> colorImages, depthImages;
    uint32_t ownDepth = 0;  // our own depth texture when the runtime offers no depth format
    uint32_t framebuffer = 0;
    int width = 0, height = 0;
  };
  std::array<Eye, 2> eyes;
  int64_t colorFormat = 0, depthFormat = 0;
  SessionState state = SessionState::kUnknown;
  bool running = false, lost = false, exited = false;
  std::string exitMessage;
  uint64_t frameIndex = 0;
  XrTime lastDisplayTime = 0;
  FrameTimings timings;
  std::string runtimeName;

  XrAction action(ActionId id) const { return actions[size_t(id)]; }
  Status CreateInstance();
  Status CreateSessionAndSpaces(const PlatformBinding& platform);
  Status CreateActions();
  Status CreateSwapchains();
  Status SyncHands(FrameInfo* info, bool* recentre);
  Status RenderEyes(const FrameInfo& info, const RenderEyeFn& renderEye,
                    std::array<XrCompositionLayerProjectionView, 2>* views, bool* rendered);
  Status RecentreAt(XrTime time);
  void Destroy();
};

Status ProbeRuntime() {
  // The loader prints its own "Error [...]" lines to stderr when no runtime is found; our status
  // says it in one line. Users who want the loader's view set XR_LOADER_DEBUG themselves.
#if defined(_WIN32)
  if (!std::getenv("XR_LOADER_DEBUG")) _putenv_s("XR_LOADER_DEBUG", "none");
#else
  setenv("XR_LOADER_DEBUG", "none", /*overwrite=*/0);
#endif
  uint32_t count = 0;
  XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr);
  if (r == XR_ERROR_RUNTIME_UNAVAILABLE || r == XR_ERROR_RUNTIME_FAILURE || r == XR_ERROR_INSTANCE_LOST ||
      r == XR_ERROR_INITIALIZATION_FAILED)
    return Status::Error(Format("no OpenXR runtime available (the loader answered %s): start a runtime (Monado, "
                                "SteamVR, ...) or point XR_RUNTIME_JSON at one; docs/dev/xr.md shows the simulated headset",
                                ResultName(r)));
  SPHXR_XR_CHECK_RESULT(xrEnumerateInstanceExtensionProperties, r);
  std::vector<XrExtensionProperties> exts(count, {XR_TYPE_EXTENSION_PROPERTIES});
  SPHXR_XR_CHECK(xrEnumerateInstanceExtensionProperties(nullptr, count, &count, exts.data()));
  bool hasGl = std::any_of(exts.begin(), exts.end(), [](const XrExtensionProperties& e) {
    return std::strcmp(e.extensionName, XR_KHR_OPENGL_ENABLE_EXTENSION_NAME) == 0;
  });
  if (!hasGl) return Status::Error("the OpenXR runtime does not offer XR_KHR_opengl_enable (sphxr draws with OpenGL)");
  return Status::Ok();
}

Status Session::Impl::CreateInstance() {
  if (Status s = ProbeRuntime(); !s) return s;
  XrResult r;

  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::snprintf(ci.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", options.applicationName.c_str());
  ci.applicationInfo.applicationVersion = 1;
  std::snprintf(ci.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "sphxr");
  ci.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  const char* extNames[] = {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME};
  ci.enabledExtensionCount = 1;
  ci.enabledExtensionNames = extNames;
  r = xrCreateInstance(&ci, &instance);
  if (r == XR_ERROR_RUNTIME_UNAVAILABLE || r == XR_ERROR_RUNTIME_FAILURE || r == XR_ERROR_INITIALIZATION_FAILED)
    return Status::Error(Format("the OpenXR runtime did not start (xrCreateInstance answered %s); its own "
                                "message, if any, is above",
                                ResultName(r)));
  SPHXR_XR_CHECK_RESULT(xrCreateInstance, r);
  XrInstanceProperties props{XR_TYPE_INSTANCE_PROPERTIES};
  SPHXR_XR_CHECK(xrGetInstanceProperties(instance, &props));
  runtimeName = props.runtimeName;

  XrSystemGetInfo si{XR_TYPE_SYSTEM_GET_INFO};
  si.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  r = xrGetSystem(instance, &si, &systemId);
  if (r == XR_ERROR_FORM_FACTOR_UNAVAILABLE)
    return Status::Error(Format("OpenXR runtime '%s' has no headset connected (XR_ERROR_FORM_FACTOR_UNAVAILABLE)",
                                runtimeName.c_str()));
  SPHXR_XR_CHECK_RESULT(xrGetSystem, r);

  uint32_t modeCount = 0;
  SPHXR_XR_CHECK(xrEnumerateEnvironmentBlendModes(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0,
                                                  &modeCount, nullptr));
  std::vector<XrEnvironmentBlendMode> modes(modeCount);
  SPHXR_XR_CHECK(xrEnumerateEnvironmentBlendModes(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                                                  modeCount, &modeCount, modes.data()));
  if (modes.empty()) return Status::Error("OpenXR: the runtime offers no environment blend mode");
  blendMode = std::find(modes.begin(), modes.end(), XR_ENVIRONMENT_BLEND_MODE_OPAQUE) != modes.end()
                  ? XR_ENVIRONMENT_BLEND_MODE_OPAQUE
                  : modes[0];
  return Status::Ok();
}

Status Session::Impl::CreateSessionAndSpaces(const PlatformBinding& platform) {
  PFN_xrGetOpenGLGraphicsRequirementsKHR getRequirements = nullptr;
  SPHXR_XR_CHECK(xrGetInstanceProcAddr(instance, "xrGetOpenGLGraphicsRequirementsKHR",
                                       reinterpret_cast<PFN_xrVoidFunction*>(&getRequirements)));
  XrGraphicsRequirementsOpenGLKHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_OPENGL_KHR};
  SPHXR_XR_CHECK(getRequirements(instance, systemId, &req));
  int major = 0, minor = 0;
  const char* version = reinterpret_cast<const char*>(gl.GetString(gl::kVersion));
  if (!version || std::sscanf(version, "%d.%d", &major, &minor) != 2)
    return Status::Error("OpenXR: cannot read the GL version of the current context");
  XrVersion have = XR_MAKE_VERSION(major, minor, 0);
  if (have < req.minApiVersionSupported)
    return Status::Error(Format("the OpenXR runtime needs OpenGL %d.%d, the context has %d.%d",
                                int(XR_VERSION_MAJOR(req.minApiVersionSupported)),
                                int(XR_VERSION_MINOR(req.minApiVersionSupported)), major, minor));

  XrSessionCreateInfo ci{XR_TYPE_SESSION_CREATE_INFO};
  ci.next = platform.header;
  ci.systemId = systemId;
  SPHXR_XR_CHECK(xrCreateSession(instance, &ci, &session));

  uint32_t count = 0;
  SPHXR_XR_CHECK(xrEnumerateReferenceSpaces(session, 0, &count, nullptr));
  std::vector<XrReferenceSpaceType> types(count);
  SPHXR_XR_CHECK(xrEnumerateReferenceSpaces(session, count, &count, types.data()));
  playType = std::find(types.begin(), types.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != types.end()
                 ? XR_REFERENCE_SPACE_TYPE_STAGE
                 : XR_REFERENCE_SPACE_TYPE_LOCAL;
  XrReferenceSpaceCreateInfo si{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  si.referenceSpaceType = playType;
  si.poseInReferenceSpace = ToXr(Pose{});
  SPHXR_XR_CHECK(xrCreateReferenceSpace(session, &si, &playSpace));
  si.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  SPHXR_XR_CHECK(xrCreateReferenceSpace(session, &si, &viewSpace));
  return Status::Ok();
}

Status Session::Impl::CreateActions() {
  XrActionSetCreateInfo si{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(si.actionSetName, "sphxr");
  std::strcpy(si.localizedActionSetName, "sphxr");
  SPHXR_XR_CHECK(xrCreateActionSet(instance, &si, &actionSet));
  for (int h = 0; h < kHandCount; ++h) SPHXR_XR_CHECK(xrStringToPath(instance, kHandPaths[h], &handPaths[h]));
  for (const ActionInfo& a : Actions()) {
    XrActionCreateInfo ci{XR_TYPE_ACTION_CREATE_INFO};
    std::snprintf(ci.actionName, XR_MAX_ACTION_NAME_SIZE, "%s", a.name);
    std::snprintf(ci.localizedActionName, XR_MAX_LOCALIZED_ACTION_NAME_SIZE, "%s", a.localizedName);
    switch (a.id) {
      case ActionId::kGripPose: ci.actionType = XR_ACTION_TYPE_POSE_INPUT; break;
      case ActionId::kTrigger:
      case ActionId::kSqueeze: ci.actionType = XR_ACTION_TYPE_FLOAT_INPUT; break;
      case ActionId::kHaptic: ci.actionType = XR_ACTION_TYPE_VIBRATION_OUTPUT; break;
      default: ci.actionType = XR_ACTION_TYPE_BOOLEAN_INPUT; break;
    }
    ci.countSubactionPaths = kHandCount;
    ci.subactionPaths = handPaths.data();
    SPHXR_XR_CHECK(xrCreateAction(actionSet, &ci, &actions[size_t(a.id)]));
  }
  // Suggest per profile, from the one table. A runtime that does not know a profile answers
  // XR_ERROR_PATH_UNSUPPORTED for it: logged, the others still count.
  auto table = SuggestedBindings();
  for (size_t i = 0; i < table.size();) {
    const char* profile = table[i].profile;
    std::vector<XrActionSuggestedBinding> bindings;
    for (; i < table.size() && std::strcmp(table[i].profile, profile) == 0; ++i) {
      for (int h = 0; h < kHandCount; ++h) {
        if (!(table[i].hands & (1u << h))) continue;
        XrPath path = XR_NULL_PATH;
        std::string full = std::string(kHandPaths[h]) + table[i].suffix;
        SPHXR_XR_CHECK(xrStringToPath(instance, full.c_str(), &path));
        bindings.push_back({action(table[i].action), path});
      }
    }
    XrInteractionProfileSuggestedBinding sb{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    SPHXR_XR_CHECK(xrStringToPath(instance, profile, &sb.interactionProfile));
    sb.countSuggestedBindings = uint32_t(bindings.size());
    sb.suggestedBindings = bindings.data();
    XrResult r = xrSuggestInteractionProfileBindings(instance, &sb);
    if (r == XR_ERROR_PATH_UNSUPPORTED)
      SPHXR_LOG_WARN("OpenXR: runtime '%s' does not support %s; its bindings are skipped", runtimeName.c_str(), profile);
    else
      SPHXR_XR_CHECK_RESULT(xrSuggestInteractionProfileBindings, r);
  }
  for (int h = 0; h < kHandCount; ++h) {
    XrActionSpaceCreateInfo ci{XR_TYPE_ACTION_SPACE_CREATE_INFO};
    ci.action = action(ActionId::kGripPose);
    ci.subactionPath = handPaths[h];
    ci.poseInActionSpace = ToXr(Pose{});
    SPHXR_XR_CHECK(xrCreateActionSpace(session, &ci, &gripSpaces[h]));
  }
  XrSessionActionSetsAttachInfo ai{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  ai.countActionSets = 1;
  ai.actionSets = &actionSet;
  SPHXR_XR_CHECK(xrAttachSessionActionSets(session, &ai));
  return Status::Ok();
}

Status Session::Impl::CreateSwapchains() {
  uint32_t count = 0;
  SPHXR_XR_CHECK(xrEnumerateSwapchainFormats(session, 0, &count, nullptr));
  std::vector<int64_t> formats(count);
  SPHXR_XR_CHECK(xrEnumerateSwapchainFormats(session, count, &count, formats.data()));
  // The runtime lists formats in its order of preference: take its first sRGB colour format.
  for (int64_t f : formats)
    if (f == gl::kSrgb8Alpha8 || f == gl::kSrgb8) {
      colorFormat = f;
      break;
    }
  if (!colorFormat) {
    for (int64_t f : formats)
      if (f == gl::kRgba8) colorFormat = f;
    if (!colorFormat) return Status::Error("OpenXR: the runtime offers neither an sRGB nor an RGBA8 swapchain format");
    SPHXR_LOG_WARN("OpenXR: the runtime offers no sRGB swapchain format; using RGBA8 (colours will look too dark)");
  }
  if (options.wantDepth)
    for (int64_t f : formats)
      if (f == gl::kDepth32F || f == gl::kDepth24 || f == gl::kDepth16) {
        depthFormat = f;
        break;
      }

  uint32_t viewCount = 0;
  SPHXR_XR_CHECK(xrEnumerateViewConfigurationViews(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0,
                                                   &viewCount, nullptr));
  if (viewCount != 2) return Status::Error(Format("OpenXR: expected 2 stereo views, the runtime has %u", viewCount));
  std::vector<XrViewConfigurationView> views(viewCount, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  SPHXR_XR_CHECK(xrEnumerateViewConfigurationViews(instance, systemId, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO,
                                                   viewCount, &viewCount, views.data()));
  auto images = [&](XrSwapchain sc, std::vector<uint32_t>* out) -> Status {
    uint32_t n = 0;
    SPHXR_XR_CHECK(xrEnumerateSwapchainImages(sc, 0, &n, nullptr));
    std::vector<XrSwapchainImageOpenGLKHR> imgs(n, {XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR});
    SPHXR_XR_CHECK(xrEnumerateSwapchainImages(sc, n, &n, reinterpret_cast<XrSwapchainImageBaseHeader*>(imgs.data())));
    for (auto& i : imgs) out->push_back(i.image);
    return Status::Ok();
  };
  for (int e = 0; e < 2; ++e) {
    Eye& eye = eyes[size_t(e)];
    eye.width = int(views[size_t(e)].recommendedImageRectWidth);
    eye.height = int(views[size_t(e)].recommendedImageRectHeight);
    XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    ci.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_SAMPLED_BIT;
    ci.format = colorFormat;
    ci.sampleCount = 1;
    ci.width = uint32_t(eye.width);
    ci.height = uint32_t(eye.height);
    ci.faceCount = 1;
    ci.arraySize = 1;
    ci.mipCount = 1;
    SPHXR_XR_CHECK(xrCreateSwapchain(session, &ci, &eye.color));
    if (Status s = images(eye.color, &eye.colorImages); !s) return s;
    if (depthFormat) {
      ci.usageFlags = XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
      ci.format = depthFormat;
      SPHXR_XR_CHECK(xrCreateSwapchain(session, &ci, &eye.depth));
      if (Status s = images(eye.depth, &eye.depthImages); !s) return s;
    } else if (options.wantDepth) {
      gl.GenTextures(1, &eye.ownDepth);
      gl.BindTexture(gl::kTexture2D, eye.ownDepth);
      gl.TexImage2D(gl::kTexture2D, 0, int(gl::kDepth24), eye.width, eye.height, 0, gl::kDepthComponent, gl::kFloat,
                    nullptr);
      gl.BindTexture(gl::kTexture2D, 0);
    }
    gl.GenFramebuffers(1, &eye.framebuffer);
  }
  return Status::Ok();
}

void Session::Impl::Destroy() {
  for (Eye& eye : eyes) {
    if (eye.framebuffer) gl.DeleteFramebuffers(1, &eye.framebuffer);
    if (eye.ownDepth) gl.DeleteTextures(1, &eye.ownDepth);
    if (eye.color) xrDestroySwapchain(eye.color);
    if (eye.depth) xrDestroySwapchain(eye.depth);
    eye = Eye{};
  }
  for (XrSpace& s : gripSpaces)
    if (s) xrDestroySpace(s), s = XR_NULL_HANDLE;
  if (viewSpace) xrDestroySpace(viewSpace), viewSpace = XR_NULL_HANDLE;
  if (playSpace) xrDestroySpace(playSpace), playSpace = XR_NULL_HANDLE;
  if (actionSet) xrDestroyActionSet(actionSet), actionSet = XR_NULL_HANDLE;
  if (session) xrDestroySession(session), session = XR_NULL_HANDLE;
  if (instance) xrDestroyInstance(instance), instance = XR_NULL_HANDLE;
}

Status Session::Create(const SessionOptions& options, const GraphicsBinding& binding, std::unique_ptr<Session>* out) {
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->binding = binding;
  if (!binding.getProcAddress) return Status::Error("OpenXR: GraphicsBinding::getProcAddress is not set");
  if (!(std::isfinite(options.nearZ) && std::isfinite(options.farZ) && options.nearZ > 0 && options.farZ > options.nearZ))
    return Status::Error(Format("OpenXR: the clip planes need 0 < near < far (near %g m, far %g m)", options.nearZ,
                                options.farZ));
  if (!(options.hapticPulseSeconds > 0 && options.hapticPulseSeconds <= 10))
    return Status::Error(Format("OpenXR: the haptic pulse must last (0, 10] s, not %g s", options.hapticPulseSeconds));
  const char* missing = nullptr;
  if (!impl->gl.Load(binding.getProcAddress, &missing))
    return Status::Error(Format("OpenXR: the GL context lacks %s", missing));
  PlatformBinding platform;
  Status s = MakePlatformBinding(binding, &platform);
  if (s) s = impl->CreateInstance();
  if (s) s = impl->CreateSessionAndSpaces(platform);
  if (s) s = impl->CreateActions();
  if (s) s = impl->CreateSwapchains();
  if (!s) {
    impl->Destroy();
    return s;
  }
  SPHXR_LOG_INFO("OpenXR: runtime '%s', %dx%d per eye, colour format 0x%llx, depth format 0x%llx, %s space",
                 impl->runtimeName.c_str(), impl->eyes[0].width, impl->eyes[0].height,
                 (unsigned long long)impl->colorFormat, (unsigned long long)impl->depthFormat,
                 impl->playType == XR_REFERENCE_SPACE_TYPE_STAGE ? "stage" : "local");
  out->reset(new Session(std::move(impl)));
  return Status::Ok();
}

Session::Session(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Session::~Session() { m_impl->Destroy(); }

EventResult Session::PollEvents() {
  Impl& m = *m_impl;
  EventResult result;
  auto finish = [&]() {
    result.state = m.state;
    result.running = m.running && !m.exited;
    result.exit = m.exited;
    result.lost = m.lost;
    result.message = m.exitMessage;
    return result;
  };
  if (m.exited) return finish();
  if (m.lost) {  // a call answered SESSION_LOST / INSTANCE_LOST before the event arrived
    m.exited = true;
    if (m.exitMessage.empty()) m.exitMessage = "OpenXR session lost";
    return finish();
  }
  XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
  while (true) {
    event = {XR_TYPE_EVENT_DATA_BUFFER};
    XrResult r = xrPollEvent(m.instance, &event);
    if (r == XR_EVENT_UNAVAILABLE) break;
    if (XR_FAILED(r)) {
      m.exited = true;
      m.lost = IsLoss(r);
      m.exitMessage = XrFailure("xrPollEvent", r, __FILE__, __LINE__).message();
      break;
    }
    switch (event.type) {
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        m.lost = m.exited = true;
        m.running = false;
        m.exitMessage = "OpenXR instance lost (the runtime is going away)";
        break;
      case XR_TYPE_EVENT_DATA_EVENTS_LOST:
        SPHXR_LOG_WARN("OpenXR: the runtime dropped %u events",
                       reinterpret_cast<XrEventDataEventsLost&>(event).lostEventCount);
        break;
      case XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED:
        SPHXR_LOG_INFO("OpenXR: controllers: left %s, right %s", interactionProfile(Hand::kLeft).c_str(),
                       interactionProfile(Hand::kRight).c_str());
        break;
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        auto& e = reinterpret_cast<XrEventDataSessionStateChanged&>(event);
        if (e.session != m.session) break;
        m.state = FromXr(e.state);
        result.transitions.push_back(m.state);
        SPHXR_LOG_DEBUG("OpenXR: session state %s", SessionStateName(m.state));
        if (e.state == XR_SESSION_STATE_READY) {
          XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
          bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
          XrResult br = xrBeginSession(m.session, &bi);
          if (XR_FAILED(br)) {
            m.exited = true;
            m.lost = IsLoss(br);
            m.exitMessage = XrFailure("xrBeginSession", br, __FILE__, __LINE__).message();
          } else {
            m.running = true;
          }
        } else if (e.state == XR_SESSION_STATE_STOPPING) {
          m.running = false;
          XrResult er = xrEndSession(m.session);
          if (XR_FAILED(er)) {
            m.exited = true;
            m.lost = IsLoss(er);
            m.exitMessage = XrFailure("xrEndSession", er, __FILE__, __LINE__).message();
          }
        } else if (e.state == XR_SESSION_STATE_EXITING) {
          m.running = false;
          m.exited = true;
          m.exitMessage = "OpenXR session ended";
        } else if (e.state == XR_SESSION_STATE_LOSS_PENDING) {
          m.running = false;
          m.exited = m.lost = true;
          m.exitMessage = "OpenXR session lost (the headset went away)";
        }
        break;
      }
      default: break;
    }
    if (m.exited) break;
  }
  return finish();
}

Status Session::Impl::RecentreAt(XrTime time) {
  XrReferenceSpaceCreateInfo si{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  si.referenceSpaceType = playType;
  si.poseInReferenceSpace = ToXr(Pose{});
  XrSpace raw = XR_NULL_HANDLE;
  SPHXR_XR_CHECK(xrCreateReferenceSpace(session, &si, &raw));
  XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
  XrResult r = xrLocateSpace(viewSpace, raw, time, &loc);
  xrDestroySpace(raw);
  SPHXR_XR_CHECK_RESULT(xrLocateSpace, r);
  const XrSpaceLocationFlags need = XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  if ((loc.locationFlags & need) != need) {
    SPHXR_LOG_WARN("OpenXR: recentre ignored: the head is not tracked");
    return Status::Ok();
  }
  Pose head = FromXr(loc.pose);
  Vec3 forward = Rotate(head.orientation, {0, 0, -1});
  float yaw = std::atan2(-forward.x, -forward.z);  // rotation about +y taking -z to the head's heading
  si.poseInReferenceSpace = ToXr(Pose{{head.position.x, 0, head.position.z}, AxisAngle({0, 1, 0}, yaw)});
  XrSpace recentred = XR_NULL_HANDLE;
  SPHXR_XR_CHECK(xrCreateReferenceSpace(session, &si, &recentred));
  xrDestroySpace(playSpace);
  playSpace = recentred;
  return Status::Ok();
}

Status Session::Impl::SyncHands(FrameInfo* info, bool* recentre) {
  XrActiveActionSet active{actionSet, XR_NULL_PATH};
  XrActionsSyncInfo si{XR_TYPE_ACTIONS_SYNC_INFO};
  si.countActiveActionSets = 1;
  si.activeActionSets = &active;
  XrResult r = xrSyncActions(session, &si);
  if (IsLoss(r)) {
    lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrSyncActions, r);
  auto pressed = [&](ActionId id, int hand, bool* out) -> Status {
    XrActionStateGetInfo gi{XR_TYPE_ACTION_STATE_GET_INFO};
    gi.action = action(id);
    gi.subactionPath = handPaths[size_t(hand)];
    XrActionStateBoolean st{XR_TYPE_ACTION_STATE_BOOLEAN};
    SPHXR_XR_CHECK(xrGetActionStateBoolean(session, &gi, &st));
    *out = *out || (st.isActive && st.changedSinceLastSync && st.currentState);
    return Status::Ok();
  };
  for (int h = 0; h < kHandCount; ++h) {
    if (Status s = pressed(ActionId::kRecentre, h, recentre); !s) return s;
    if (Status s = pressed(ActionId::kReset, h, &info->resetRequested); !s) return s;
    if (Status s = pressed(ActionId::kSaveState, h, &info->saveRequested); !s) return s;
  }
  if (*recentre) {
    if (Status s = RecentreAt(info->predictedDisplayTimeNs); !s) return s;
    info->recentred = true;
  }
  for (int h = 0; h < kHandCount; ++h) {
    HandState& hand = info->hands[size_t(h)];
    XrActionStateGetInfo gi{XR_TYPE_ACTION_STATE_GET_INFO};
    gi.subactionPath = handPaths[size_t(h)];
    XrActionStateFloat fs{XR_TYPE_ACTION_STATE_FLOAT};
    gi.action = action(ActionId::kTrigger);
    SPHXR_XR_CHECK(xrGetActionStateFloat(session, &gi, &fs));
    hand.trigger = fs.isActive ? std::clamp(fs.currentState, 0.0f, 1.0f) : 0.0f;
    gi.action = action(ActionId::kSqueeze);
    fs = {XR_TYPE_ACTION_STATE_FLOAT};
    SPHXR_XR_CHECK(xrGetActionStateFloat(session, &gi, &fs));
    hand.squeeze = fs.isActive ? std::clamp(fs.currentState, 0.0f, 1.0f) : 0.0f;
    XrActionStatePose ps{XR_TYPE_ACTION_STATE_POSE};
    gi.action = action(ActionId::kGripPose);
    SPHXR_XR_CHECK(xrGetActionStatePose(session, &gi, &ps));
    hand.active = ps.isActive;
    if (!ps.isActive) continue;
    XrSpaceVelocity vel{XR_TYPE_SPACE_VELOCITY};
    XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION, &vel};
    SPHXR_XR_CHECK(xrLocateSpace(gripSpaces[size_t(h)], playSpace, info->predictedDisplayTimeNs, &loc));
    const auto f = loc.locationFlags;
    hand.poseValid = (f & XR_SPACE_LOCATION_POSITION_VALID_BIT) && (f & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT);
    hand.tracked = (f & XR_SPACE_LOCATION_POSITION_TRACKED_BIT) && (f & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT);
    if (hand.poseValid) hand.grip = FromXr(loc.pose);
    hand.velocityValid = vel.velocityFlags & XR_SPACE_VELOCITY_LINEAR_VALID_BIT;
    if (hand.velocityValid) hand.linearVelocity = FromXr(vel.linearVelocity);
    if (vel.velocityFlags & XR_SPACE_VELOCITY_ANGULAR_VALID_BIT) hand.angularVelocity = FromXr(vel.angularVelocity);
  }
  return Status::Ok();
}

Status Session::Impl::RenderEyes(const FrameInfo& info, const RenderEyeFn& renderEye,
                                 std::array<XrCompositionLayerProjectionView, 2>* layerViews, bool* rendered) {
  *rendered = false;
  XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
  li.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  li.displayTime = info.predictedDisplayTimeNs;
  li.space = playSpace;
  XrViewState vs{XR_TYPE_VIEW_STATE};
  std::array<XrView, 2> views{{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};
  uint32_t count = 0;
  XrResult r = xrLocateViews(session, &li, &vs, 2, &count, views.data());
  if (IsLoss(r)) {
    lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrLocateViews, r);
  const XrViewStateFlags need = XR_VIEW_STATE_POSITION_VALID_BIT | XR_VIEW_STATE_ORIENTATION_VALID_BIT;
  if ((vs.viewStateFlags & need) != need) return Status::Ok();  // no head pose: submit nothing

  GlFunctions::GLint prevFramebuffer = 0;
  gl.GetIntegerv(gl::kDrawFramebufferBinding, &prevFramebuffer);
  const bool srgb = colorFormat == gl::kSrgb8Alpha8 || colorFormat == gl::kSrgb8;
  const bool srgbWasOn = gl.IsEnabled(gl::kFramebufferSrgb);
  for (int e = 0; e < 2; ++e) {
    Eye& eye = eyes[size_t(e)];
    XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
    XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
    wi.timeout = XR_INFINITE_DURATION;
    XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    uint32_t colorIndex = 0, depthIndex = 0;
    SPHXR_XR_CHECK(xrAcquireSwapchainImage(eye.color, &ai, &colorIndex));
    SPHXR_XR_CHECK(xrWaitSwapchainImage(eye.color, &wi));
    if (eye.depth) {
      SPHXR_XR_CHECK(xrAcquireSwapchainImage(eye.depth, &ai, &depthIndex));
      SPHXR_XR_CHECK(xrWaitSwapchainImage(eye.depth, &wi));
    }
    EyeView ev;
    ev.eye = e;
    ev.pose = FromXr(views[size_t(e)].pose);
    const XrFovf& f = views[size_t(e)].fov;
    ev.fov = {f.angleLeft, f.angleRight, f.angleUp, f.angleDown};
    ev.view = ViewMatrix(ev.pose);
    ev.projection = ProjectionMatrix(ev.fov, options.nearZ, options.farZ);
    ev.framebuffer = eye.framebuffer;
    ev.colorTexture = eye.colorImages[colorIndex];
    ev.depthTexture = eye.depth ? eye.depthImages[depthIndex] : eye.ownDepth;
    ev.width = eye.width;
    ev.height = eye.height;
    ev.srgb = srgb;
    gl.BindFramebuffer(gl::kFramebuffer, eye.framebuffer);
    gl.FramebufferTexture2D(gl::kFramebuffer, gl::kColorAttachment0, gl::kTexture2D, ev.colorTexture, 0);
    gl.FramebufferTexture2D(gl::kFramebuffer, gl::kDepthAttachment, gl::kTexture2D, ev.depthTexture, 0);
    Status status = Status::Ok();
    if (gl.CheckFramebufferStatus(gl::kFramebuffer) != gl::kFramebufferComplete) {
      status = Status::Error("OpenXR: the eye framebuffer is incomplete");
    } else {
      gl.Viewport(0, 0, eye.width, eye.height);
      if (srgb) gl.Enable(gl::kFramebufferSrgb);  // the renderer writes linear colour
      renderEye(info, ev);
      if (srgb && !srgbWasOn) gl.Disable(gl::kFramebufferSrgb);
    }
    gl.BindFramebuffer(gl::kFramebuffer, GlFunctions::GLuint(prevFramebuffer));
    SPHXR_XR_CHECK(xrReleaseSwapchainImage(eye.color, &ri));
    if (eye.depth) SPHXR_XR_CHECK(xrReleaseSwapchainImage(eye.depth, &ri));
    if (!status) return status;
    XrCompositionLayerProjectionView& lv = (*layerViews)[size_t(e)];
    lv = {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW};
    lv.pose = views[size_t(e)].pose;
    lv.fov = views[size_t(e)].fov;
    lv.subImage.swapchain = eye.color;
    lv.subImage.imageRect = {{0, 0}, {eye.width, eye.height}};
    lv.subImage.imageArrayIndex = 0;
  }
  *rendered = true;
  return Status::Ok();
}

Status Session::Frame(const UpdateFn& update, const RenderEyeFn& renderEye) {
  Impl& m = *m_impl;
  if (!m.running || m.exited || m.lost) return Status::Ok();  // PollEvents says why; nothing to do
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  m.timings = {};
  auto t0 = Clock::now();
  XrFrameWaitInfo wi{XR_TYPE_FRAME_WAIT_INFO};
  XrFrameState fs{XR_TYPE_FRAME_STATE};
  XrResult r = xrWaitFrame(m.session, &wi, &fs);
  auto t1 = Clock::now();
  m.timings.waitMs = ms(t0, t1);
  if (IsLoss(r)) {
    m.lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrWaitFrame, r);
  FrameInfo info;
  info.predictedDisplayTimeNs = fs.predictedDisplayTime;
  info.displayPeriodNs = fs.predictedDisplayPeriod;
  info.shouldRender = fs.shouldRender;
  info.frameIndex = m.frameIndex++;
  m.lastDisplayTime = fs.predictedDisplayTime;
  bool recentre = false;
  Status status = m.SyncHands(&info, &recentre);
  auto t2 = Clock::now();
  m.timings.syncMs = ms(t1, t2);
  if (status && !m.lost && update) update(info);
  auto t3 = Clock::now();
  m.timings.updateMs = ms(t2, t3);

  XrFrameBeginInfo bi{XR_TYPE_FRAME_BEGIN_INFO};
  r = xrBeginFrame(m.session, &bi);
  if (IsLoss(r)) {
    m.lost = true;
    return status;
  }
  SPHXR_XR_CHECK_RESULT(xrBeginFrame, r);
  // From here xrEndFrame is always called, whatever happens while drawing.
  std::array<XrCompositionLayerProjectionView, 2> views{};
  bool rendered = false;
  if (status && !m.lost && info.shouldRender && renderEye) status = m.RenderEyes(info, renderEye, &views, &rendered);
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  layer.space = m.playSpace;
  layer.viewCount = 2;
  layer.views = views.data();
  const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = fs.predictedDisplayTime;
  ei.environmentBlendMode = m.blendMode;
  ei.layerCount = rendered ? 1 : 0;
  ei.layers = rendered ? layers : nullptr;
  auto t4 = Clock::now();
  m.timings.renderMs = ms(t3, t4);
  r = xrEndFrame(m.session, &ei);
  m.timings.endMs = ms(t4, Clock::now());
  if (IsLoss(r)) {
    m.lost = true;
    return status;
  }
  if (!status) return status;
  SPHXR_XR_CHECK_RESULT(xrEndFrame, r);
  return Status::Ok();
}

Status Session::ApplyHaptics(Hand hand, float amplitude) {
  Impl& m = *m_impl;
  if (!m.running || m.lost) return Status::Ok();
  XrHapticActionInfo hi{XR_TYPE_HAPTIC_ACTION_INFO};
  hi.action = m.action(ActionId::kHaptic);
  hi.subactionPath = m.handPaths[size_t(hand)];
  amplitude = std::isfinite(amplitude) ? std::clamp(amplitude, 0.0f, 1.0f) : 0.0f;
  XrResult r;
  if (amplitude <= 0.0f) {
    r = xrStopHapticFeedback(m.session, &hi);
  } else {
    XrHapticVibration v{XR_TYPE_HAPTIC_VIBRATION};
    v.amplitude = amplitude;
    v.duration = XrDuration(double(m.options.hapticPulseSeconds) * 1e9);
    v.frequency = XR_FREQUENCY_UNSPECIFIED;
    r = xrApplyHapticFeedback(m.session, &hi, reinterpret_cast<const XrHapticBaseHeader*>(&v));
  }
  if (IsLoss(r)) {
    m.lost = true;
    return Status::Ok();
  }
  if (XR_FAILED(r))
    return XrFailure(amplitude <= 0.0f ? "xrStopHapticFeedback" : "xrApplyHapticFeedback", r, __FILE__, __LINE__);
  return Status::Ok();
}

Status Session::Recentre() {
  Impl& m = *m_impl;
  if (!m.running || m.lost || !m.lastDisplayTime) return Status::Error("OpenXR: recentre needs a running session");
  return m.RecentreAt(m.lastDisplayTime);
}

Status Session::RequestExit() {
  Impl& m = *m_impl;
  if (!m.running || m.lost) return Status::Ok();
  XrResult r = xrRequestExitSession(m.session);
  if (IsLoss(r)) {
    m.lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrRequestExitSession, r);
  return Status::Ok();
}

SessionState Session::state() const { return m_impl->state; }
const FrameTimings& Session::lastFrameTimings() const { return m_impl->timings; }
std::string Session::runtimeName() const { return m_impl->runtimeName; }
int Session::eyeWidth() const { return m_impl->eyes[0].width; }
int Session::eyeHeight() const { return m_impl->eyes[0].height; }
int64_t Session::colorFormat() const { return m_impl->colorFormat; }
int64_t Session::depthFormat() const { return m_impl->depthFormat; }

std::string Session::interactionProfile(Hand hand) const {
  const Impl& m = *m_impl;
  XrInteractionProfileState st{XR_TYPE_INTERACTION_PROFILE_STATE};
  if (XR_FAILED(xrGetCurrentInteractionProfile(m.session, m.handPaths[size_t(hand)], &st)) ||
      st.interactionProfile == XR_NULL_PATH)
    return "none";
  char buffer[XR_MAX_PATH_LENGTH];
  uint32_t n = 0;
  if (XR_FAILED(xrPathToString(m.instance, st.interactionProfile, sizeof buffer, &n, buffer))) return "?";
  return buffer;
}

}  // namespace sphxr::xr
