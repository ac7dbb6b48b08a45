#include "sphxr/app/run_arguments.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

#include "sphxr/common/log.h"
#include "sphxr/common/shown_text.h"
#include "sphxr/sim/openmp_wait.h"

namespace sphxr::app {
namespace {

constexpr double kMachine = -1.0;  // RunArgumentRule::max: sim::MaxSolverThreads()

constexpr RunArgumentRule kRules[] = {
    {"--time", 1e-9, kMaxRunTime, false, "s"},
    {"--steps", 1.0, kMaxSteps, true, ""},
    {"--settle", 0.0, kMaxSettle, false, "s"},
    {"--threads", 0.0, kMachine, true, "(0: all cores; four per core here, at least 64)"},
    {"--workers", 1.0, kMachine, true, "(four per core here, at least 64)"},
    {"run_to", 0.0, kMaxRunTime, false, "s"},
    {"advance", 0.0, kMaxRunTime, false, "s"},
    {"step", 0.0, kMaxSteps, true, ""},
    {"settle", 0.0, kMaxSettle, false, "s"},
    {"threads", 0.0, kMachine, true, "(0: all cores; four per core here, at least 64)"},
};

Status Check(const RunArgumentRule& rule, const std::string& shown, double value) {
  const std::string name(rule.name);
  if (!std::isfinite(value)) return Status::Error(name + " " + shown + ": not a finite number");
  const double max = rule.max < 0.0 ? static_cast<double>(sim::MaxSolverThreads()) : rule.max;
  if (value < rule.min || value > max) {
    return Status::Error(Format("%s %s: must be from %s to %s%s%s", name.c_str(), shown.c_str(),
                                ShowNumber(rule.min).c_str(), ShowNumber(max).c_str(), rule.what.empty() ? "" : " ",
                                std::string(rule.what).c_str()));
  }
  if (rule.integer && value != std::floor(value)) return Status::Error(name + " " + shown + ": not a whole number");
  return Status::Ok();
}

}  // namespace

const RunArgumentRule* FindRunArgument(std::string_view name) {
  for (const RunArgumentRule& rule : kRules) {
    if (rule.name == name) return &rule;
  }
  return nullptr;
}

Status CheckRunArgument(std::string_view name, double value) {
  const RunArgumentRule* rule = FindRunArgument(name);
  if (!rule) return Status::Error("no run argument " + ShowText(name));
  // A whole number as the command line shows one typed (1000000000, not 1e+09).
  const bool whole = std::isfinite(value) && value == std::floor(value) && std::fabs(value) < 1e15;
  return Check(*rule, whole ? Format("%.0f", value) : ShowNumber(value), value);
}

Status ParseRunArgument(std::string_view name, std::string_view text, double* out) {
  const RunArgumentRule* rule = FindRunArgument(name);
  if (!rule) return Status::Error("no run argument " + ShowText(name));
  const std::string shown = ShowText(text, 40), flag(name);
  const std::string copy(text);
  if (copy.size() != std::string(copy.c_str()).size()) return Status::Error(flag + " " + shown + ": not a number");
  if (copy.find_first_of("xXpP") != std::string::npos)
    return Status::Error(flag + " " + shown + ": not a decimal number");
  char* end = nullptr;
  double v = 0.0;
  if (rule->integer) {  // digits only, as the shell's users write a count ("1e3" is not one)
    errno = 0;
    const long long n = std::strtoll(copy.c_str(), &end, 10);
    v = errno == ERANGE ? (n < 0 ? -HUGE_VAL : HUGE_VAL) : static_cast<double>(n);
    if (errno == ERANGE && !copy.empty() && *end == '\0') {
      return Status::Error(Format("%s %s: must be from %s to %s", flag.c_str(), shown.c_str(),
                                  ShowNumber(rule->min).c_str(),
                                  ShowNumber(rule->max < 0.0 ? sim::MaxSolverThreads() : rule->max).c_str()));
    }
  } else {
    v = std::strtod(copy.c_str(), &end);
  }
  if (copy.empty() || *end != '\0' || end == copy.c_str()) {
    return Status::Error(flag + " " + shown + (rule->integer ? ": not an integer" : ": not a number"));
  }
  if (Status s = Check(*rule, shown, v); !s) return s;
  *out = v;
  return Status::Ok();
}

Status CheckPathArgument(std::string_view name, std::string_view path, bool required) {
  const std::string n(name);
  if (required && path.empty()) return Status::Error(n + ": give a file name");
  if (path.find('\0') != std::string_view::npos) {
    return Status::Error(n + " " + ShowText(path) + ": a file name cannot hold a NUL byte (\\x00)");
  }
  return Status::Ok();
}

std::string ShownMessage(std::string_view message, size_t maxBytes) { return ShowText(message, maxBytes); }

}  // namespace sphxr::app
