// Scenes by name: `sphxr --scene stir` from any directory, in the build tree and once installed.
#include <filesystem>

#include "sphxr/app/scene_file.h"
#include "sphxr/common/shown_text.h"

#ifndef SPHXR_SCENES_DIR
#define SPHXR_SCENES_DIR ""
#endif

namespace sphxr::app {
namespace {

namespace fs = std::filesystem;

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec) && !fs::is_directory(p, ec);
}

/// <prefix>/share/sphxr/scenes for the running executable at <prefix>/bin (relocatable: a .deb's
/// /usr/bin/sphxr, or `cmake --install build --prefix P`).
std::string InstalledScenes() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  return (exe.parent_path().parent_path() / "share" / "sphxr" / "scenes").string();
}

}  // namespace

std::vector<std::string> SceneSearchDirs(const std::string& installDir) {
  const std::string installed = installDir.empty() ? InstalledScenes() : installDir;
  std::error_code ec;
  // An installed program has its own scenes: the build's source tree (compiled in, perhaps on another
  // machine, the one a .deb was made on) is only for a program run from its build tree.
  const bool isInstalled = !installed.empty() && fs::is_directory(installed, ec);
  std::vector<std::string> candidates = {".", installed, isInstalled ? "" : SPHXR_SCENES_DIR};
  std::vector<std::string> dirs;
  for (const std::string& d : candidates) {
    if (d.empty() || !fs::is_directory(d, ec)) continue;
    bool seen = false;
    for (const std::string& e : dirs) seen = seen || fs::equivalent(e, d, ec);
    if (!seen) dirs.push_back(d);
  }
  return dirs;
}

Status FindScene(const std::string& name, std::string* path, const std::string& installDir) {
  if (IsFile(name) || name.find('/') != std::string::npos || name.empty()) {
    *path = name;
    return Status::Ok();
  }
  const std::vector<std::string> dirs = SceneSearchDirs(installDir);
  for (const std::string& dir : dirs) {
    for (const std::string& file : {name, name + ".json"}) {
      const fs::path p = fs::path(dir) / file;
      if (IsFile(p)) {
        *path = dir == "." ? file : p.string();
        return Status::Ok();
      }
    }
  }
  std::string where;
  for (const std::string& dir : dirs) where += (where.empty() ? "" : ", ") + (dir == "." ? "the current directory" : dir);
  // The name once, escaped and cut (it may be anything a user or a script passed).
  return Status::Error("--scene " + ShowText(name) + ": no scene of that name (nor with .json) in " +
                       (where.empty() ? "the current directory" : where) + " (give a file's path, or a scene's name)");
}

}  // namespace sphxr::app
