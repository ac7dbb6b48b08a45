// The other tests assert that the core validation layer reported nothing. This one shows that the
// check can fail: a call with a wrong structure type, made straight through the loader (tests may
// use private and third-party headers), is reported in the layer's log.
#include <openxr/openxr.h>

#include <cstring>

#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

TEST(XrValidationLayer, ReportsAnApiMisuseInItsLog) {
  SimHeadset headset("misuse");
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "misuse");
  ci.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  XrInstance instance = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateInstance(&ci, &instance), XR_SUCCESS);
  EXPECT_EQ(headset.ValidationText(), "");
  XrSystemGetInfo si{XR_TYPE_SYSTEM_PROPERTIES};  // wrong type on purpose
  si.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId id = XR_NULL_SYSTEM_ID;
  EXPECT_EQ(xrGetSystem(instance, &si, &id), XR_ERROR_VALIDATION_FAILURE);
  xrDestroyInstance(instance);
  std::string text = headset.ValidationText();
  EXPECT_NE(text.find("VUID-XrSystemGetInfo-type-type"), std::string::npos) << text;
}

}  // namespace
}  // namespace sphxr::xr::test
