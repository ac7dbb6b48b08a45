#include "action_bindings.h"

namespace sphxr::xr {
namespace {

constexpr ActionInfo kActions[] = {
    {ActionId::kGripPose, "grip_pose", "Hand pose"},
    {ActionId::kTrigger, "trigger", "Trigger"},
    {ActionId::kSqueeze, "squeeze", "Squeeze"},
    {ActionId::kHaptic, "haptic", "Paddle feedback"},
    {ActionId::kRecentre, "recentre", "Recentre view"},
    {ActionId::kReset, "reset", "Reset scene"},
    {ActionId::kSaveState, "save_state", "Save the water"},
};
static_assert(std::size(kActions) == size_t(ActionId::kCount));

constexpr const char* kSimple = "/interaction_profiles/khr/simple_controller";
constexpr const char* kTouch = "/interaction_profiles/oculus/touch_controller";
constexpr const char* kIndex = "/interaction_profiles/valve/index_controller";
constexpr const char* kVive = "/interaction_profiles/htc/vive_controller";
constexpr const char* kWmr = "/interaction_profiles/microsoft/motion_controller";

// Paths from the OpenXR 1.0 specification, section 6.4 "Interaction Profile Paths". The simple
// controller has no squeeze; Touch has a menu button on the left hand only (the right one is the
// reserved system button), so reset sits on A; Index has no menu button: recentre on left B. Saving
// the state takes the right B where there is one (Touch, Index), else the right trackpad click (Vive)
// or thumbstick click (WMR); the simple controller has no spare button, and its users save from the
// mirror window's panel.
constexpr SuggestedBinding kBindings[] = {
    {kSimple, ActionId::kGripPose, kBothHands, "/input/grip/pose"},
    {kSimple, ActionId::kTrigger, kBothHands, "/input/select/click"},
    {kSimple, ActionId::kHaptic, kBothHands, "/output/haptic"},
    {kSimple, ActionId::kRecentre, kLeftHand, "/input/menu/click"},
    {kSimple, ActionId::kReset, kRightHand, "/input/menu/click"},

    {kTouch, ActionId::kGripPose, kBothHands, "/input/grip/pose"},
    {kTouch, ActionId::kTrigger, kBothHands, "/input/trigger/value"},
    {kTouch, ActionId::kSqueeze, kBothHands, "/input/squeeze/value"},
    {kTouch, ActionId::kHaptic, kBothHands, "/output/haptic"},
    {kTouch, ActionId::kRecentre, kLeftHand, "/input/menu/click"},
    {kTouch, ActionId::kReset, kRightHand, "/input/a/click"},
    {kTouch, ActionId::kSaveState, kRightHand, "/input/b/click"},

    {kIndex, ActionId::kGripPose, kBothHands, "/input/grip/pose"},
    {kIndex, ActionId::kTrigger, kBothHands, "/input/trigger/value"},
    {kIndex, ActionId::kSqueeze, kBothHands, "/input/squeeze/value"},
    {kIndex, ActionId::kHaptic, kBothHands, "/output/haptic"},
    {kIndex, ActionId::kRecentre, kLeftHand, "/input/b/click"},
    {kIndex, ActionId::kReset, kRightHand, "/input/a/click"},
    {kIndex, ActionId::kSaveState, kRightHand, "/input/b/click"},

    {kVive, ActionId::kGripPose, kBothHands, "/input/grip/pose"},
    {kVive, ActionId::kTrigger, kBothHands, "/input/trigger/value"},
    {kVive, ActionId::kSqueeze, kBothHands, "/input/squeeze/click"},
    {kVive, ActionId::kHaptic, kBothHands, "/output/haptic"},
    {kVive, ActionId::kRecentre, kLeftHand, "/input/menu/click"},
    {kVive, ActionId::kReset, kRightHand, "/input/menu/click"},
    {kVive, ActionId::kSaveState, kRightHand, "/input/trackpad/click"},

    {kWmr, ActionId::kGripPose, kBothHands, "/input/grip/pose"},
    {kWmr, ActionId::kTrigger, kBothHands, "/input/trigger/value"},
    {kWmr, ActionId::kSqueeze, kBothHands, "/input/squeeze/click"},
    {kWmr, ActionId::kHaptic, kBothHands, "/output/haptic"},
    {kWmr, ActionId::kRecentre, kLeftHand, "/input/menu/click"},
    {kWmr, ActionId::kReset, kRightHand, "/input/menu/click"},
    {kWmr, ActionId::kSaveState, kRightHand, "/input/thumbstick/click"},
};

}  // namespace

std::span<const ActionInfo> Actions() { return kActions; }
std::span<const SuggestedBinding> SuggestedBindings() { return kBindings; }

}  // namespace sphxr::xr
