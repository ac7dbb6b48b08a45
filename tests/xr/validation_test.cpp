// The other tests assert that the core validation layer reported nothing. This one shows that the
// check can fail: a call with a wrong structure type, made straight through the loader (tests may
// use private and third-party headers), is reported in the layer's log.
#include <openxr/openxr.h>

#include <cstring>

#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

/// An instance of the simulated headset straight through the loader (XR_NULL_HANDLE on failure).
XrInstance CreateInstance(const char* name) {
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, name);
  ci.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  XrInstance instance = XR_NULL_HANDLE;
  return xrCreateInstance(&ci, &instance) == XR_SUCCESS ? instance : XR_NULL_HANDLE;
}

TEST(XrValidationLayer, ReportsAnApiMisuseInItsLog) {
  SimHeadset headset("misuse");
  const XrInstance instance = CreateInstance("misuse");
  ASSERT_NE(instance, XR_NULL_HANDLE);
  EXPECT_EQ(headset.ValidationText(), "");
  XrSystemGetInfo si{XR_TYPE_SYSTEM_PROPERTIES};  // wrong type on purpose
  si.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId id = XR_NULL_SYSTEM_ID;
  EXPECT_EQ(xrGetSystem(instance, &si, &id), XR_ERROR_VALIDATION_FAILURE);
  xrDestroyInstance(instance);
  std::string text = headset.ValidationText();
  EXPECT_NE(text.find("VUID-XrSystemGetInfo-type-type"), std::string::npos) << text;
}

// The simulated runtime refuses, as a real one does, a suggestion with a path the controller does not
// have: the whole profile's suggestion fails with XR_ERROR_PATH_UNSUPPORTED (the application's own
// table is then skipped for that controller, logged). So XrProfiles.* fails for a binding that is valid
// on one controller but not on another, instead of passing on the simulated headset alone.
TEST(XrSimRuntime, RefusesABindingPathTheControllerDoesNotHave) {
  SimHeadset headset("paths");
  const XrInstance instance = CreateInstance("paths");
  ASSERT_NE(instance, XR_NULL_HANDLE);
  XrActionSetCreateInfo si{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(si.actionSetName, "paths");
  std::strcpy(si.localizedActionSetName, "Paths");
  XrActionSet set = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateActionSet(instance, &si, &set), XR_SUCCESS);
  XrActionCreateInfo ai{XR_TYPE_ACTION_CREATE_INFO};
  ai.actionType = XR_ACTION_TYPE_BOOLEAN_INPUT;
  std::strcpy(ai.actionName, "press");
  std::strcpy(ai.localizedActionName, "Press");
  XrAction press = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateAction(set, &ai, &press), XR_SUCCESS);
  auto suggest = [&](const char* profile, const char* binding) {
    XrPath profilePath = XR_NULL_PATH, bindingPath = XR_NULL_PATH;
    EXPECT_EQ(xrStringToPath(instance, profile, &profilePath), XR_SUCCESS);
    EXPECT_EQ(xrStringToPath(instance, binding, &bindingPath), XR_SUCCESS);
    XrActionSuggestedBinding b{press, bindingPath};
    XrInteractionProfileSuggestedBinding sb{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    sb.interactionProfile = profilePath;
    sb.countSuggestedBindings = 1;
    sb.suggestedBindings = &b;
    return xrSuggestInteractionProfileBindings(instance, &sb);
  };
  const char* vive = "/interaction_profiles/htc/vive_controller";
  const char* touch = "/interaction_profiles/oculus/touch_controller";
  const char* wmr = "/interaction_profiles/microsoft/motion_controller";
  EXPECT_EQ(suggest(vive, "/user/hand/right/input/trackpad/click"), XR_SUCCESS);
  EXPECT_EQ(suggest(vive, "/user/hand/right/input/a/click"), XR_ERROR_PATH_UNSUPPORTED);  // no A on a Vive wand
  EXPECT_EQ(suggest(wmr, "/user/hand/right/input/thumbstick/click"), XR_SUCCESS);
  EXPECT_EQ(suggest(wmr, "/user/hand/right/input/b/click"), XR_ERROR_PATH_UNSUPPORTED);
  EXPECT_EQ(suggest(touch, "/user/hand/right/input/b/click"), XR_SUCCESS);
  EXPECT_EQ(suggest(touch, "/user/hand/left/input/b/click"), XR_ERROR_PATH_UNSUPPORTED);  // Y on the left
  EXPECT_EQ(suggest(touch, "/user/hand/left/input/menu/click"), XR_SUCCESS);
  EXPECT_EQ(suggest(touch, "/user/hand/right/input/menu/click"), XR_ERROR_PATH_UNSUPPORTED);  // the system button
  EXPECT_EQ(suggest(touch, "/user/hand/right/input/trigger"), XR_SUCCESS);  // the identifier alone
  EXPECT_EQ(suggest(touch, "/user/hand/right/input/thumbrest/touch"), XR_SUCCESS);  // real, not simulated
  EXPECT_EQ(suggest("/interaction_profiles/acme/teapot_controller", "/user/hand/right/input/trigger/value"),
            XR_ERROR_PATH_UNSUPPORTED);
  xrDestroyInstance(instance);
  EXPECT_EQ(headset.ValidationText(), "");
}

}  // namespace
}  // namespace sphxr::xr::test
