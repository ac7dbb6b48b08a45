#pragma once
// The command line of every mode (`sphxr --help`): its options (options.h) parsed and checked, one
// line naming the flag for anything refused. What every mode then does with them before it runs is
// run_start.h. main.cpp picks the mode; headless.h, desktop.h and xr_mode.h run one.
#include <string>

#include "sphxr/app/options.h"
#include "sphxr/common/status.h"

namespace sphxr::app {

/// Parses argv. Values are checked here (a bad number is a one-line error naming the flag).
Status ParseCommandLine(int argc, const char* const* argv, Options* out);
std::string UsageText();

}  // namespace sphxr::app
