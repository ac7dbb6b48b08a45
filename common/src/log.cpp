#include "sphxr/common/log.h"

#include "sphxr/common/shown_text.h"

#include <cstdio>
#include <mutex>
#include <set>
#include <vector>

namespace sphxr {
namespace {

std::mutex g_mutex;
LogLevel g_level = LogLevel::kInfo;
std::function<void(LogLevel, const std::string&)> g_sink;
std::set<std::string> g_onceKeys;

const char* LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarn: return "warning";
    case LogLevel::kError: return "error";
    default: return "";
  }
}

std::string VFormat(const char* fmt, va_list args) {
  va_list copy;
  va_copy(copy, args);
  const int n = std::vsnprintf(nullptr, 0, fmt, copy);
  va_end(copy);
  if (n <= 0) return {};
  std::vector<char> buf(static_cast<size_t>(n) + 1);
  std::vsnprintf(buf.data(), buf.size(), fmt, args);
  return std::string(buf.data(), static_cast<size_t>(n));
}

// Every line leaves through ShowText: whatever a message quotes, it cannot move the cursor, retitle the
// terminal, turn the text around or start a line of its own.
void Emit(LogLevel level, const std::string& raw) {
  if (level < g_level) return;
  const std::string text = ShowText(raw, std::string::npos);
  if (g_sink) {
    g_sink(level, text);
    return;
  }
  std::fprintf(stderr, "sphxr %s: %s\n", LevelName(level), text.c_str());
}

}  // namespace

void SetLogLevel(LogLevel level) {
  std::lock_guard lock(g_mutex);
  g_level = level;
}
LogLevel GetLogLevel() { return g_level; }
void SetLogSink(std::function<void(LogLevel, const std::string&)> sink) {
  std::lock_guard lock(g_mutex);
  g_sink = std::move(sink);
}

void Log(LogLevel level, const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  std::string text = VFormat(fmt, args);
  va_end(args);
  std::lock_guard lock(g_mutex);
  Emit(level, text);
}

void LogOnce(const char* key, LogLevel level, const char* fmt, ...) {
  std::lock_guard lock(g_mutex);
  if (!g_onceKeys.insert(key).second) return;
  va_list args;
  va_start(args, fmt);
  std::string text = VFormat(fmt, args);
  va_end(args);
  Emit(level, text);
}

void ResetLogOnce() {
  std::lock_guard lock(g_mutex);
  g_onceKeys.clear();
}

std::string Format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  std::string text = VFormat(fmt, args);
  va_end(args);
  return text;
}

}  // namespace sphxr
