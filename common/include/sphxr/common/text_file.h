#pragma once
// Reading a whole text file given on the command line or in a scene (scene files, trajectories), with
// a size limit. Only regular files: a device or an endless pipe (/dev/zero) would be read until the
// kernel kills the process, and a FIFO with no writer blocks for ever (--scene /dev/stdin works when
// stdin is a redirected file).
#include <cstddef>
#include <string>

#include "sphxr/common/status.h"

namespace sphxr {

/// Reads `path` into `*out`. Errors (one line, naming the path and `what`): a directory, a file that
/// cannot be opened, not a regular file (a pipe or device), more than `maxBytes` bytes.
Status ReadTextFile(const std::string& path, const char* what, size_t maxBytes, std::string* out);

}  // namespace sphxr
