#pragma once
// Session::Impl, the state behind xr::Session, and the small conversions its source files share.
// The members are defined by concept: session_create.cpp (instance, system, session, spaces,
// teardown), session_actions.cpp (actions, hands, haptics), session_swapchains.cpp (swapchains and
// GL entry points), session_frame.cpp (the frame loop) and session.cpp (the state machine).
#include <array>
#include <string>
#include <vector>

#include "action_bindings.h"
#include "gl_functions.h"
#include "graphics_binding.h"
#include "openxr_include.h"
#include "sphxr/xr/session.h"

namespace sphxr::xr {

inline Pose FromXr(const XrPosef& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z}};
}
inline XrPosef ToXr(const Pose& p) {
  return {{p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w},
          {p.position.x, p.position.y, p.position.z}};
}
inline Vec3 FromXr(const XrVector3f& v) { return {v.x, v.y, v.z}; }

inline bool IsLoss(XrResult r) { return r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST; }

inline constexpr const char* kHandPaths[kHandCount] = {"/user/hand/left", "/user/hand/right"};

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
  bool depthLayerOffered = false;  // XR_KHR_composition_layer_depth enabled on the instance
  std::array<XrCompositionLayerDepthInfoKHR, 2> depthInfos{};  // chained to the layer's views until xrEndFrame
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
  void LayerView(int e, const XrView& view, XrCompositionLayerProjectionView* out);
  void OnSessionState(XrSessionState next);  // begin, end, exit or loss (session.cpp)
  Status RenderEyes(const FrameInfo& info, const RenderEyeFn& renderEye,
                    std::array<XrCompositionLayerProjectionView, 2>* views, bool* rendered);
  Status RecentreAt(XrTime time);
  void Destroy();
};

}  // namespace sphxr::xr
