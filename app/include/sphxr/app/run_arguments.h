#pragma once
// The arguments of a run that the command line (--time, --steps, --settle, --threads), the Python module
// (sphxr.Run's threads and settle; run_to, advance, step) and its sweeps (--time, --steps, --settle,
// --threads, --workers) take: one table of bounds, one parser, one form of message ("--settle 4000: must
// be from 0 to 3600"), so that none of the three accepts what another refuses. Paths given to the module
// are checked here too (a NUL byte would cut the file name the system sees).
#include <string>
#include <string_view>

#include "sphxr/common/status.h"

namespace sphxr::app {

inline constexpr double kMaxRunTime = 1e6;            // s of simulated time a run, or a target clock, may reach
inline constexpr double kMaxSettle = 3600.0;          // s of settling
inline constexpr double kMaxSteps = 1099511627776.0;  // 2^40 steps

/// One argument's bounds, by the name it is given under.
struct RunArgumentRule {
  std::string_view name;  // "--time", "run_to", ...
  double min, max;        // inclusive; max < 0: sim::MaxSolverThreads()
  bool integer;
  std::string_view what;  // the range in words after "must be from MIN to MAX", e.g. "s"
};

/// The rule of `name`, or nullptr: --time, --steps, --settle, --threads, --workers (the command line's
/// and the sweeps'), run_to, advance, step, settle, threads (the module's).
const RunArgumentRule* FindRunArgument(std::string_view name);

/// `value` against the rule of `name`: finite, integral where it must be, within the bounds.
Status CheckRunArgument(std::string_view name, double value);

/// `text` as the command line reads a number (decimal: no hexadecimal, no "inf"), then its rule. The
/// message shows the text as given (escaped, cut).
Status ParseRunArgument(std::string_view name, std::string_view text, double* out);

/// A file name given to the module: not empty where `required`, and no NUL byte.
Status CheckPathArgument(std::string_view name, std::string_view path, bool required = true);

/// A message as the module and the sweeps hand it on: every hidden code point escaped (ShowText) and
/// cut to `maxBytes`; applied twice it changes nothing more.
std::string ShownMessage(std::string_view message, size_t maxBytes = 2000);

}  // namespace sphxr::app
