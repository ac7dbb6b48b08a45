// Paths, action sets, actions, suggested bindings, action state and haptics of the simulated headset.
//
// The runtime picks one interaction profile (SPHXR_SIM_XR_PROFILE, default the Khronos simple
// controller; the first suggested profile if the application suggested nothing for it) and reads
// each bound input from the scripted device of that hand: a binding path's last components name the
// source (grip/aim pose, trigger or select, squeeze, menu, a/x, b/y, trackpad and thumbstick clicks,
// haptic output).
#include <algorithm>
#include <cstring>

#include "runtime.h"

namespace sphxr::xr::simrt {
namespace {

enum class Source { kNone, kPose, kTrigger, kSqueeze, kMenu, kA, kB, kTrackpad, kThumbstick, kHaptic };

struct Bound {
  Device device;
  Source source;
  bool click = false;  // a .../click source reads 0 or 1
};

/// "/user/hand/left/input/..." -> kLeft and "input/..."; false for a path of no hand.
bool SplitHand(const std::string& path, Device* device, std::string* rest) {
  for (Device d : {Device::kLeft, Device::kRight}) {
    const std::string prefix = d == Device::kLeft ? "/user/hand/left/" : "/user/hand/right/";
    if (path.rfind(prefix, 0) == 0) {
      *device = d;
      *rest = path.substr(prefix.size());
      return true;
    }
  }
  return false;
}

Bound Classify(const std::string& path) {
  Bound b{Device::kHead, Source::kNone};
  std::string rest;
  if (!SplitHand(path, &b.device, &rest)) return b;
  for (const char* p : {"input/grip/pose", "input/grip", "input/aim/pose", "input/aim"})
    if (rest == p) b.source = Source::kPose;
  for (const char* p : {"input/trigger/value", "input/trigger", "input/trigger/click", "input/select/click", "input/select"})
    if (rest == p) b.source = Source::kTrigger;
  for (const char* p : {"input/squeeze/value", "input/squeeze", "input/squeeze/click", "input/squeeze/force"})
    if (rest == p) b.source = Source::kSqueeze;
  if (rest == "input/menu/click" || rest == "input/menu") b.source = Source::kMenu;
  if (rest == "input/a/click" || rest == "input/x/click") b.source = Source::kA;
  if (rest == "input/b/click" || rest == "input/y/click") b.source = Source::kB;
  if (rest == "input/trackpad/click") b.source = Source::kTrackpad;
  if (rest == "input/thumbstick/click") b.source = Source::kThumbstick;
  if (rest == "output/haptic") b.source = Source::kHaptic;
  b.click = rest.size() > 6 && rest.compare(rest.size() - 6, 6, "/click") == 0;
  return b;
}

// The input and output paths each known interaction profile has (OpenXR 1.0, section 6.4 "Interaction
// Profile Paths"), per hand: a real runtime refuses a profile's whole suggestion when one path is not
// the controller's (XR_ERROR_PATH_UNSUPPORTED), and so does this one, so that a binding valid on
// one controller but not on another fails here as on a headset. Components left out name the
// identifier alone (".../input/trigger"), which the spec lets the runtime resolve.
constexpr uint8_t kL = 1, kR = 2, kLR = 3;
struct ProfilePath {
  const char* profile;  // after "/interaction_profiles/"
  uint8_t hands;
  const char* path;  // after "/user/hand/<hand>/"
};
constexpr ProfilePath kProfilePaths[] = {
    {"khr/simple_controller", kLR, "input/select/click"},
    {"khr/simple_controller", kLR, "input/menu/click"},
    {"khr/simple_controller", kLR, "input/grip/pose"},
    {"khr/simple_controller", kLR, "input/aim/pose"},
    {"khr/simple_controller", kLR, "output/haptic"},

    {"oculus/touch_controller", kL, "input/x/click"},
    {"oculus/touch_controller", kL, "input/x/touch"},
    {"oculus/touch_controller", kL, "input/y/click"},
    {"oculus/touch_controller", kL, "input/y/touch"},
    {"oculus/touch_controller", kL, "input/menu/click"},
    {"oculus/touch_controller", kR, "input/a/click"},
    {"oculus/touch_controller", kR, "input/a/touch"},
    {"oculus/touch_controller", kR, "input/b/click"},
    {"oculus/touch_controller", kR, "input/b/touch"},
    {"oculus/touch_controller", kR, "input/system/click"},
    {"oculus/touch_controller", kLR, "input/squeeze/value"},
    {"oculus/touch_controller", kLR, "input/trigger/value"},
    {"oculus/touch_controller", kLR, "input/trigger/touch"},
    {"oculus/touch_controller", kLR, "input/thumbstick/x"},
    {"oculus/touch_controller", kLR, "input/thumbstick/y"},
    {"oculus/touch_controller", kLR, "input/thumbstick/click"},
    {"oculus/touch_controller", kLR, "input/thumbstick/touch"},
    {"oculus/touch_controller", kLR, "input/thumbrest/touch"},
    {"oculus/touch_controller", kLR, "input/grip/pose"},
    {"oculus/touch_controller", kLR, "input/aim/pose"},
    {"oculus/touch_controller", kLR, "output/haptic"},

    {"valve/index_controller", kLR, "input/system/click"},
    {"valve/index_controller", kLR, "input/system/touch"},
    {"valve/index_controller", kLR, "input/a/click"},
    {"valve/index_controller", kLR, "input/a/touch"},
    {"valve/index_controller", kLR, "input/b/click"},
    {"valve/index_controller", kLR, "input/b/touch"},
    {"valve/index_controller", kLR, "input/squeeze/value"},
    {"valve/index_controller", kLR, "input/squeeze/force"},
    {"valve/index_controller", kLR, "input/trigger/click"},
    {"valve/index_controller", kLR, "input/trigger/value"},
    {"valve/index_controller", kLR, "input/trigger/touch"},
    {"valve/index_controller", kLR, "input/thumbstick/x"},
    {"valve/index_controller", kLR, "input/thumbstick/y"},
    {"valve/index_controller", kLR, "input/thumbstick/click"},
    {"valve/index_controller", kLR, "input/thumbstick/touch"},
    {"valve/index_controller", kLR, "input/trackpad/x"},
    {"valve/index_controller", kLR, "input/trackpad/y"},
    {"valve/index_controller", kLR, "input/trackpad/force"},
    {"valve/index_controller", kLR, "input/trackpad/touch"},
    {"valve/index_controller", kLR, "input/grip/pose"},
    {"valve/index_controller", kLR, "input/aim/pose"},
    {"valve/index_controller", kLR, "output/haptic"},

    {"htc/vive_controller", kLR, "input/system/click"},
    {"htc/vive_controller", kLR, "input/squeeze/click"},
    {"htc/vive_controller", kLR, "input/menu/click"},
    {"htc/vive_controller", kLR, "input/trigger/click"},
    {"htc/vive_controller", kLR, "input/trigger/value"},
    {"htc/vive_controller", kLR, "input/trackpad/x"},
    {"htc/vive_controller", kLR, "input/trackpad/y"},
    {"htc/vive_controller", kLR, "input/trackpad/click"},
    {"htc/vive_controller", kLR, "input/trackpad/touch"},
    {"htc/vive_controller", kLR, "input/grip/pose"},
    {"htc/vive_controller", kLR, "input/aim/pose"},
    {"htc/vive_controller", kLR, "output/haptic"},

    {"microsoft/motion_controller", kLR, "input/menu/click"},
    {"microsoft/motion_controller", kLR, "input/squeeze/click"},
    {"microsoft/motion_controller", kLR, "input/trigger/value"},
    {"microsoft/motion_controller", kLR, "input/thumbstick/x"},
    {"microsoft/motion_controller", kLR, "input/thumbstick/y"},
    {"microsoft/motion_controller", kLR, "input/thumbstick/click"},
    {"microsoft/motion_controller", kLR, "input/trackpad/x"},
    {"microsoft/motion_controller", kLR, "input/trackpad/y"},
    {"microsoft/motion_controller", kLR, "input/trackpad/click"},
    {"microsoft/motion_controller", kLR, "input/trackpad/touch"},
    {"microsoft/motion_controller", kLR, "input/grip/pose"},
    {"microsoft/motion_controller", kLR, "input/aim/pose"},
    {"microsoft/motion_controller", kLR, "output/haptic"},
};

bool KnownProfile(const std::string& profile) {
  for (const ProfilePath& p : kProfilePaths)
    if (profile == std::string("/interaction_profiles/") + p.profile) return true;
  return false;
}

/// Whether `path` (/user/hand/<hand>/...) is one of `profile`'s, whole or as an identifier alone.
bool PathOfProfile(const std::string& profile, const std::string& path) {
  Device device = Device::kHead;
  std::string rest;
  if (!SplitHand(path, &device, &rest)) return false;
  const uint8_t hand = device == Device::kLeft ? kL : kR;
  for (const ProfilePath& p : kProfilePaths) {
    if (profile != std::string("/interaction_profiles/") + p.profile || !(p.hands & hand)) continue;
    const std::string known = p.path;
    if (rest == known || known.rfind(rest + "/", 0) == 0) return true;
  }
  return false;
}

XrPath HandPath(Instance* inst, Device d) {
  return InternPath(inst, d == Device::kLeft ? "/user/hand/left" : "/user/hand/right");
}

/// Bindings of `action` in the current profile that belong to `subaction` (any hand if null).
std::vector<std::pair<Bound, XrPath>> Bindings(Session* s, Action* action, XrPath subaction) {
  std::vector<std::pair<Bound, XrPath>> out;
  Instance* inst = s->instance;
  auto it = inst->suggested.find(s->currentProfile);
  if (it == inst->suggested.end()) return out;
  for (auto& [a, path] : it->second) {
    if (a != action) continue;
    Bound b = Classify(*PathString(inst, path));
    if (b.source == Source::kNone) continue;
    if (subaction != XR_NULL_PATH && HandPath(inst, b.device) != subaction) continue;
    out.push_back({b, path});
  }
  return out;
}

float SourceValue(const DeviceSample& d, Bound b) {
  if (b.click) {
    b.click = false;
    return SourceValue(d, b) > 0.5f ? 1.0f : 0.0f;
  }
  switch (b.source) {
    case Source::kTrigger: return d.trigger;
    case Source::kSqueeze: return d.squeeze;
    case Source::kMenu: return d.menu ? 1.0f : 0.0f;
    case Source::kA: return d.a ? 1.0f : 0.0f;
    case Source::kB: return d.b ? 1.0f : 0.0f;
    case Source::kTrackpad: return d.trackpad ? 1.0f : 0.0f;
    case Source::kThumbstick: return d.thumbstick ? 1.0f : 0.0f;
    default: return 0.0f;
  }
}

bool IsSubactionOf(Action* action, XrPath subaction) {
  return subaction == XR_NULL_PATH ||
         std::find(action->subactions.begin(), action->subactions.end(), subaction) != action->subactions.end();
}

template <class State>
XrResult GetState(XrSession handle, const XrActionStateGetInfo* info, XrActionType want, State* state,
                  float* valueOut) {
  SIMRT_SESSION(handle, s);
  Action* action = Check<Action>(info->action, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  if (!action->set->attached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  bool typeOk = action->type == want;
  if (!typeOk) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (!IsSubactionOf(action, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
  auto it = s->actionStates.find({action, info->subactionPath});
  ActionStateCache c = it == s->actionStates.end() ? ActionStateCache{} : it->second;
  state->isActive = c.active ? XR_TRUE : XR_FALSE;
  *valueOut = c.active ? c.value : 0.0f;
  if constexpr (requires { state->changedSinceLastSync; }) {
    state->changedSinceLastSync = (c.active && c.value != c.previous) ? XR_TRUE : XR_FALSE;
    state->lastChangeTime = c.changeTime;
  }
  return XR_SUCCESS;
}

}  // namespace

XrPath InternPath(Instance* inst, const std::string& path) {
  auto it = inst->pathIds.find(path);
  if (it != inst->pathIds.end()) return it->second;
  inst->paths.push_back(path);
  XrPath id = inst->paths.size();
  inst->pathIds.emplace(path, id);
  return id;
}

const std::string* PathString(const Instance* inst, XrPath path) {
  if (path == XR_NULL_PATH || path > inst->paths.size()) return nullptr;
  return &inst->paths[path - 1];
}

XrResult StringToPath(XrInstance handle, const char* str, XrPath* out) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->lost) return XR_ERROR_INSTANCE_LOST;
  std::string s(str);
  if (s.empty() || s[0] != '/' || s.back() == '/' || s.find("//") != std::string::npos)
    return XR_ERROR_PATH_FORMAT_INVALID;
  for (char c : s)
    if (!(std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) || c == '/' ||
          c == '-' || c == '_' || c == '.'))
      return XR_ERROR_PATH_FORMAT_INVALID;
  *out = InternPath(inst, s);
  return XR_SUCCESS;
}

XrResult PathToString(XrInstance handle, XrPath path, uint32_t capacity, uint32_t* count, char* buffer) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  const std::string* s = PathString(inst, path);
  if (!s) return XR_ERROR_PATH_INVALID;
  return TwoCall(capacity, count, uint32_t(s->size() + 1), [&](uint32_t i) { buffer[i] = (*s).c_str()[i]; });
}

XrResult CreateActionSet(XrInstance handle, const XrActionSetCreateInfo* info, XrActionSet* out) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->lost) return XR_ERROR_INSTANCE_LOST;
  for (auto& set : inst->actionSets)
    if (set->name == info->actionSetName) return XR_ERROR_NAME_DUPLICATED;
  auto set = std::make_unique<ActionSet>();
  set->instance = inst;
  set->name = info->actionSetName;
  *out = reinterpret_cast<XrActionSet>(set.get());
  inst->actionSets.push_back(std::move(set));
  return XR_SUCCESS;
}

XrResult DestroyActionSet(XrActionSet handle) {
  std::lock_guard lock(Lock());
  ActionSet* set = Check<ActionSet>(handle, Tag::kActionSet);
  if (!set) return XR_ERROR_HANDLE_INVALID;
  // Actions stay alive while a session may still reference them (the spec lets sessions keep using
  // attached sets); they are marked dead and freed with the instance.
  set->tag = Tag::kDead;
  for (auto& a : set->actions) a->tag = Tag::kDead;
  return XR_SUCCESS;
}

XrResult CreateAction(XrActionSet handle, const XrActionCreateInfo* info, XrAction* out) {
  std::lock_guard lock(Lock());
  ActionSet* set = Check<ActionSet>(handle, Tag::kActionSet);
  if (!set) return XR_ERROR_HANDLE_INVALID;
  if (set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
  for (auto& a : set->actions)
    if (a->name == info->actionName) return XR_ERROR_NAME_DUPLICATED;
  auto action = std::make_unique<Action>();
  action->set = set;
  action->name = info->actionName;
  action->type = info->actionType;
  for (uint32_t i = 0; i < info->countSubactionPaths; ++i) {
    const std::string* p = PathString(set->instance, info->subactionPaths[i]);
    if (!p || (*p != "/user/hand/left" && *p != "/user/hand/right" && *p != "/user/head" && *p != "/user/gamepad"))
      return XR_ERROR_PATH_UNSUPPORTED;
    action->subactions.push_back(info->subactionPaths[i]);
  }
  *out = reinterpret_cast<XrAction>(action.get());
  set->actions.push_back(std::move(action));
  return XR_SUCCESS;
}

XrResult DestroyAction(XrAction handle) {
  std::lock_guard lock(Lock());
  Action* action = Check<Action>(handle, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  action->tag = Tag::kDead;  // freed with its set's instance
  return XR_SUCCESS;
}

XrResult SuggestInteractionProfileBindings(XrInstance handle, const XrInteractionProfileSuggestedBinding* info) {
  std::lock_guard lock(Lock());
  Instance* inst = Check<Instance>(handle, Tag::kInstance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (inst->lost) return XR_ERROR_INSTANCE_LOST;
  const std::string* profile = PathString(inst, info->interactionProfile);
  if (!profile || !KnownProfile(*profile)) return XR_ERROR_PATH_UNSUPPORTED;
  std::vector<std::pair<Action*, XrPath>> list;
  for (uint32_t i = 0; i < info->countSuggestedBindings; ++i) {
    Action* a = Check<Action>(info->suggestedBindings[i].action, Tag::kAction);
    if (!a) return XR_ERROR_HANDLE_INVALID;
    if (a->set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    const std::string* path = PathString(inst, info->suggestedBindings[i].binding);
    if (!path) return XR_ERROR_PATH_INVALID;
    if (!PathOfProfile(*profile, *path)) return XR_ERROR_PATH_UNSUPPORTED;  // not this controller's
    Bound b = Classify(*path);
    if (b.source == Source::kNone) {  // the controller's, but not simulated (a thumbrest, a force): never active
      list.push_back({a, info->suggestedBindings[i].binding});
      continue;
    }
    bool isPose = b.source == Source::kPose, isHaptic = b.source == Source::kHaptic;
    if ((a->type == XR_ACTION_TYPE_POSE_INPUT) != isPose || (a->type == XR_ACTION_TYPE_VIBRATION_OUTPUT) != isHaptic)
      return XR_ERROR_PATH_UNSUPPORTED;
    list.push_back({a, info->suggestedBindings[i].binding});
  }
  inst->suggested[info->interactionProfile] = std::move(list);  // replaces earlier suggestions
  return XR_SUCCESS;
}

XrResult AttachSessionActionSets(XrSession handle, const XrSessionActionSetsAttachInfo* info) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (s->currentProfile != XR_NULL_PATH) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
  for (uint32_t i = 0; i < info->countActionSets; ++i) {
    ActionSet* set = Check<ActionSet>(info->actionSets[i], Tag::kActionSet);
    if (!set) return XR_ERROR_HANDLE_INVALID;
    set->attached = true;
  }
  Instance* inst = s->instance;
  XrPath wanted = InternPath(inst, inst->config.profile);
  s->currentProfile = inst->suggested.count(wanted) ? wanted
                      : inst->suggested.empty()      ? XR_NULL_PATH
                                                     : inst->suggested.begin()->first;
  if (s->currentProfile == XR_NULL_PATH) s->currentProfile = wanted;  // nothing bound, still "attached"
  XrEventDataInteractionProfileChanged e{XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED, nullptr, handle};
  XrEventDataBuffer buffer{};
  std::memcpy(&buffer, &e, sizeof(e));
  inst->events.push_back(buffer);
  return XR_SUCCESS;
}

XrResult GetCurrentInteractionProfile(XrSession handle, XrPath topLevel, XrInteractionProfileState* state) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  const std::string* p = PathString(s->instance, topLevel);
  if (!p) return XR_ERROR_PATH_INVALID;
  if (s->currentProfile == XR_NULL_PATH) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  bool hand = *p == "/user/hand/left" || *p == "/user/hand/right";
  state->interactionProfile = hand && s->instance->suggested.count(s->currentProfile) ? s->currentProfile : XR_NULL_PATH;
  return XR_SUCCESS;
}

XrResult GetActionStateBoolean(XrSession h, const XrActionStateGetInfo* info, XrActionStateBoolean* state) {
  std::lock_guard lock(Lock());
  float v = 0;
  XrResult r = GetState(h, info, XR_ACTION_TYPE_BOOLEAN_INPUT, state, &v);
  if (r == XR_SUCCESS) state->currentState = v > 0.5f ? XR_TRUE : XR_FALSE;
  return r;
}

XrResult GetActionStateFloat(XrSession h, const XrActionStateGetInfo* info, XrActionStateFloat* state) {
  std::lock_guard lock(Lock());
  float v = 0;
  XrResult r = GetState(h, info, XR_ACTION_TYPE_FLOAT_INPUT, state, &v);
  if (r == XR_SUCCESS) state->currentState = v;
  return r;
}

XrResult GetActionStateVector2f(XrSession h, const XrActionStateGetInfo* info, XrActionStateVector2f* state) {
  std::lock_guard lock(Lock());
  float v = 0;
  XrResult r = GetState(h, info, XR_ACTION_TYPE_VECTOR2F_INPUT, state, &v);
  if (r == XR_SUCCESS) state->currentState = {0, 0};  // the simulated thumbsticks and trackpads only click
  return r;
}

XrResult GetActionStatePose(XrSession h, const XrActionStateGetInfo* info, XrActionStatePose* state) {
  std::lock_guard lock(Lock());
  float v = 0;
  return GetState(h, info, XR_ACTION_TYPE_POSE_INPUT, state, &v);
}

XrResult SyncActions(XrSession handle, const XrActionsSyncInfo* info) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  bool focused = s->state == XR_SESSION_STATE_FOCUSED;
  s->activeSets.clear();
  for (uint32_t i = 0; i < info->countActiveActionSets; ++i) {
    ActionSet* set = Check<ActionSet>(info->activeActionSets[i].actionSet, Tag::kActionSet);
    if (!set) return XR_ERROR_HANDLE_INVALID;
    if (!set->attached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    s->activeSets.push_back(set);
  }
  XrTime t = s->lastDisplayTime ? s->lastDisplayTime : Now();
  double seconds = ScriptSeconds(s, t);
  Instance* inst = s->instance;
  for (auto& set : inst->actionSets) {
    if (set->tag != Tag::kActionSet || !set->attached) continue;
    bool setActive = focused && std::find(s->activeSets.begin(), s->activeSets.end(), set.get()) != s->activeSets.end();
    for (auto& action : set->actions) {
      std::vector<XrPath> subs = action->subactions;
      subs.push_back(XR_NULL_PATH);
      for (XrPath sub : subs) {
        ActionStateCache& c = s->actionStates[{action.get(), sub}];
        c.previous = c.value;
        auto bound = Bindings(s, action.get(), sub);
        c.active = setActive && !bound.empty();
        float v = 0;
        for (auto& [b, path] : bound) v = std::max(v, SourceValue(inst->script.Sample(b.device, seconds), b));
        c.value = c.active ? v : 0.0f;
        if (c.value != c.previous) c.changeTime = t;
      }
    }
  }
  return focused ? XR_SUCCESS : XR_SESSION_NOT_FOCUSED;
}

XrResult EnumerateBoundSourcesForAction(XrSession handle, const XrBoundSourcesForActionEnumerateInfo* info,
                                        uint32_t capacity, uint32_t* count, XrPath* sources) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  Action* action = Check<Action>(info->action, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  auto bound = Bindings(s, action, XR_NULL_PATH);
  return TwoCall(capacity, count, uint32_t(bound.size()), [&](uint32_t i) { sources[i] = bound[i].second; });
}

XrResult GetInputSourceLocalizedName(XrSession handle, const XrInputSourceLocalizedNameGetInfo* info,
                                     uint32_t capacity, uint32_t* count, char* buffer) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  const std::string* p = PathString(s->instance, info->sourcePath);
  if (!p) return XR_ERROR_PATH_INVALID;
  return TwoCall(capacity, count, uint32_t(p->size() + 1), [&](uint32_t i) { buffer[i] = p->c_str()[i]; });
}

bool ActionPose(Session* s, Action* action, XrPath subaction, XrTime time, Pose* out) {
  auto it = s->actionStates.find({action, subaction});
  if (it == s->actionStates.end() || !it->second.active) return false;
  for (auto& [b, path] : Bindings(s, action, subaction)) {
    if (b.source != Source::kPose) continue;
    DeviceSample d = s->instance->script.Sample(b.device, ScriptSeconds(s, time));
    if (!d.tracked) return false;
    *out = d.pose;
    return true;
  }
  return false;
}

void RecordHaptic(Session* s, Action* action, XrPath subaction, float amplitude, XrDuration duration,
                  float frequency, bool stop) {
  FILE* log = s->instance->hapticsLog;
  if (!log) return;
  XrTime t = s->lastDisplayTime ? s->lastDisplayTime : Now();
  for (auto& [b, path] : Bindings(s, action, subaction)) {
    if (b.source != Source::kHaptic) continue;
    std::fprintf(log, "%ld %.6f %s %.6f %lld %.3f%s\n", s->framesEnded, ScriptSeconds(s, t),
                 b.device == Device::kLeft ? "left" : "right", stop ? 0.0f : amplitude, (long long)duration, frequency,
                 stop ? " stop" : "");
  }
  std::fflush(log);
}

XrResult ApplyHapticFeedback(XrSession handle, const XrHapticActionInfo* info, const XrHapticBaseHeader* haptic) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  Action* action = Check<Action>(info->action, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  if (action->type != XR_ACTION_TYPE_VIBRATION_OUTPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (!action->set->attached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  if (!IsSubactionOf(action, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
  if (haptic->type != XR_TYPE_HAPTIC_VIBRATION) return XR_ERROR_VALIDATION_FAILURE;
  const auto* v = reinterpret_cast<const XrHapticVibration*>(haptic);
  if (s->state != XR_SESSION_STATE_FOCUSED) return XR_SESSION_NOT_FOCUSED;  // ignored, as on a headset
  RecordHaptic(s, action, info->subactionPath, std::clamp(v->amplitude, 0.0f, 1.0f), v->duration, v->frequency, false);
  return XR_SUCCESS;
}

XrResult StopHapticFeedback(XrSession handle, const XrHapticActionInfo* info) {
  std::lock_guard lock(Lock());
  SIMRT_SESSION(handle, s);
  Action* action = Check<Action>(info->action, Tag::kAction);
  if (!action) return XR_ERROR_HANDLE_INVALID;
  if (action->type != XR_ACTION_TYPE_VIBRATION_OUTPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (s->state != XR_SESSION_STATE_FOCUSED) return XR_SESSION_NOT_FOCUSED;
  RecordHaptic(s, action, info->subactionPath, 0, 0, 0, true);
  return XR_SUCCESS;
}

}  // namespace sphxr::xr::simrt
