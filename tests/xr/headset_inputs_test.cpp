// What the headset path reads from outside and how it ends: the runtime manifest (XR_RUNTIME_JSON) and
// the simulated headset's pose script read only when they are regular files of a bounded size, every
// SPHXR_SIM_XR_* setting finite and in range, a capture folder checked once, a lost session's water saved
// under a bounded name whatever the scene is called, and SIGINT or SIGTERM during `sphxr --xr` ending the
// session cleanly with its summary and its water saved. The real program, the real loader, the simulated
// runtime (as app_xr_test.cpp).
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <array>
#include <cmath>

#include "pose_script.h"
#include "xr_test_support.h"

namespace sphxr::xr::test {
namespace {

struct AppRun {
  int code = -1;
  std::string out;  // stdout and stderr
};

const std::string kCommon = " --quality scene --threads 1 --window-size 160x120";

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

AppRun RunSphxr(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path output = dir / "sphxr_out.txt";
  const std::string cmd = "cd '" + std::filesystem::absolute(dir).string() + "' && timeout 60 " +
                          std::string(SPHXR_BINARY) + " " + args + " >" + output.string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  AppRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadText(output);
  return r;
}

int CountOf(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

std::filesystem::path WriteScene(const std::filesystem::path& dir, const std::string& name = "xr_inputs_tank") {
  const std::filesystem::path path = dir / "scene.json";
  std::ofstream(path) << R"({
  "name": ")" << name << R"(",
  "solver": { "spacing": 0.02, "max_dt": 0.001 },
  "tank": { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.2] },
  "fluid": [ { "min": [0.0, 0.0, 0.0], "max": [0.2, 0.1, 0.2] } ]
})";
  return path;
}

std::filesystem::path MakeFifo(const std::filesystem::path& dir) {
  const std::filesystem::path fifo = dir / "fifo";
  EXPECT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  return fifo;
}

// ---- what is read ---------------------------------------------------------------------------------

TEST(XrHeadsetInputs, AManifestThatIsNotARegularFileIsOneLineThenTheDesktopWindow) {
  const auto dir = TempDir("inputs_manifest");
  for (const std::string manifest : {std::string("/dev/zero"), MakeFifo(dir).string()}) {
    ScopedEnv env;
    env.Set("XR_RUNTIME_JSON", manifest);
    const auto begin = std::chrono::steady_clock::now();
    const AppRun r = RunSphxr("--xr --scene " + WriteScene(dir).string() + " --frame-limit 3" + kCommon, dir);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_LT(std::chrono::steady_clock::now() - begin, std::chrono::seconds(30));
    EXPECT_EQ(CountOf(r.out, "no OpenXR runtime available (XR_RUNTIME_JSON=" + manifest + " is not a regular file)"), 1)
        << r.out;
    EXPECT_EQ(CountOf(r.out, "OpenXR"), 1) << r.out;
    EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
  }
}

TEST(XrHeadsetInputs, APoseScriptThatIsNotARegularFileIsOneLineThenTheDesktopWindow) {
  const auto dir = TempDir("inputs_poses");
  for (const std::string poses : {std::string("/dev/zero"), MakeFifo(dir).string()}) {
    SimHeadset headset("inputs_poses_run");
    headset.env.Set("SPHXR_SIM_XR_POSES", poses);
    const AppRun r =
        RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 3" + kCommon, headset.dir);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(CountOf(r.out, "SPHXR_SIM_XR_POSES='" + poses + "' is not a pose script (not a regular file)"), 1)
        << r.out;
    EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
  }
}

TEST(XrHeadsetInputs, SettingsThatAreNotFiniteAreRefusedInOneLine) {
  for (const auto& [name, value] :
       std::vector<std::pair<std::string, std::string>>{{"SPHXR_SIM_XR_RATE_HZ", "nan"},
                                                        {"SPHXR_SIM_XR_IPD", "nan"},
                                                        {"SPHXR_SIM_XR_IPD", "-inf"},
                                                        {"SPHXR_SIM_XR_CAPTURE_EVERY", "inf"},
                                                        {"SPHXR_SIM_XR_EXIT_AFTER_FRAMES", "nan"}}) {
    SimHeadset headset("inputs_settings");
    headset.env.Set(name, value);
    const AppRun r =
        RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 3" + kCommon, headset.dir);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(CountOf(r.out, name + "='" + value + "' is not a number in ["), 1) << r.out;
    EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
    EXPECT_EQ(CountOf(r.out, "sphxr --xr:"), 0) << r.out;
  }
}

TEST(XrHeadsetInputs, AHapticsLogOrAnEyeSizeThatCannotBeUsedIsOneLine) {
  const auto dir = TempDir("inputs_haptics");
  const std::string fifo = MakeFifo(dir).string();
  for (const auto& [name, value, message] :
       std::vector<std::array<std::string, 3>>{{"SPHXR_SIM_XR_HAPTICS_LOG", fifo, "' is not a regular file"},
                                               {"SPHXR_SIM_XR_EYE_SIZE", "64x48junk",
                                                "' is not WIDTHxHEIGHT (1..8192)"}}) {
    SimHeadset headset("inputs_haptics_run");
    headset.env.Set(name, value);
    const AppRun r =
        RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 3" + kCommon, headset.dir);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(CountOf(r.out, name + "='" + value + message), 1) << r.out;
    EXPECT_EQ(CountOf(r.out, "using the desktop window"), 1) << r.out;
  }
}

TEST(XrHeadsetInputs, ABadCaptureFolderIsOneLine) {
  SimHeadset headset("inputs_capture");
  headset.env.Set("SPHXR_SIM_XR_CAPTURE_DIR", (headset.dir / "no_such_folder").string());
  const AppRun r =
      RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 40" + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "SPHXR_SIM_XR_CAPTURE_DIR"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "cannot write"), 0) << r.out;
  EXPECT_NE(r.out.find("is not a folder this process can write"), std::string::npos) << r.out;
}

TEST(SimRuntimePoseScript, ValuesThatAreNotFiniteAreRefused) {
  simrt::PoseScript script;
  std::string error;
  for (const char* text : {"0 right 0 1 0  0 0 0 1  trigger=nan\n", "0 right 0 1 0  0 0 0 1  squeeze=inf\n",
                           "0 right 0 1 0  0 0 0 1  trigger=2\n", "0 right nan 1 0  0 0 0 1\n",
                           "0 right 0 1 0  nan 0 0 1\n", "nan right 0 1 0  0 0 0 1\n", "loop nan\n"}) {
    EXPECT_FALSE(simrt::PoseScript::Parse(text, &script, &error)) << "accepted: " << text;
    EXPECT_NE(error.find("line 1"), std::string::npos) << error;
  }
  EXPECT_TRUE(simrt::PoseScript::Parse("0 right 0 1 0  0 0 0 1  trigger=1 squeeze=0\n", &script, &error)) << error;
  const auto dir = TempDir("inputs_pose_load");
  EXPECT_FALSE(simrt::PoseScript::Load("/dev/zero", &script, &error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(simrt::PoseScript::Load(MakeFifo(dir).string(), &script, &error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(simrt::PoseScript::Load("/x\x1b]0;t\x07", &script, &error));
  EXPECT_EQ(error.find('\x1b'), std::string::npos) << error;
}

// ---- how a session ends ---------------------------------------------------------------------------

TEST(XrHeadsetInputs, ALostSessionOfALongScenesNameStillSaves) {
  SimHeadset headset("inputs_long_name");
  headset.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "5");
  const std::string name(300, 'n');
  const AppRun r =
      RunSphxr("--xr --scene " + WriteScene(headset.dir, name).string() + " --frame-limit 5" + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "the XR session was lost"), 1) << r.out;
  const std::filesystem::path saved = headset.dir / (std::string(100, 'n') + "-lost.state");
  EXPECT_TRUE(std::filesystem::is_regular_file(saved)) << r.out;
  EXPECT_EQ(CountOf(r.out, "save state:"), 0) << r.out;  // no failed save
}

TEST(XrHeadsetInputs, ALostSessionThatCannotSaveBesideItSavesInTheTemporaryFolder) {
  SimHeadset headset("inputs_lost_fallback");
  headset.env.Set("SPHXR_SIM_XR_LOSE_SESSION_AFTER_FRAMES", "5");
  // The working directory's "<scene>-lost.state" is a folder: that save fails.
  std::filesystem::create_directories(headset.dir / "xr_inputs_tank-lost.state");
  std::filesystem::create_directories(headset.dir / "tmp");
  headset.env.Set("TMPDIR", (headset.dir / "tmp").string());
  const AppRun r =
      RunSphxr("--xr --scene " + WriteScene(headset.dir).string() + " --frame-limit 5" + kCommon, headset.dir);
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(CountOf(r.out, "the XR session was lost"), 1) << r.out;
  EXPECT_TRUE(std::filesystem::is_regular_file(headset.dir / "tmp" / "xr_inputs_tank-lost.state")) << r.out;
}

/// `sphxr args` in `dir`, its output to sphxr_out.txt; the child's pid.
pid_t Spawn(const std::vector<std::string>& args, const std::filesystem::path& dir) {
  const std::string output = (dir / "sphxr_out.txt").string();
  std::vector<char*> argv{const_cast<char*>(SPHXR_BINARY)};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (chdir(dir.c_str()) != 0) _exit(126);
    const int fd = open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    execv(SPHXR_BINARY, argv.data());
    _exit(127);
  }
  return pid;
}

AppRun SignalMidSession(const std::filesystem::path& dir, const std::vector<std::string>& args, int signal) {
  const pid_t pid = Spawn(args, dir);
  AppRun r;
  const auto begin = std::chrono::steady_clock::now();
  // The session runs (its runtime line is logged), then a second of frames.
  while (ReadText(dir / "sphxr_out.txt").find("headset: runtime") == std::string::npos &&
         std::chrono::steady_clock::now() - begin < std::chrono::seconds(60)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  kill(pid, signal);
  int status = 0;
  for (int k = 0; k < 300 && waitpid(pid, &status, WNOHANG) == 0; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (waitpid(pid, &status, WNOHANG) == 0 && !WIFEXITED(status) && !WIFSIGNALED(status)) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadText(dir / "sphxr_out.txt");
  return r;
}

TEST(XrHeadsetInputs, SigtermEndsTheSessionCleanlyAndSavesToSaveState) {
  SimHeadset headset("inputs_sigterm");
  const std::string state = (headset.dir / "asked.state").string();
  const AppRun r = SignalMidSession(headset.dir,
                                    {"--xr", "--scene", WriteScene(headset.dir).string(), "--save-state", state,
                                     "--quality", "scene", "--threads", "1", "--window-size", "160x120"},
                                    SIGTERM);
  EXPECT_EQ(r.code, 128 + SIGTERM) << r.out;
  EXPECT_EQ(CountOf(r.out, "SIGTERM: ending the headset session"), 1) << r.out;
  EXPECT_EQ(CountOf(r.out, "sphxr --xr: ended by SIGTERM after "), 1) << r.out;
  EXPECT_NE(r.out.find("session states IDLE READY SYNCHRONIZED VISIBLE FOCUSED"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::is_regular_file(state)) << r.out;
  EXPECT_EQ(CountOf(r.out, "using the desktop window"), 0) << r.out;
  ExpectNoValidationErrors(headset);
}

TEST(XrHeadsetInputs, SigintEndsTheSessionCleanlyAndSavesAsALostSessionDoes) {
  SimHeadset headset("inputs_sigint");
  const AppRun r = SignalMidSession(headset.dir,
                                    {"--xr", "--scene", WriteScene(headset.dir).string(), "--quality", "scene",
                                     "--threads", "1", "--window-size", "160x120"},
                                    SIGINT);
  EXPECT_EQ(r.code, 128 + SIGINT) << r.out;
  EXPECT_EQ(CountOf(r.out, "sphxr --xr: ended by SIGINT after "), 1) << r.out;
  EXPECT_TRUE(std::filesystem::is_regular_file(headset.dir / "xr_inputs_tank-lost.state")) << r.out;
}

}  // namespace
}  // namespace sphxr::xr::test
