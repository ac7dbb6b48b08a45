#pragma once
// Shared by the xr tests: an X display (our own Xvfb when DISPLAY is unset), a GLFW window whose GLX
// context the session draws with, the environment that points the real Khronos loader at the
// simulated headset with the core validation layer, and a loop that runs a session to its end.
#include <gtest/gtest.h>
#include <GLFW/glfw3.h>
#include <X11/Xlib.h>
// From glfw3native.h, which with GLFW_EXPOSE_NATIVE_X11 also wants the Xrandr headers.
extern "C" Display* glfwGetX11Display(void);
#undef Status
#undef Bool
#undef Success
#undef None
#undef Always
#include <png.h>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sphxr/common/log.h"
#include "sphxr/xr/session.h"
#include "xvfb.h"

namespace sphxr::xr::test {

/// Sets environment variables for its lifetime, restoring the previous values.
class ScopedEnv {
 public:
  ScopedEnv() = default;
  ScopedEnv(const ScopedEnv&) = delete;
  ~ScopedEnv() {
    for (auto& [name, old] : m_old) {
      if (old) setenv(name.c_str(), old->c_str(), 1);
      else unsetenv(name.c_str());
    }
  }
  void Set(const std::string& name, const std::string& value) {
    if (!m_old.count(name)) {
      const char* v = std::getenv(name.c_str());
      m_old[name] = v ? std::optional<std::string>(v) : std::nullopt;
    }
    setenv(name.c_str(), value.c_str(), 1);
  }

 private:
  std::map<std::string, std::optional<std::string>> m_old;
};

inline std::filesystem::path TempRoot() {
  return std::filesystem::temp_directory_path() / ("sphxr_xr_test_" + std::to_string(getpid()));
}
inline std::filesystem::path TempDir(const std::string& name) {
  auto dir = TempRoot() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// One X display and one hidden GLFW window for the whole test program.
class DisplayEnvironment : public ::testing::Environment {
 public:
  void SetUp() override {
    if (!std::getenv("DISPLAY") || !*std::getenv("DISPLAY")) StartXvfb();
    ASSERT_TRUE(glfwInit()) << "GLFW could not open the X display";
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    s_window = glfwCreateWindow(64, 64, "sphxr xr test", nullptr, nullptr);
    ASSERT_NE(s_window, nullptr) << "no GL 3.3 context";
    glfwMakeContextCurrent(s_window);
  }
  void TearDown() override {
    if (::testing::UnitTest::GetInstance()->Passed())  // keep the files of a failed run to look at
      std::filesystem::remove_all(TempRoot());
    if (s_window) glfwDestroyWindow(s_window);
    glfwTerminate();
    m_xvfb.reset();
  }
  static GLFWwindow* window() { return s_window; }

 private:
  // Our own Xvfb (tests/xvfb.h: it picks a free display itself, no race between tests started at once).
  void StartXvfb() {
    m_xvfb = std::make_unique<sphxr::test::Xvfb>("320x240x24");
    ASSERT_FALSE(m_xvfb->Display().empty()) << "could not start Xvfb (install xvfb, or set DISPLAY)";
    setenv("DISPLAY", m_xvfb->Display().c_str(), 1);
  }
  std::unique_ptr<sphxr::test::Xvfb> m_xvfb;
  static inline GLFWwindow* s_window = nullptr;
};

inline GraphicsBinding CurrentBinding() {
  GraphicsBinding b;
  b.getProcAddress = [](const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); };
  Status s = CurrentXlibGlxBinding(glfwGetX11Display(), &b);
  EXPECT_TRUE(s) << s.message();
  return b;
}

/// Points the real loader at the simulated headset with the core validation layer writing to a
/// file; small eyes keep llvmpipe quick.
struct SimHeadset {
  ScopedEnv env;
  std::filesystem::path dir;
  std::filesystem::path validationLog;
  explicit SimHeadset(const std::string& name) : dir(TempDir(name)), validationLog(dir / "validation.txt") {
    env.Set("XR_RUNTIME_JSON", SPHXR_SIM_RUNTIME_JSON);
    env.Set("XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation");
    env.Set("XR_CORE_VALIDATION_EXPORT_TYPE", "text");
    env.Set("XR_CORE_VALIDATION_FILE_NAME", validationLog.string());
    env.Set("SPHXR_SIM_XR_EYE_SIZE", "64x48");
    env.Set("SPHXR_SIM_XR_RATE_HZ", "90");
  }
  std::string ValidationText() const {
    std::ifstream in(validationLog);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
};

/// The validation layer writes "[VALID_ERROR | VUID-... | call]" lines (or warnings) to its file
/// when the API is misused; nothing when it is used correctly (validation_test.cpp shows both).
inline void ExpectNoValidationErrors(const SimHeadset& h) {
  std::string text = h.ValidationText();
  EXPECT_EQ(text.find("VALID_"), std::string::npos) << text;
  EXPECT_EQ(text.find("VUID"), std::string::npos) << text;
}

struct RunResult {
  std::vector<SessionState> transitions;
  std::vector<FrameInfo> frames;  // every frame's info (update callback)
  int renderedFrames = 0;
  EventResult last;
};

/// Runs the loop until the session exits; after `maxFrames` frames asks for the exit.
inline RunResult RunSession(Session& session, int maxFrames,
                            const std::function<void(Session&, const FrameInfo&)>& onUpdate = {},
                            const RenderEyeFn& renderEye = {}) {
  RunResult r;
  bool exitRequested = false;
  RenderEyeFn draw = renderEye ? renderEye : [](const FrameInfo&, const EyeView&) {
    glClearColor(0.1f, 0.2f, 0.3f, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  };
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    EventResult ev = session.PollEvents();
    r.transitions.insert(r.transitions.end(), ev.transitions.begin(), ev.transitions.end());
    r.last = ev;
    if (ev.exit) break;
    if (!ev.running) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    if (int(r.frames.size()) >= maxFrames && !exitRequested) {
      Status s = session.RequestExit();
      EXPECT_TRUE(s) << s.message();
      exitRequested = true;
    }
    Status s = session.Frame(
        [&](const FrameInfo& info) {
          r.frames.push_back(info);
          if (onUpdate) onUpdate(session, info);
        },
        [&](const FrameInfo& info, const EyeView& eye) {
          if (eye.eye == 0) ++r.renderedFrames;
          draw(info, eye);
        });
    EXPECT_TRUE(s) << s.message();
    if (!s) break;
  }
  return r;
}

/// Reads an 8-bit RGBA PNG (top row first).
inline bool ReadPng(const std::filesystem::path& path, int* w, int* h, std::vector<uint8_t>* rgba) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return false;
  image.format = PNG_FORMAT_RGBA;
  rgba->resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgba->data(), 0, nullptr)) return false;
  *w = int(image.width);
  *h = int(image.height);
  return true;
}

}  // namespace sphxr::xr::test
