#pragma once
// One logger with levels. Messages go to stderr (the app may install another sink).
// Never log per particle or per frame without a rate limit: use LogOnce for repeated conditions.
#include <cstdarg>
#include <functional>
#include <string>

namespace sphxr {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3, kOff = 4 };

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
/// Replaces the sink (default: stderr). Pass nullptr to restore the default.
void SetLogSink(std::function<void(LogLevel, const std::string&)> sink);

void Log(LogLevel level, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
/// Logs only the first time `key` is seen in this process (for "clamped dt" and similar).
void LogOnce(const char* key, LogLevel level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
/// Forgets every LogOnce key (tests).
void ResetLogOnce();

std::string Format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

#define SPHXR_LOG_DEBUG(...) ::sphxr::Log(::sphxr::LogLevel::kDebug, __VA_ARGS__)
#define SPHXR_LOG_INFO(...) ::sphxr::Log(::sphxr::LogLevel::kInfo, __VA_ARGS__)
#define SPHXR_LOG_WARN(...) ::sphxr::Log(::sphxr::LogLevel::kWarn, __VA_ARGS__)
#define SPHXR_LOG_ERROR(...) ::sphxr::Log(::sphxr::LogLevel::kError, __VA_ARGS__)

}  // namespace sphxr
