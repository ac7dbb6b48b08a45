// libFuzzer target: the run arguments' parser (app/run_arguments.h), shared by the command line, the
// Python module and its sweeps. The first byte picks the argument, the rest is its text. Any input
// must give a finite value within the argument's bounds, or one short line of plain text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "sphxr/app/run_arguments.h"
#include "sphxr/common/shown_text.h"

namespace {

void ExpectOneLine(const sphxr::Status& s) {
  if (s.message().size() > 400 || !sphxr::IsPlainText(s.message())) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static constexpr const char* kNames[] = {"--time", "--steps", "--settle", "--threads", "--workers",
                                           "run_to", "advance", "step",     "settle",    "threads"};
  if (size == 0) return 0;
  const char* name = kNames[data[0] % (sizeof(kNames) / sizeof(kNames[0]))];
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const sphxr::app::RunArgumentRule* rule = sphxr::app::FindRunArgument(name);
  if (!rule) std::abort();
  double value = -12345.0;
  const sphxr::Status s = sphxr::app::ParseRunArgument(name, text, &value);
  if (s) {
    if (!std::isfinite(value) || value < rule->min || (rule->integer && value != std::floor(value))) std::abort();
    // The same value checked as a number (the module's path) must pass too.
    if (!sphxr::app::CheckRunArgument(name, value)) std::abort();
  } else {
    ExpectOneLine(s);
  }
  const sphxr::Status path = sphxr::app::CheckPathArgument(name, text);
  if (!path) ExpectOneLine(path);
  // A message handed on (the module's sphxr.Error, the program's error line): plain text, bounded.
  const std::string shown = sphxr::app::ShownMessage(text);
  if (shown.size() > 2000 + 32 || !sphxr::IsPlainText(shown)) std::abort();
  return 0;
}
