#pragma once
// The checks of an output's place before a run makes anything: files the run writes, directories it
// fills. Each error names the flag.
#include <string>

#include "sphxr/common/status.h"

namespace sphxr::app {

/// A file that `flag` writes after the run: not a directory, in a directory we may write into (an
/// empty path: nothing to check).
Status CheckPlaceToWrite(const std::string& flag, const std::string& path, const char* nameHint);
/// An output directory: made when missing, but only in a directory that exists (a typo, or a path
/// under /, must not make a tree of directories, as root anywhere).
Status MakeOutputDirectory(const std::string& flag, const std::string& dir);

}  // namespace sphxr::app
