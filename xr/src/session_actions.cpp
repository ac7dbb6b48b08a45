// The session's input and output: the action set and its suggested bindings (from the one table in
// action_bindings.cpp), the grip spaces, each frame's hand state (poses, velocities, trigger,
// squeeze, button edges), haptic pulses and the current interaction profile.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "openxr_include.h"
#include "session_impl.h"
#include "sphxr/common/log.h"

namespace sphxr::xr {

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
