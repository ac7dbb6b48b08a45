#pragma once
// Reading a whole text file given on the command line or in a scene (scene files, trajectories), with
// a size limit: a path that is a device or an endless pipe (/dev/zero) must be refused, not read until
// the kernel kills the process. Pipes within the limit still work (--scene /dev/stdin).
#include <cstddef>
#include <string>

#include "sphxr/common/status.h"

namespace sphxr {

/// Reads `path` into `*out`. Errors (one line, naming the path and `what`): a directory, a file that
/// cannot be opened, more than `maxBytes` bytes.
Status ReadTextFile(const std::string& path, const char* what, size_t maxBytes, std::string* out);

}  // namespace sphxr
