// Creating an xr::Session: the runtime probe, instance, HMD system and blend mode, the session with
// its platform binding, the play and view reference spaces (and recentring, which replaces the play
// space), then actions and swapchains in that order; and the teardown that undoes it all.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "openxr_include.h"
#include "session_impl.h"
#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"

namespace sphxr::xr {

namespace {

/// XR_RUNTIME_JSON, when set, names a regular file under kMaxManifestBytes, checked before the loader
/// reads it: /dev/zero grew the loader's memory without end, a FIFO blocked it for ever.
Status CheckRuntimeManifest() {
  constexpr long long kMaxManifestBytes = 1 << 20;
  const char* path = std::getenv("XR_RUNTIME_JSON");
  if (!path || !*path) return Status::Ok();
  struct stat st {};
  std::string why;
  if (stat(path, &st) != 0) return Status::Ok();  // missing: the loader's own answer (no runtime)
  if (!S_ISREG(st.st_mode))
    why = "not a regular file";
  else if (st.st_size > kMaxManifestBytes)
    why = Format("%lld bytes, more than a manifest's %lld", static_cast<long long>(st.st_size), kMaxManifestBytes);
  if (why.empty()) return Status::Ok();
  return Status::Error("no OpenXR runtime available (XR_RUNTIME_JSON=" + ShowText(path) + " is " + why +
                       "): point XR_RUNTIME_JSON at a runtime's manifest; docs/dev/xr.md shows the simulated headset");
}

}  // namespace

Status ProbeRuntime() {
  if (Status s = CheckRuntimeManifest(); !s) return s;
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
  // Each view's depth goes to the compositor with its colour (XR_KHR_composition_layer_depth) when the
  // runtime offers it: reprojection then moves near things (the water, the paddles) by their own depth.
  uint32_t extCount = 0;
  SPHXR_XR_CHECK(xrEnumerateInstanceExtensionProperties(nullptr, 0, &extCount, nullptr));
  std::vector<XrExtensionProperties> offered(extCount, {XR_TYPE_EXTENSION_PROPERTIES});
  SPHXR_XR_CHECK(xrEnumerateInstanceExtensionProperties(nullptr, extCount, &extCount, offered.data()));
  depthLayerOffered = options.wantDepth &&
                      std::any_of(offered.begin(), offered.end(), [](const XrExtensionProperties& e) {
                        return std::strcmp(e.extensionName, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME) == 0;
                      });
  const char* extNames[] = {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME};
  ci.enabledExtensionCount = depthLayerOffered ? 2 : 1;
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

Status Session::Recentre() {
  Impl& m = *m_impl;
  if (!m.running || m.lost || !m.lastDisplayTime) return Status::Error("OpenXR: recentre needs a running session");
  return m.RecentreAt(m.lastDisplayTime);
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

}  // namespace sphxr::xr
