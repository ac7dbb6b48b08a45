#pragma once
// The simulated headset: an OpenXR 1.0 runtime of our own, loaded by the Khronos loader through
// its manifest (XR_RUNTIME_JSON). Private to the runtime library; see docs/dev/xr.md for its settings.
//
// One mutex guards everything: the runtime serves one application with one session, and nothing in
// it is hot. Handles are pointers to the objects below, each starting with a tag checked on entry.
#define XR_USE_PLATFORM_XLIB
#define XR_USE_GRAPHICS_API_OPENGL
#include <GL/gl.h>
#include <GL/glx.h>
#include <X11/Xlib.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <cstdio>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "pose_script.h"

namespace sphxr::xr::simrt {

/// Settings, read from the environment at xrCreateInstance (docs/dev/xr.md lists them).
struct Config {
  double rateHz = 90.0;
  int eyeWidth = 1024, eyeHeight = 1024;
  float ipdMetres = 0.064f;
  std::string profile = "/interaction_profiles/khr/simple_controller";
  std::string poseScriptPath;
  std::string captureDir;
  int captureEvery = 1;
  std::string hapticsLogPath;
  long exitAfterFrames = -1;          // runtime-initiated exit (STOPPING) after this many frames
  long loseSessionAfterFrames = -1;   // LOSS_PENDING after this many frames
  long loseInstanceAfterFrames = -1;  // instance loss after this many frames
  bool failSessionCreate = false;     // xrCreateSession answers XR_ERROR_RUNTIME_FAILURE
};

enum class Tag : uint32_t { kInstance = 0x51a1, kSession, kSpace, kActionSet, kAction, kSwapchain, kDead };

struct Session;
struct ActionSet;

struct Action {
  Tag tag = Tag::kAction;
  ActionSet* set = nullptr;
  std::string name;
  XrActionType type{};
  std::vector<XrPath> subactions;
};

struct ActionSet {
  Tag tag = Tag::kActionSet;
  struct Instance* instance = nullptr;
  std::string name;
  bool attached = false;
  std::vector<std::unique_ptr<Action>> actions;
};

struct Instance {
  Tag tag = Tag::kInstance;
  Config config;
  PoseScript script;
  std::vector<std::string> paths;  // XrPath n is paths[n - 1]
  std::unordered_map<std::string, XrPath> pathIds;
  std::deque<XrEventDataBuffer> events;
  std::vector<std::unique_ptr<ActionSet>> actionSets;
  // Suggested bindings: profile path -> (action, binding path).
  std::map<XrPath, std::vector<std::pair<Action*, XrPath>>> suggested;
  bool depthLayersEnabled = false;  // the application enabled XR_KHR_composition_layer_depth
  bool graphicsRequirementsQueried = false;
  bool systemQueried = false;
  bool lost = false;
  Session* session = nullptr;
  FILE* hapticsLog = nullptr;
  bool captureFailed = false;  // a picture could not be written: said once, no more captured
};

struct Space {
  Tag tag = Tag::kSpace;
  Session* session = nullptr;
  bool isAction = false;
  XrReferenceSpaceType referenceType{};
  Action* action = nullptr;
  XrPath subaction = XR_NULL_PATH;
  Pose offset;
};

struct Swapchain {
  Tag tag = Tag::kSwapchain;
  Session* session = nullptr;
  int64_t format = 0;
  uint32_t width = 0, height = 0;
  std::vector<GLuint> textures;
  uint32_t nextIndex = 0;
  std::deque<uint32_t> acquired;  // acquired, not yet released, in order
  bool waited = false;
  int lastReleased = -1;
};

/// Per (action, subaction) state as of the last xrSyncActions.
struct ActionStateCache {
  float value = 0, previous = 0;
  bool active = false;
  XrTime changeTime = 0;
};

struct Session {
  Tag tag = Tag::kSession;
  Instance* instance = nullptr;
  XrGraphicsBindingOpenGLXlibKHR binding{};
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false;
  bool exitRequested = false;
  bool lost = false;
  XrTime periodNs = 0;
  XrTime lastDisplayTime = 0;   // predicted display time handed out by the last xrWaitFrame
  XrTime beginTime = 0;         // xrBeginSession: time zero of the pose script
  bool frameWaited = false, frameBegun = false;
  long framesEnded = 0;
  XrPath currentProfile = XR_NULL_PATH;
  std::vector<ActionSet*> activeSets;  // of the last xrSyncActions
  std::map<std::pair<Action*, XrPath>, ActionStateCache> actionStates;
  std::vector<std::unique_ptr<Space>> spaces;
  std::vector<std::unique_ptr<Swapchain>> swapchains;
  long depthLayersReceived[2] = {0, 0};  // frames whose projection view carried a depth layer, per eye
};

inline constexpr XrSystemId kSystemId = 1;
inline constexpr uint32_t kViewCount = 2;

// Shared between the runtime's source files.
std::mutex& Lock();
XrTime Now();
/// Queues an event for xrPollEvent.
void PushEvent(Instance* inst, const void* event, size_t size);
void PushSessionState(Session* s, XrSessionState state);
/// Walks a running session down to STOPPING (through VISIBLE and SYNCHRONIZED).
void Stop(Session* s);
/// Checks the depth layers chained to a projection layer's views (XR_KHR_composition_layer_depth):
/// XR_SUCCESS, or the error xrEndFrame answers. `views` gets, per view, whether one was there.
XrResult CheckDepthLayers(Session* s, const XrCompositionLayerProjection& layer, bool views[2]);
/// Appends one line per view to <capture dir>/depth_layers.txt: the frame, the eye, whether a depth
/// layer came, its near/far planes and what its image holds (the nearest depth, the share of texels
/// nearer than the far plane).
void RecordDepthLayers(Session* s, const XrCompositionLayerProjection& layer, const bool views[2]);
XrPath InternPath(Instance* inst, const std::string& path);
const std::string* PathString(const Instance* inst, XrPath path);
/// Seconds of the pose script at `time`.
double ScriptSeconds(const Session* s, XrTime time);
/// The world (STAGE) pose of an action's device at `time`; false if the action has no pose binding
/// for `subaction` in the current profile or is not active.
bool ActionPose(Session* s, Action* action, XrPath subaction, XrTime time, Pose* out);
void RecordHaptic(Session* s, Action* action, XrPath subaction, float amplitude, XrDuration duration,
                  float frequency, bool stop);
/// Saves the submitted projection views as PNGs when capture is on (called by xrEndFrame).
void CaptureFrame(Session* s, const XrCompositionLayerProjection& layer);

inline XrPosef ToXr(const Pose& p) {
  return {{p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w},
          {p.position.x, p.position.y, p.position.z}};
}
inline Pose FromXr(const XrPosef& p) {
  return {{p.position.x, p.position.y, p.position.z},
          {p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z}};
}

template <class T>
T* Check(void* handle, Tag tag) {
  auto* t = static_cast<T*>(handle);
  return (t && t->tag == tag) ? t : nullptr;
}

// Entry points, by file; runtime.cpp's xrGetInstanceProcAddr hands them to the loader.
// instance.cpp
XrResult EnumerateInstanceExtensionProperties(const char*, uint32_t, uint32_t*, XrExtensionProperties*);
XrResult CreateInstance(const XrInstanceCreateInfo*, XrInstance*);
XrResult DestroyInstance(XrInstance);
XrResult GetInstanceProperties(XrInstance, XrInstanceProperties*);
XrResult PollEvent(XrInstance, XrEventDataBuffer*);
XrResult ResultToString(XrInstance, XrResult, char*);
XrResult StructureTypeToString(XrInstance, XrStructureType, char*);
XrResult GetSystem(XrInstance, const XrSystemGetInfo*, XrSystemId*);
XrResult GetSystemProperties(XrInstance, XrSystemId, XrSystemProperties*);
XrResult EnumerateEnvironmentBlendModes(XrInstance, XrSystemId, XrViewConfigurationType, uint32_t, uint32_t*,
                                        XrEnvironmentBlendMode*);
XrResult EnumerateViewConfigurations(XrInstance, XrSystemId, uint32_t, uint32_t*, XrViewConfigurationType*);
XrResult GetViewConfigurationProperties(XrInstance, XrSystemId, XrViewConfigurationType,
                                        XrViewConfigurationProperties*);
XrResult EnumerateViewConfigurationViews(XrInstance, XrSystemId, XrViewConfigurationType, uint32_t, uint32_t*,
                                         XrViewConfigurationView*);
XrResult GetOpenGLGraphicsRequirementsKHR(XrInstance, XrSystemId, XrGraphicsRequirementsOpenGLKHR*);
// session.cpp
XrResult CreateSession(XrInstance, const XrSessionCreateInfo*, XrSession*);
XrResult DestroySession(XrSession);
XrResult BeginSession(XrSession, const XrSessionBeginInfo*);
XrResult EndSession(XrSession);
XrResult RequestExitSession(XrSession);
// frame.cpp
XrResult WaitFrame(XrSession, const XrFrameWaitInfo*, XrFrameState*);
XrResult BeginFrame(XrSession, const XrFrameBeginInfo*);
XrResult EndFrame(XrSession, const XrFrameEndInfo*);
// spaces.cpp
XrResult EnumerateReferenceSpaces(XrSession, uint32_t, uint32_t*, XrReferenceSpaceType*);
XrResult CreateReferenceSpace(XrSession, const XrReferenceSpaceCreateInfo*, XrSpace*);
XrResult GetReferenceSpaceBoundsRect(XrSession, XrReferenceSpaceType, XrExtent2Df*);
XrResult CreateActionSpace(XrSession, const XrActionSpaceCreateInfo*, XrSpace*);
XrResult DestroySpace(XrSpace);
XrResult LocateSpace(XrSpace, XrSpace, XrTime, XrSpaceLocation*);
XrResult LocateViews(XrSession, const XrViewLocateInfo*, XrViewState*, uint32_t, uint32_t*, XrView*);
// actions.cpp
XrResult StringToPath(XrInstance, const char*, XrPath*);
XrResult PathToString(XrInstance, XrPath, uint32_t, uint32_t*, char*);
XrResult CreateActionSet(XrInstance, const XrActionSetCreateInfo*, XrActionSet*);
XrResult DestroyActionSet(XrActionSet);
XrResult CreateAction(XrActionSet, const XrActionCreateInfo*, XrAction*);
XrResult DestroyAction(XrAction);
XrResult SuggestInteractionProfileBindings(XrInstance, const XrInteractionProfileSuggestedBinding*);
XrResult AttachSessionActionSets(XrSession, const XrSessionActionSetsAttachInfo*);
XrResult GetCurrentInteractionProfile(XrSession, XrPath, XrInteractionProfileState*);
XrResult GetActionStateBoolean(XrSession, const XrActionStateGetInfo*, XrActionStateBoolean*);
XrResult GetActionStateFloat(XrSession, const XrActionStateGetInfo*, XrActionStateFloat*);
XrResult GetActionStateVector2f(XrSession, const XrActionStateGetInfo*, XrActionStateVector2f*);
XrResult GetActionStatePose(XrSession, const XrActionStateGetInfo*, XrActionStatePose*);
XrResult SyncActions(XrSession, const XrActionsSyncInfo*);
XrResult EnumerateBoundSourcesForAction(XrSession, const XrBoundSourcesForActionEnumerateInfo*, uint32_t,
                                        uint32_t*, XrPath*);
XrResult GetInputSourceLocalizedName(XrSession, const XrInputSourceLocalizedNameGetInfo*, uint32_t, uint32_t*,
                                     char*);
XrResult ApplyHapticFeedback(XrSession, const XrHapticActionInfo*, const XrHapticBaseHeader*);
XrResult StopHapticFeedback(XrSession, const XrHapticActionInfo*);
// swapchain.cpp
XrResult EnumerateSwapchainFormats(XrSession, uint32_t, uint32_t*, int64_t*);
XrResult CreateSwapchain(XrSession, const XrSwapchainCreateInfo*, XrSwapchain*);
XrResult DestroySwapchain(XrSwapchain);
XrResult EnumerateSwapchainImages(XrSwapchain, uint32_t, uint32_t*, XrSwapchainImageBaseHeader*);
XrResult AcquireSwapchainImage(XrSwapchain, const XrSwapchainImageAcquireInfo*, uint32_t*);
XrResult WaitSwapchainImage(XrSwapchain, const XrSwapchainImageWaitInfo*);
XrResult ReleaseSwapchainImage(XrSwapchain, const XrSwapchainImageReleaseInfo*);

/// Two-call idiom helper: writes `count` items via `write(i)` when capacity allows.
template <class F>
XrResult TwoCall(uint32_t capacity, uint32_t* countOut, uint32_t count, F write) {
  if (!countOut) return XR_ERROR_VALIDATION_FAILURE;
  *countOut = count;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < count) return XR_ERROR_SIZE_INSUFFICIENT;
  for (uint32_t i = 0; i < count; ++i) write(i);
  return XR_SUCCESS;
}

/// Entry-point preambles: the handle's object, or the error a runtime answers for a bad or lost handle.
#define SIMRT_INSTANCE(handle, var)                        \
  Instance* var = Check<Instance>(handle, Tag::kInstance); \
  if (!var) return XR_ERROR_HANDLE_INVALID;                \
  if (var->lost) return XR_ERROR_INSTANCE_LOST
#define SIMRT_SESSION(handle, var)                        \
  Session* var = Check<Session>(handle, Tag::kSession);   \
  if (!var) return XR_ERROR_HANDLE_INVALID;               \
  if (var->instance->lost) return XR_ERROR_INSTANCE_LOST; \
  if (var->lost) return XR_ERROR_SESSION_LOST

}  // namespace sphxr::xr::simrt
