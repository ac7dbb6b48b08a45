// The simulated headset's spaces and views: reference spaces (VIEW follows the scripted head; LOCAL
// and STAGE share the world origin), action spaces on the scripted controllers, xrLocateSpace with
// velocities by central difference, and xrLocateViews for two eyes an IPD apart.
#include <algorithm>
#include <cmath>
#include <memory>

#include "runtime.h"

namespace sphxr::xr::simrt {
namespace {

const Fov kEyeFov{-0.80f, 0.75f, 0.80f, -0.85f};  // a little asymmetric, like real lenses

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

}  // namespace

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

double ScriptSeconds(const Session* s, XrTime time) {
  return s->beginTime ? double(time - s->beginTime) * 1e-9 : 0.0;
}

}  // namespace sphxr::xr::simrt
