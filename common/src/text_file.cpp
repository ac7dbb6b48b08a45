#include "sphxr/common/text_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "sphxr/common/shown_text.h"

namespace sphxr {

Status ReadTextFile(const std::string& path, const char* what, size_t maxBytes, std::string* out) {
  out->clear();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return Status::Error(ShowText(path) + ": is a directory, not a " + what);
  // Opened without blocking, then looked at: a FIFO with no writer would block the open for ever, and a
  // pipe or device can be read only once (the up-front check and the run each read the file).
  {
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return Status::Error(ShowText(path) + ": cannot open the " + what);
    struct stat st {};
    const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
    ::close(fd);
    if (!regular)
      return Status::Error(ShowText(path) + ": not a regular file (a pipe or device): give a " + what + " on disk");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(ShowText(path) + ": cannot open the " + what);
  char buffer[65536];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    out->append(buffer, static_cast<size_t>(in.gcount()));
    if (out->size() > maxBytes) {
      out->clear();
      return Status::Error(ShowText(path) + ": more than " + std::to_string(maxBytes >> 20) + " MiB: not a " + what);
    }
  }
  if (in.bad()) return Status::Error(ShowText(path) + ": read failed");
  return Status::Ok();
}

}  // namespace sphxr
