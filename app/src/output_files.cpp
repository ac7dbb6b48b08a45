#include "output_files.h"

#include <unistd.h>

#include <filesystem>

#include "sphxr/common/shown_text.h"

namespace sphxr::app {

Status CheckPlaceToWrite(const std::string& flag, const std::string& path, const char* nameHint) {
  if (path.empty()) return Status::Ok();
  const std::filesystem::path file(path);
  const std::filesystem::path dir = file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    return Status::Error(flag + " " + path + ": is a directory; give a file name" + nameHint);
  }
  // (These files are replaced whole: a device or a pipe there is not a place for them.)
  if (std::filesystem::exists(file, ec) && !std::filesystem::is_regular_file(file, ec)) {
    return Status::Error(flag + " " + path + ": not a regular file (a device or pipe); give a file name" + nameHint);
  }
  if (!std::filesystem::is_directory(dir, ec) || access(dir.c_str(), W_OK) != 0) {
    return Status::Error(flag + " " + path + ": cannot write into " + dir.string());
  }
  return Status::Ok();
}

Status MakeOutputDirectory(const std::string& flag, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return Status::Ok();
  if (fs::exists(dir, ec)) return Status::Error(flag + " " + ShowText(dir) + ": exists and is not a directory");
  fs::path normal = fs::path(dir).lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();  // "out/"
  const fs::path parent = normal.parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec)) {
    return Status::Error(flag + " " + ShowText(dir) + ": " + ShowText(parent.string()) + " does not exist; make it first");
  }
  fs::create_directory(dir, ec);
  if (ec) return Status::Error(flag + " " + ShowText(dir) + ": cannot create the directory: " + ec.message());
  return Status::Ok();
}

}  // namespace sphxr::app
