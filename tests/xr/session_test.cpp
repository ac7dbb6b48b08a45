// The XR path end to end: sphxr's xr::Session through the real Khronos loader, with the core
// validation layer on, against the simulated headset runtime, drawing with a real GLX context
// (Mesa llvmpipe) under Xvfb.
#include <algorithm>
#include <cmath>

#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

const auto* const kDisplay = ::testing::AddGlobalTestEnvironment(new DisplayEnvironment);

constexpr float kPi = 3.14159265358979f;

std::unique_ptr<Session> MakeSession(SessionOptions options = {}) {
  std::unique_ptr<Session> session;
  Status s = Session::Create(options, CurrentBinding(), &session);
  EXPECT_TRUE(s) << s.message();
  return session;
}

void ExpectNear(Vec3 a, Vec3 b, float tol) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

std::filesystem::path WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

TEST(XrSession, GoesThroughItsStatesToACleanExit) {
  SimHeadset headset("states");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  EXPECT_EQ(session->runtimeName(), "sphxr simulated headset");
  EXPECT_EQ(session->colorFormat(), 0x8C43);  // GL_SRGB8_ALPHA8, the runtime's first choice
  EXPECT_EQ(session->depthFormat(), 0x8CAC);  // GL_DEPTH_COMPONENT32F
  EXPECT_EQ(session->eyeWidth(), 64);
  EXPECT_EQ(session->eyeHeight(), 48);
  RunResult r = RunSession(*session, 10);
  using S = SessionState;
  std::vector<S> expected{S::kIdle,    S::kReady,        S::kSynchronized, S::kVisible, S::kFocused,
                          S::kVisible, S::kSynchronized, S::kStopping,     S::kIdle,    S::kExiting};
  EXPECT_EQ(r.transitions, expected);
  EXPECT_TRUE(r.last.exit);
  EXPECT_FALSE(r.last.lost);
  EXPECT_GE(r.frames.size(), 10u);
  // The first frame comes before the session is visible: not rendered, but still ended.
  ASSERT_FALSE(r.frames.empty());
  EXPECT_FALSE(r.frames.front().shouldRender);
  EXPECT_GE(r.renderedFrames, 9);
  const FrameTimings& t = session->lastFrameTimings();
  EXPECT_GT(t.waitMs + t.syncMs + t.renderMs + t.endMs, 0.0);
  session.reset();
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, FramesFollowTheRuntimesDisplayRate) {
  SimHeadset headset("rate");
  headset.env.Set("SPHXR_SIM_XR_RATE_HZ", "60");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  const int kFrames = 30;
  auto start = std::chrono::steady_clock::now();
  RunResult r = RunSession(*session, kFrames);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_GE(r.frames.size(), size_t(kFrames));
  const int64_t period = 16666667;  // 1e9 / 60, rounded
  int64_t slots = 0;
  for (size_t i = 0; i < r.frames.size(); ++i) {
    EXPECT_EQ(r.frames[i].displayPeriodNs, period);
    if (i == 0) continue;
    int64_t dt = r.frames[i].predictedDisplayTimeNs - r.frames[i - 1].predictedDisplayTimeNs;
    // Display times lie on the runtime's vsync lattice; a slow frame may skip slots, never split one.
    EXPECT_GT(dt, 0);
    EXPECT_EQ(dt % period, 0) << "frame " << i;
    slots += dt / period;
  }
  // The runtime paces the loop: N frames take at least N - 1 periods of wall time (a lower bound,
  // so a loaded machine cannot fail it).
  EXPECT_GE(seconds, (r.frames.size() - 1) * 1e-9 * period * 0.98);
  EXPECT_GE(slots, int64_t(r.frames.size()) - 1);
  session.reset();
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, ScriptedControllerArrivesAsTheGripPose) {
  SimHeadset headset("grip");
  // Right controller moving along +x at 0.5 m/s, turned 90 degrees about +y (forward -z becomes -x),
  // trigger at 0.75; head still, turned 90 degrees about +y as well.
  const float s45 = std::sin(kPi / 4), c45 = std::cos(kPi / 4);
  std::string script = Format("0 right 0 1.2 -0.5  0 %.8f 0 %.8f trigger=0.75 squeeze=0.5\n"
                              "100 right 50 1.2 -0.5  0 %.8f 0 %.8f trigger=0.75 squeeze=0.5\n"
                              "0 head 0.2 1.7 0.3  0 %.8f 0 %.8f\n",
                              s45, c45, s45, c45, s45, c45);
  headset.env.Set("SPHXR_SIM_XR_PROFILE", "oculus/touch_controller");
  headset.env.Set("SPHXR_SIM_XR_POSES", WriteFile(headset.dir / "poses.txt", script).string());
  headset.env.Set("SPHXR_SIM_XR_IPD", "0.07");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  std::vector<EyeView> eyes;
  RunResult r = RunSession(*session, 8, {}, [&](const FrameInfo&, const EyeView& eye) {
    eyes.push_back(eye);
    glClear(GL_COLOR_BUFFER_BIT);
  });
  EXPECT_EQ(session->interactionProfile(Hand::kRight), "/interaction_profiles/oculus/touch_controller");
  int checked = 0;
  for (const FrameInfo& f : r.frames) {
    const HandState& right = f.hands[1];
    if (!right.active) continue;  // before FOCUSED actions are inactive
    ++checked;
    EXPECT_TRUE(right.poseValid && right.tracked);
    EXPECT_NEAR(right.grip.position.y, 1.2f, 1e-5f);
    EXPECT_NEAR(right.grip.position.z, -0.5f, 1e-5f);
    EXPECT_GE(right.grip.position.x, 0.0f);
    ExpectNear(Rotate(right.grip.orientation, {0, 0, -1}), {-1, 0, 0}, 1e-5f);
    ExpectNear(Rotate(right.grip.orientation, {0, 1, 0}), {0, 1, 0}, 1e-5f);
    ASSERT_TRUE(right.velocityValid);
    ExpectNear(right.linearVelocity, {0.5f, 0, 0}, 1e-3f);
    EXPECT_NEAR(right.trigger, 0.75f, 1e-6f);
    EXPECT_NEAR(right.squeeze, 0.5f, 1e-6f);
  }
  EXPECT_GE(checked, 5);
  // Grip x advances 0.5 m/s along the script clock: two frames' difference over their display times.
  const FrameInfo* a = nullptr;
  const FrameInfo* b = nullptr;
  for (const FrameInfo& f : r.frames)
    if (f.hands[1].active) (a ? b : a) = &f;
  ASSERT_TRUE(a && b);
  double dt = (b->predictedDisplayTimeNs - a->predictedDisplayTimeNs) * 1e-9;
  EXPECT_NEAR(b->hands[1].grip.position.x - a->hands[1].grip.position.x, 0.5 * dt, 1e-4);
  // The eyes: the head faces -x, so the right eye sits 7 cm along -z of the left one; both look along -x.
  ASSERT_GE(eyes.size(), 2u);
  const EyeView& left = eyes[eyes.size() - 2];
  const EyeView& rightEye = eyes.back();
  ASSERT_EQ(left.eye, 0);
  ASSERT_EQ(rightEye.eye, 1);
  ExpectNear(rightEye.pose.position - left.pose.position, {0, 0, -0.07f}, 1e-5f);
  ExpectNear((left.pose.position + rightEye.pose.position) * 0.5f, {0.2f, 1.7f, 0.3f}, 1e-5f);
  ExpectNear(Rotate(left.pose.orientation, {0, 0, -1}), {-1, 0, 0}, 1e-5f);
  EXPECT_EQ(left.width, 64);
  EXPECT_EQ(left.height, 48);
  EXPECT_NE(left.framebuffer, 0u);
  EXPECT_NE(left.depthTexture, 0u);
  session.reset();
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, HapticAmplitudesAreRecordedByTheRuntime) {
  SimHeadset headset("haptics");
  auto log = headset.dir / "haptics.txt";
  headset.env.Set("SPHXR_SIM_XR_HAPTICS_LOG", log.string());
  auto session = MakeSession();
  ASSERT_TRUE(session);
  RunSession(*session, 6, [](Session& s, const FrameInfo& f) {
    if (!f.hands[0].active) return;
    EXPECT_TRUE(s.ApplyHaptics(Hand::kRight, 0.6f));
    EXPECT_TRUE(s.ApplyHaptics(Hand::kLeft, 1.7f));   // clamped to 1
    EXPECT_TRUE(s.ApplyHaptics(Hand::kLeft, 0.0f));   // stops
  });
  session.reset();
  std::ifstream in(log);
  std::string line;
  int right = 0, leftClamped = 0, leftStop = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    long frame;
    double t, amplitude;
    std::string hand;
    long long duration;
    ASSERT_TRUE(ls >> frame >> t >> hand >> amplitude >> duration) << line;
    if (hand == "right") {
      EXPECT_NEAR(amplitude, 0.6, 1e-6);
      EXPECT_EQ(duration, 50000000);  // SessionOptions::hapticPulseSeconds = 0.05
      ++right;
    } else if (line.find("stop") != std::string::npos) {
      EXPECT_EQ(amplitude, 0.0);
      ++leftStop;
    } else {
      EXPECT_NEAR(amplitude, 1.0, 1e-6);
      ++leftClamped;
    }
  }
  EXPECT_GE(right, 4);
  EXPECT_EQ(right, leftClamped);
  EXPECT_EQ(right, leftStop);
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, SubmittedEyeImagesAreSavedWithWhatWasDrawn) {
  SimHeadset headset("capture");
  auto dir = headset.dir / "frames";
  std::filesystem::create_directories(dir);
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", dir.string());
  auto session = MakeSession();
  ASSERT_TRUE(session);
  // Left eye red, right eye blue; a linear 50 % grey square in the bottom-left quarter of the left eye.
  RunResult r = RunSession(*session, 4, {}, [](const FrameInfo&, const EyeView& eye) {
    glDisable(GL_SCISSOR_TEST);
    glClearColor(eye.eye == 0 ? 1.0f : 0.0f, 0.0f, eye.eye == 0 ? 0.0f : 1.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (eye.eye == 0) {
      glEnable(GL_SCISSOR_TEST);
      glScissor(0, 0, eye.width / 2, eye.height / 2);
      glClearColor(0.5f, 0.5f, 0.5f, 1.0f);
      glClear(GL_COLOR_BUFFER_BIT);
      glDisable(GL_SCISSOR_TEST);
    }
  });
  session.reset();
  int pairs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    std::string name = entry.path().filename().string();
    if (name.find("_left.png") == std::string::npos) continue;
    ++pairs;
    int w = 0, h = 0;
    std::vector<uint8_t> px;
    ASSERT_TRUE(ReadPng(entry.path(), &w, &h, &px)) << name;
    ASSERT_EQ(w, 64);
    ASSERT_EQ(h, 48);
    auto at = [&](int x, int y) { return &px[(size_t(y) * w + x) * 4]; };
    // Top-right: red. Bottom-left (PNG rows run top-down): grey, sRGB-encoded: 0.5 linear -> 188.
    EXPECT_EQ(at(w - 1, 0)[0], 255);
    EXPECT_EQ(at(w - 1, 0)[1], 0);
    EXPECT_EQ(at(w - 1, 0)[2], 0);
    const uint8_t* grey = at(2, h - 3);
    EXPECT_NEAR(grey[0], 188, 1) << name;
    EXPECT_EQ(grey[0], grey[1]);
    EXPECT_EQ(grey[1], grey[2]);
    EXPECT_EQ(at(w / 2 + 1, h - 3)[0], 255);  // just right of the square: red again
    std::string rightName = name.substr(0, name.size() - 9) + "_right.png";
    ASSERT_TRUE(ReadPng(dir / rightName, &w, &h, &px)) << rightName;
    for (int y = 0; y < h; y += 7)
      for (int x = 0; x < w; x += 7) {
        EXPECT_EQ(at(x, y)[0], 0);
        EXPECT_EQ(at(x, y)[2], 255);
      }
  }
  EXPECT_EQ(pairs, r.renderedFrames);
  EXPECT_GE(pairs, 3);
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, NoRuntimeGivesOneClearLine) {
  ScopedEnv env;
  env.Set("XR_RUNTIME_JSON", "/nonexistent/sphxr/runtime.json");
  std::unique_ptr<Session> session;
  Status s = Session::Create({}, CurrentBinding(), &session);
  ASSERT_FALSE(s);
  EXPECT_FALSE(session);
  EXPECT_NE(s.message().find("no OpenXR runtime"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos) << s.message();
  // The probe for the default mode gives the same answer without creating anything.
  Status probe = ProbeRuntime();
  EXPECT_FALSE(probe);
  EXPECT_EQ(probe.message(), s.message());
  env.Set("XR_RUNTIME_JSON", SPHXR_SIM_RUNTIME_JSON);
  probe = ProbeRuntime();
  EXPECT_TRUE(probe) << probe.message();
}

TEST(XrSession, BadOptionsAreRefusedBeforeTouchingTheRuntime) {
  ScopedEnv env;
  env.Set("XR_RUNTIME_JSON", "/nonexistent/sphxr/runtime.json");  // never reached
  std::unique_ptr<Session> session;
  SessionOptions o;
  o.nearZ = 0;
  Status s = Session::Create(o, CurrentBinding(), &session);
  EXPECT_NE(s.message().find("0 < near < far"), std::string::npos) << s.message();
  o = {};
  o.farZ = std::nanf("");
  EXPECT_NE(Session::Create(o, CurrentBinding(), &session).message().find("0 < near < far"), std::string::npos);
  o = {};
  o.hapticPulseSeconds = -1;
  EXPECT_NE(Session::Create(o, CurrentBinding(), &session).message().find("haptic pulse"), std::string::npos);
  EXPECT_FALSE(session);
}

TEST(XrSession, RuntimeFailingAtSessionCreationGivesOneClearLine) {
  SimHeadset headset("failsession");
  headset.env.Set("SPHXR_SIM_XR_FAIL_SESSION", "1");
  std::unique_ptr<Session> session;
  Status s = Session::Create({}, CurrentBinding(), &session);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("xrCreateSession failed: XR_ERROR_RUNTIME_FAILURE"), std::string::npos) << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
  // Everything created before the failure was destroyed: a new instance can be made at once.
  headset.env.Set("SPHXR_SIM_XR_FAIL_SESSION", "0");
  EXPECT_TRUE(MakeSession());
}

TEST(XrSession, RuntimeRefusingToStartGivesOneClearLine) {
  SimHeadset headset("badscript");
  headset.env.Set("SPHXR_SIM_XR_POSES", WriteFile(headset.dir / "poses.txt", "0 elbow 0 0 0 0 0 0 1\n").string());
  std::unique_ptr<Session> session;
  Status s = Session::Create({}, CurrentBinding(), &session);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("the OpenXR runtime did not start (xrCreateInstance answered "
                             "XR_ERROR_INITIALIZATION_FAILED)"),
            std::string::npos)
      << s.message();
  EXPECT_EQ(s.message().find('\n'), std::string::npos);
}

TEST(XrSession, SessionLossEndsTheLoopCleanly) {
  SimHeadset headset("loss");
  headset.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "5");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  RunResult r = RunSession(*session, 1000);
  EXPECT_TRUE(r.last.exit);
  EXPECT_TRUE(r.last.lost);
  EXPECT_NE(r.last.message.find("lost"), std::string::npos) << r.last.message;
  EXPECT_EQ(r.transitions.back(), SessionState::kLossPending);
  EXPECT_EQ(r.frames.size(), 5u);
  // After the loss Frame and haptics are no-ops, not errors.
  EXPECT_TRUE(session->Frame({}, {}));
  EXPECT_TRUE(session->ApplyHaptics(Hand::kLeft, 0.5f));
  session.reset();
  ExpectNoValidationErrors(headset);
  // The application can try again (the headset came back).
  headset.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "");
  auto again = MakeSession();
  ASSERT_TRUE(again);
  EXPECT_FALSE(RunSession(*again, 3).last.lost);
}

TEST(XrSession, InstanceLossEndsTheLoopCleanly) {
  SimHeadset headset("instanceloss");
  headset.env.Set("SPHXR_SIM_XR_LOSE_INSTANCE_AFTER_FRAMES", "4");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  RunResult r = RunSession(*session, 1000);
  EXPECT_TRUE(r.last.exit);
  EXPECT_TRUE(r.last.lost);
  EXPECT_NE(r.last.message.find("instance lost"), std::string::npos) << r.last.message;
  EXPECT_EQ(r.frames.size(), 4u);
  session.reset();
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, RuntimeInitiatedExitStopsTheSession) {
  SimHeadset headset("runtimeexit");
  headset.env.Set("SPHXR_SIM_XR_EXIT_AFTER_FRAMES", "6");
  auto session = MakeSession();
  ASSERT_TRUE(session);
  RunResult r = RunSession(*session, 1000);
  EXPECT_TRUE(r.last.exit);
  EXPECT_FALSE(r.last.lost);
  EXPECT_EQ(r.transitions.back(), SessionState::kExiting);
  EXPECT_EQ(r.frames.size(), 6u);
  session.reset();
  ExpectNoValidationErrors(headset);
}

TEST(XrSession, RecentreAndResetButtons) {
  SimHeadset headset("recentre");
  // Head at (0.5, 1.7, 0.2) facing -x (yaw 90 degrees about +y), pitched down 20 degrees about its
  // own x axis; left menu pressed from 0.05 s, right menu from 0.1 s (simple controller).
  Quat yaw = AxisAngle({0, 1, 0}, kPi / 2), pitch = AxisAngle({1, 0, 0}, -0.35f);
  Quat head = Mul(yaw, pitch);
  std::string script = Format("0 head 0.5 1.7 0.2  %.8f %.8f %.8f %.8f\n"
                              "0 left -0.2 1 0 0 0 0 1\n0.05 left -0.2 1 0 0 0 0 1 menu=1\n"
                              "0 right 0.2 1 0 0 0 0 1\n0.10 right 0.2 1 0 0 0 0 1 menu=1\n",
                              head.x, head.y, head.z, head.w);
  headset.env.Set("SPHXR_SIM_XR_POSES", WriteFile(headset.dir / "poses.txt", script).string());
  auto session = MakeSession();
  ASSERT_TRUE(session);
  std::vector<EyeView> eyes;
  RunResult r = RunSession(*session, 20, {}, [&](const FrameInfo&, const EyeView& eye) {
    eyes.push_back(eye);
    glClear(GL_COLOR_BUFFER_BIT);
  });
  int recentred = 0, resets = 0;
  for (const FrameInfo& f : r.frames) {
    recentred += f.recentred;
    resets += f.resetRequested;
  }
  EXPECT_EQ(recentred, 1);  // one press, one recentre (an edge, not a level)
  EXPECT_EQ(resets, 1);
  ASSERT_GE(eyes.size(), 2u);
  // After recentring the head is above the origin and looks along -z (pitch kept, yaw removed).
  Vec3 centre = (eyes[eyes.size() - 2].pose.position + eyes.back().pose.position) * 0.5f;
  ExpectNear(centre, {0, 1.7f, 0}, 1e-5f);
  Vec3 forward = Rotate(eyes.back().pose.orientation, {0, 0, -1});
  ExpectNear(forward, {0, -std::sin(0.35f), -std::cos(0.35f)}, 1e-5f);
  session.reset();
  ExpectNoValidationErrors(headset);
}

}  // namespace
}  // namespace sphxr::xr::test

namespace sphxr::xr::test {
namespace {

// Each controller profile of the binding table, chosen by the simulated headset: the scripted
// trigger (0.75) and squeeze (0.6) reach the application through that profile's paths. Click
// sources read 0 or 1; the simple controller has no squeeze. The right hand's save input, pressed
// from 0.05 s, arrives as one save request (and no reset); the simple controller has none, so B,
// trackpad and thumbstick pressed on it give no save.
struct ProfileCase {
  const char* profile;
  float trigger, squeeze;
  const char* savePress;  // the pose script's inputs pressed from 0.05 s
  int saves;              // save requests expected from them
};

class XrProfiles : public ::testing::TestWithParam<ProfileCase> {};

TEST_P(XrProfiles, ScriptedInputsArriveThroughTheProfilesBindings) {
  const ProfileCase& c = GetParam();
  SimHeadset headset("profile");
  headset.env.Set("SPHXR_SIM_XR_PROFILE", c.profile);
  headset.env.Set("SPHXR_SIM_XR_POSES",
                  WriteFile(headset.dir / "poses.txt",
                            "0 left -0.2 1 0 0 0 0 1 trigger=0.75 squeeze=0.6\n"
                            "0 right 0.2 1 0 0 0 0 1 trigger=0.75 squeeze=0.6\n" +
                                Format("0.05 right 0.2 1 0 0 0 0 1 trigger=0.75 squeeze=0.6 %s\n", c.savePress))
                      .string());
  headset.env.Set("SPHXR_SIM_XR_HAPTICS_LOG", (headset.dir / "haptics.txt").string());
  auto session = MakeSession();
  ASSERT_TRUE(session);
  int focused = 0, saves = 0, resets = 0;
  RunSession(*session, 20, [&](Session& s, const FrameInfo& f) {
    saves += f.saveRequested;
    resets += f.resetRequested;
    if (!f.hands[0].active) return;
    ++focused;
    for (const HandState& h : f.hands) {
      EXPECT_TRUE(h.poseValid);
      EXPECT_NEAR(h.trigger, c.trigger, 1e-6f);
      EXPECT_NEAR(h.squeeze, c.squeeze, 1e-6f);
    }
    EXPECT_NEAR(f.hands[0].grip.position.x, -0.2f, 1e-6f);
    EXPECT_NEAR(f.hands[1].grip.position.x, 0.2f, 1e-6f);
    EXPECT_TRUE(s.ApplyHaptics(Hand::kRight, 0.5f));
  });
  EXPECT_GE(focused, 3);
  EXPECT_EQ(saves, c.saves) << "one press, one save (an edge)";
  EXPECT_EQ(resets, 0);
  EXPECT_EQ(session->interactionProfile(Hand::kLeft), std::string("/interaction_profiles/") + c.profile);
  session.reset();
  std::ifstream log(headset.dir / "haptics.txt");
  std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find(" right 0.500000 "), std::string::npos) << text;  // the haptic output is bound too
  ExpectNoValidationErrors(headset);
}

INSTANTIATE_TEST_SUITE_P(
    Table, XrProfiles,
    ::testing::Values(ProfileCase{"khr/simple_controller", 1.0f, 0.0f, "b=1 trackpad=1 thumbstick=1", 0},
                      ProfileCase{"oculus/touch_controller", 0.75f, 0.6f, "b=1", 1},
                      ProfileCase{"valve/index_controller", 0.75f, 0.6f, "b=1", 1},
                      ProfileCase{"htc/vive_controller", 0.75f, 1.0f, "trackpad=1", 1},
                      ProfileCase{"microsoft/motion_controller", 0.75f, 1.0f, "thumbstick=1", 1}),
    [](const ::testing::TestParamInfo<ProfileCase>& info) {
      std::string name = info.param.profile;
      for (char& ch : name)
        if (ch == '/') ch = '_';
      return name;
    });

}  // namespace
}  // namespace sphxr::xr::test
