// The simulated headset runtime's front door: the loader negotiation (the one exported symbol) and
// xrGetInstanceProcAddr's table of entry points, plus the lock and clock every file shares. The
// entry points live by concept: instance.cpp (configuration, instance, events, system), session.cpp
// (session lifecycle), frame.cpp (frame timing), spaces.cpp (spaces, poses, views), actions.cpp,
// swapchain.cpp.
#include "runtime.h"

#include <chrono>
#include <cstring>

// The loader's negotiation interface (loader_interfaces.h, absent from Debian's loader 1.0.20
// package): declared here exactly as the OpenXR loader documentation gives it.
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_CREATE_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_NEXT_INFO,
};
struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};
struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;
  uint32_t structVersion;
  size_t structSize;
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};
__attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* runtimeRequest);
}

namespace sphxr::xr::simrt {
namespace {

constexpr uint32_t kLoaderRuntimeInterfaceVersion = 1;

XRAPI_ATTR XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance instance, const char* name,
                                                   PFN_xrVoidFunction* function) {
  if (!name || !function) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
#define SIMRT_FN(xrName, impl)                                      \
  if (std::strcmp(name, #xrName) == 0) {                            \
    *function = reinterpret_cast<PFN_xrVoidFunction>(&impl);        \
    return XR_SUCCESS;                                              \
  }
  SIMRT_FN(xrGetInstanceProcAddr, GetInstanceProcAddr)
  SIMRT_FN(xrEnumerateInstanceExtensionProperties, EnumerateInstanceExtensionProperties)
  SIMRT_FN(xrCreateInstance, CreateInstance)
  if (instance == XR_NULL_HANDLE) return XR_ERROR_HANDLE_INVALID;
  SIMRT_FN(xrDestroyInstance, DestroyInstance)
  SIMRT_FN(xrGetInstanceProperties, GetInstanceProperties)
  SIMRT_FN(xrPollEvent, PollEvent)
  SIMRT_FN(xrResultToString, ResultToString)
  SIMRT_FN(xrStructureTypeToString, StructureTypeToString)
  SIMRT_FN(xrGetSystem, GetSystem)
  SIMRT_FN(xrGetSystemProperties, GetSystemProperties)
  SIMRT_FN(xrEnumerateEnvironmentBlendModes, EnumerateEnvironmentBlendModes)
  SIMRT_FN(xrEnumerateViewConfigurations, EnumerateViewConfigurations)
  SIMRT_FN(xrGetViewConfigurationProperties, GetViewConfigurationProperties)
  SIMRT_FN(xrEnumerateViewConfigurationViews, EnumerateViewConfigurationViews)
  SIMRT_FN(xrGetOpenGLGraphicsRequirementsKHR, GetOpenGLGraphicsRequirementsKHR)
  SIMRT_FN(xrCreateSession, CreateSession)
  SIMRT_FN(xrDestroySession, DestroySession)
  SIMRT_FN(xrBeginSession, BeginSession)
  SIMRT_FN(xrEndSession, EndSession)
  SIMRT_FN(xrRequestExitSession, RequestExitSession)
  SIMRT_FN(xrWaitFrame, WaitFrame)
  SIMRT_FN(xrBeginFrame, BeginFrame)
  SIMRT_FN(xrEndFrame, EndFrame)
  SIMRT_FN(xrLocateViews, LocateViews)
  SIMRT_FN(xrEnumerateReferenceSpaces, EnumerateReferenceSpaces)
  SIMRT_FN(xrCreateReferenceSpace, CreateReferenceSpace)
  SIMRT_FN(xrGetReferenceSpaceBoundsRect, GetReferenceSpaceBoundsRect)
  SIMRT_FN(xrCreateActionSpace, CreateActionSpace)
  SIMRT_FN(xrLocateSpace, LocateSpace)
  SIMRT_FN(xrDestroySpace, DestroySpace)
  SIMRT_FN(xrStringToPath, StringToPath)
  SIMRT_FN(xrPathToString, PathToString)
  SIMRT_FN(xrCreateActionSet, CreateActionSet)
  SIMRT_FN(xrDestroyActionSet, DestroyActionSet)
  SIMRT_FN(xrCreateAction, CreateAction)
  SIMRT_FN(xrDestroyAction, DestroyAction)
  SIMRT_FN(xrSuggestInteractionProfileBindings, SuggestInteractionProfileBindings)
  SIMRT_FN(xrAttachSessionActionSets, AttachSessionActionSets)
  SIMRT_FN(xrGetCurrentInteractionProfile, GetCurrentInteractionProfile)
  SIMRT_FN(xrGetActionStateBoolean, GetActionStateBoolean)
  SIMRT_FN(xrGetActionStateFloat, GetActionStateFloat)
  SIMRT_FN(xrGetActionStateVector2f, GetActionStateVector2f)
  SIMRT_FN(xrGetActionStatePose, GetActionStatePose)
  SIMRT_FN(xrSyncActions, SyncActions)
  SIMRT_FN(xrEnumerateBoundSourcesForAction, EnumerateBoundSourcesForAction)
  SIMRT_FN(xrGetInputSourceLocalizedName, GetInputSourceLocalizedName)
  SIMRT_FN(xrApplyHapticFeedback, ApplyHapticFeedback)
  SIMRT_FN(xrStopHapticFeedback, StopHapticFeedback)
  SIMRT_FN(xrEnumerateSwapchainFormats, EnumerateSwapchainFormats)
  SIMRT_FN(xrCreateSwapchain, CreateSwapchain)
  SIMRT_FN(xrDestroySwapchain, DestroySwapchain)
  SIMRT_FN(xrEnumerateSwapchainImages, EnumerateSwapchainImages)
  SIMRT_FN(xrAcquireSwapchainImage, AcquireSwapchainImage)
  SIMRT_FN(xrWaitSwapchainImage, WaitSwapchainImage)
  SIMRT_FN(xrReleaseSwapchainImage, ReleaseSwapchainImage)
#undef SIMRT_FN
  return XR_ERROR_FUNCTION_UNSUPPORTED;
}

}  // namespace

std::mutex& Lock() {
  static std::mutex m;
  return m;
}

XrTime Now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace sphxr::xr::simrt

extern "C" XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* loaderInfo,
                                                      XrNegotiateRuntimeRequest* request) {
  using namespace sphxr::xr::simrt;
  if (!loaderInfo || !request || loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      loaderInfo->structVersion != 1 || loaderInfo->structSize != sizeof(XrNegotiateLoaderInfo) ||
      request->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST || request->structVersion != 1 ||
      request->structSize != sizeof(XrNegotiateRuntimeRequest))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (loaderInfo->minInterfaceVersion > kLoaderRuntimeInterfaceVersion ||
      loaderInfo->maxInterfaceVersion < kLoaderRuntimeInterfaceVersion ||
      XR_VERSION_MAJOR(loaderInfo->minApiVersion) > 1 || XR_VERSION_MAJOR(loaderInfo->maxApiVersion) < 1)
    return XR_ERROR_INITIALIZATION_FAILED;
  request->runtimeInterfaceVersion = kLoaderRuntimeInterfaceVersion;
  request->runtimeApiVersion = XR_CURRENT_API_VERSION;
  request->getInstanceProcAddr = &GetInstanceProcAddr;
  return XR_SUCCESS;
}
