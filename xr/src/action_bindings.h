#pragma once
// sphxr's actions and the bindings it suggests for each controller profile: one data table.
#include <cstdint>
#include <span>

namespace sphxr::xr {

enum class ActionId { kGripPose, kTrigger, kSqueeze, kHaptic, kRecentre, kReset, kSaveState, kCount };

struct ActionInfo {
  ActionId id;
  const char* name;           // OpenXR action name
  const char* localizedName;  // shown by runtimes in their binding UI
};
std::span<const ActionInfo> Actions();

enum HandMask : uint8_t { kLeftHand = 1, kRightHand = 2, kBothHands = 3 };

/// One row: for `profile`, bind `action` on each hand of `hands` to /user/hand/<hand><suffix>.
struct SuggestedBinding {
  const char* profile;
  ActionId action;
  uint8_t hands;
  const char* suffix;
};
std::span<const SuggestedBinding> SuggestedBindings();

}  // namespace sphxr::xr
