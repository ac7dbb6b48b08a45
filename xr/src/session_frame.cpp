// The session's frame loop: wait, sync the hands, the application's update, begin, draw each eye into
// its swapchain image, and end. xrEndFrame is called whenever the frame has begun; each phase is
// timed for lastFrameTimings().
#include <array>
#include <chrono>

#include "gl_functions.h"
#include "openxr_include.h"
#include "session_impl.h"

namespace sphxr::xr {

// The composition layer's view of eye `e` (its depth image chained when the runtime takes depth).
void Session::Impl::LayerView(int e, const XrView& view, XrCompositionLayerProjectionView* out) {
  const Eye& eye = eyes[size_t(e)];
  XrCompositionLayerProjectionView& lv = *out;
  lv = {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW};
  lv.pose = view.pose;
  lv.fov = view.fov;
  lv.subImage.swapchain = eye.color;
  lv.subImage.imageRect = {{0, 0}, {eye.width, eye.height}};
  lv.subImage.imageArrayIndex = 0;
  if (depthLayerOffered && eye.depth) {
    XrCompositionLayerDepthInfoKHR& d = depthInfos[size_t(e)];
    d = {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR};
    d.subImage.swapchain = eye.depth;
    d.subImage.imageRect = lv.subImage.imageRect;
    d.subImage.imageArrayIndex = 0;
    d.minDepth = 0.0f;
    d.maxDepth = 1.0f;
    d.nearZ = options.nearZ;
    d.farZ = options.farZ;
    lv.next = &d;
  }
}

Status Session::Impl::RenderEyes(const FrameInfo& info, const RenderEyeFn& renderEye,
                                 std::array<XrCompositionLayerProjectionView, 2>* layerViews, bool* rendered) {
  *rendered = false;
  XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
  li.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  li.displayTime = info.predictedDisplayTimeNs;
  li.space = playSpace;
  XrViewState vs{XR_TYPE_VIEW_STATE};
  std::array<XrView, 2> views{{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};
  uint32_t count = 0;
  XrResult r = xrLocateViews(session, &li, &vs, 2, &count, views.data());
  if (IsLoss(r)) {
    lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrLocateViews, r);
  const XrViewStateFlags need = XR_VIEW_STATE_POSITION_VALID_BIT | XR_VIEW_STATE_ORIENTATION_VALID_BIT;
  if ((vs.viewStateFlags & need) != need) return Status::Ok();  // no head pose: submit nothing

  GlFunctions::GLint prevFramebuffer = 0;
  gl.GetIntegerv(gl::kDrawFramebufferBinding, &prevFramebuffer);
  const bool srgb = colorFormat == gl::kSrgb8Alpha8 || colorFormat == gl::kSrgb8;
  const bool srgbWasOn = gl.IsEnabled(gl::kFramebufferSrgb);
  for (int e = 0; e < 2; ++e) {
    Eye& eye = eyes[size_t(e)];
    XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
    XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
    wi.timeout = XR_INFINITE_DURATION;
    XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
    uint32_t colorIndex = 0, depthIndex = 0;
    SPHXR_XR_CHECK(xrAcquireSwapchainImage(eye.color, &ai, &colorIndex));
    SPHXR_XR_CHECK(xrWaitSwapchainImage(eye.color, &wi));
    if (eye.depth) {
      SPHXR_XR_CHECK(xrAcquireSwapchainImage(eye.depth, &ai, &depthIndex));
      SPHXR_XR_CHECK(xrWaitSwapchainImage(eye.depth, &wi));
    }
    EyeView ev;
    ev.eye = e;
    ev.pose = FromXr(views[size_t(e)].pose);
    const XrFovf& f = views[size_t(e)].fov;
    ev.fov = {f.angleLeft, f.angleRight, f.angleUp, f.angleDown};
    ev.view = ViewMatrix(ev.pose);
    ev.projection = ProjectionMatrix(ev.fov, options.nearZ, options.farZ);
    ev.framebuffer = eye.framebuffer;
    ev.colorTexture = eye.colorImages[colorIndex];
    ev.depthTexture = eye.depth ? eye.depthImages[depthIndex] : eye.ownDepth;
    ev.width = eye.width;
    ev.height = eye.height;
    ev.srgb = srgb;
    gl.BindFramebuffer(gl::kFramebuffer, eye.framebuffer);
    gl.FramebufferTexture2D(gl::kFramebuffer, gl::kColorAttachment0, gl::kTexture2D, ev.colorTexture, 0);
    gl.FramebufferTexture2D(gl::kFramebuffer, gl::kDepthAttachment, gl::kTexture2D, ev.depthTexture, 0);
    Status status = Status::Ok();
    if (gl.CheckFramebufferStatus(gl::kFramebuffer) != gl::kFramebufferComplete) {
      status = Status::Error("OpenXR: the eye framebuffer is incomplete");
    } else {
      gl.Viewport(0, 0, eye.width, eye.height);
      if (srgb) gl.Enable(gl::kFramebufferSrgb);  // the renderer writes linear colour
      renderEye(info, ev);
      if (srgb && !srgbWasOn) gl.Disable(gl::kFramebufferSrgb);
    }
    gl.BindFramebuffer(gl::kFramebuffer, GlFunctions::GLuint(prevFramebuffer));
    SPHXR_XR_CHECK(xrReleaseSwapchainImage(eye.color, &ri));
    if (eye.depth) SPHXR_XR_CHECK(xrReleaseSwapchainImage(eye.depth, &ri));
    if (!status) return status;
    LayerView(e, views[size_t(e)], &(*layerViews)[size_t(e)]);
  }
  *rendered = true;
  return Status::Ok();
}

Status Session::Frame(const UpdateFn& update, const RenderEyeFn& renderEye) {
  Impl& m = *m_impl;
  if (!m.running || m.exited || m.lost) return Status::Ok();  // PollEvents says why; nothing to do
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  m.timings = {};
  auto t0 = Clock::now();
  XrFrameWaitInfo wi{XR_TYPE_FRAME_WAIT_INFO};
  XrFrameState fs{XR_TYPE_FRAME_STATE};
  XrResult r = xrWaitFrame(m.session, &wi, &fs);
  auto t1 = Clock::now();
  m.timings.waitMs = ms(t0, t1);
  if (IsLoss(r)) {
    m.lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrWaitFrame, r);
  FrameInfo info;
  info.predictedDisplayTimeNs = fs.predictedDisplayTime;
  info.displayPeriodNs = fs.predictedDisplayPeriod;
  info.shouldRender = fs.shouldRender;
  info.frameIndex = m.frameIndex++;
  m.lastDisplayTime = fs.predictedDisplayTime;
  bool recentre = false;
  Status status = m.SyncHands(&info, &recentre);
  auto t2 = Clock::now();
  m.timings.syncMs = ms(t1, t2);
  if (status && !m.lost && update) update(info);
  auto t3 = Clock::now();
  m.timings.updateMs = ms(t2, t3);

  XrFrameBeginInfo bi{XR_TYPE_FRAME_BEGIN_INFO};
  r = xrBeginFrame(m.session, &bi);
  if (IsLoss(r)) {
    m.lost = true;
    return status;
  }
  SPHXR_XR_CHECK_RESULT(xrBeginFrame, r);
  // From here xrEndFrame is always called, whatever happens while drawing.
  std::array<XrCompositionLayerProjectionView, 2> views{};
  bool rendered = false;
  if (status && !m.lost && info.shouldRender && renderEye) status = m.RenderEyes(info, renderEye, &views, &rendered);
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  layer.space = m.playSpace;
  layer.viewCount = 2;
  layer.views = views.data();
  const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = fs.predictedDisplayTime;
  ei.environmentBlendMode = m.blendMode;
  ei.layerCount = rendered ? 1 : 0;
  ei.layers = rendered ? layers : nullptr;
  auto t4 = Clock::now();
  m.timings.renderMs = ms(t3, t4);
  r = xrEndFrame(m.session, &ei);
  m.timings.endMs = ms(t4, Clock::now());
  if (IsLoss(r)) {
    m.lost = true;
    return status;
  }
  if (!status) return status;
  SPHXR_XR_CHECK_RESULT(xrEndFrame, r);
  return Status::Ok();
}

}  // namespace sphxr::xr
