// sphxr's OpenXR session: the session state machine of the specification (PollEvents), exit, the
// state queries, and the names of results and states. hello_xr's shape: the session knows no graphics
// beyond binding an eye's framebuffer; the application draws in the callback. Creation is in
// session_create.cpp, actions and haptics in session_actions.cpp, swapchains in
// session_swapchains.cpp, the frame loop in session_frame.cpp; Session::Impl is in session_impl.h.
#include "sphxr/xr/session.h"

#include <cstring>

#include "openxr_include.h"
#include "session_impl.h"
#include "sphxr/common/log.h"

#include <openxr/openxr_reflection.h>

namespace sphxr::xr {

const char* ResultName(XrResult result) {
#define SPHXR_XR_RESULT_CASE(name, value) \
  case name: return #name;
  switch (result) {
    XR_LIST_ENUM_XrResult(SPHXR_XR_RESULT_CASE) default : return "XR_UNKNOWN_RESULT";
  }
}

Status XrFailure(const char* call, XrResult result, const char* file, int line) {
  std::string c(call);
  if (auto paren = c.find('('); paren != std::string::npos) c.resize(paren);  // "xrCreateSession"
  const char* base = std::strrchr(file, '/');
  return Status::Error(Format("OpenXR: %s failed: %s (%s:%d)", c.c_str(), ResultName(result), base ? base + 1 : file,
                              line));
}

const char* SessionStateName(SessionState s) {
  switch (s) {
    case SessionState::kUnknown: return "UNKNOWN";
    case SessionState::kIdle: return "IDLE";
    case SessionState::kReady: return "READY";
    case SessionState::kSynchronized: return "SYNCHRONIZED";
    case SessionState::kVisible: return "VISIBLE";
    case SessionState::kFocused: return "FOCUSED";
    case SessionState::kStopping: return "STOPPING";
    case SessionState::kLossPending: return "LOSS_PENDING";
    case SessionState::kExiting: return "EXITING";
  }
  return "?";
}

namespace {

SessionState FromXr(XrSessionState s) {
  switch (s) {
    case XR_SESSION_STATE_IDLE: return SessionState::kIdle;
    case XR_SESSION_STATE_READY: return SessionState::kReady;
    case XR_SESSION_STATE_SYNCHRONIZED: return SessionState::kSynchronized;
    case XR_SESSION_STATE_VISIBLE: return SessionState::kVisible;
    case XR_SESSION_STATE_FOCUSED: return SessionState::kFocused;
    case XR_SESSION_STATE_STOPPING: return SessionState::kStopping;
    case XR_SESSION_STATE_LOSS_PENDING: return SessionState::kLossPending;
    case XR_SESSION_STATE_EXITING: return SessionState::kExiting;
    default: return SessionState::kUnknown;
  }
}

}  // namespace

Session::Session(std::unique_ptr<Impl> impl) : m_impl(std::move(impl)) {}
Session::~Session() { m_impl->Destroy(); }

// The session state machine of the spec: READY begins the session, STOPPING ends it, EXITING and
// LOSS_PENDING end the run.
void Session::Impl::OnSessionState(XrSessionState next) {
  if (next == XR_SESSION_STATE_READY) {
    XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
    bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    XrResult br = xrBeginSession(session, &bi);
    if (XR_FAILED(br)) {
      exited = true;
      lost = IsLoss(br);
      exitMessage = XrFailure("xrBeginSession", br, __FILE__, __LINE__).message();
    } else {
      running = true;
    }
  } else if (next == XR_SESSION_STATE_STOPPING) {
    running = false;
    XrResult er = xrEndSession(session);
    if (XR_FAILED(er)) {
      exited = true;
      lost = IsLoss(er);
      exitMessage = XrFailure("xrEndSession", er, __FILE__, __LINE__).message();
    }
  } else if (next == XR_SESSION_STATE_EXITING) {
    running = false;
    exited = true;
    exitMessage = "OpenXR session ended";
  } else if (next == XR_SESSION_STATE_LOSS_PENDING) {
    running = false;
    exited = lost = true;
    exitMessage = "OpenXR session lost (the headset went away)";
  }
}

EventResult Session::PollEvents() {
  Impl& m = *m_impl;
  EventResult result;
  auto finish = [&]() {
    result.state = m.state;
    result.running = m.running && !m.exited;
    result.exit = m.exited;
    result.lost = m.lost;
    result.message = m.exitMessage;
    return result;
  };
  if (m.exited) return finish();
  if (m.lost) {  // a call answered SESSION_LOST / INSTANCE_LOST before the event arrived
    m.exited = true;
    if (m.exitMessage.empty()) m.exitMessage = "OpenXR session lost";
    return finish();
  }
  XrEventDataBuffer event{XR_TYPE_EVENT_DATA_BUFFER};
  while (true) {
    event = {XR_TYPE_EVENT_DATA_BUFFER};
    XrResult r = xrPollEvent(m.instance, &event);
    if (r == XR_EVENT_UNAVAILABLE) break;
    if (XR_FAILED(r)) {
      m.exited = true;
      m.lost = IsLoss(r);
      m.exitMessage = XrFailure("xrPollEvent", r, __FILE__, __LINE__).message();
      break;
    }
    switch (event.type) {
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        m.lost = m.exited = true;
        m.running = false;
        m.exitMessage = "OpenXR instance lost (the runtime is going away)";
        break;
      case XR_TYPE_EVENT_DATA_EVENTS_LOST:
        SPHXR_LOG_WARN("OpenXR: the runtime dropped %u events",
                       reinterpret_cast<XrEventDataEventsLost&>(event).lostEventCount);
        break;
      case XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED:
        SPHXR_LOG_INFO("OpenXR: controllers: left %s, right %s", interactionProfile(Hand::kLeft).c_str(),
                       interactionProfile(Hand::kRight).c_str());
        break;
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        auto& e = reinterpret_cast<XrEventDataSessionStateChanged&>(event);
        if (e.session != m.session) break;
        m.state = FromXr(e.state);
        result.transitions.push_back(m.state);
        SPHXR_LOG_DEBUG("OpenXR: session state %s", SessionStateName(m.state));
        m.OnSessionState(e.state);
        break;
      }
      default: break;
    }
    if (m.exited) break;
  }
  return finish();
}

Status Session::RequestExit() {
  Impl& m = *m_impl;
  if (!m.running || m.lost) return Status::Ok();
  XrResult r = xrRequestExitSession(m.session);
  if (IsLoss(r)) {
    m.lost = true;
    return Status::Ok();
  }
  SPHXR_XR_CHECK_RESULT(xrRequestExitSession, r);
  return Status::Ok();
}

SessionState Session::state() const { return m_impl->state; }
const FrameTimings& Session::lastFrameTimings() const { return m_impl->timings; }
std::string Session::runtimeName() const { return m_impl->runtimeName; }
int Session::eyeWidth() const { return m_impl->eyes[0].width; }
int Session::eyeHeight() const { return m_impl->eyes[0].height; }
int64_t Session::colorFormat() const { return m_impl->colorFormat; }
int64_t Session::depthFormat() const { return m_impl->depthFormat; }
bool Session::submitsDepth() const { return m_impl->depthLayerOffered && m_impl->eyes[0].depth != XR_NULL_HANDLE; }

}  // namespace sphxr::xr
