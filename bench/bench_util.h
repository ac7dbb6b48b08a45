#pragma once
// Small helpers shared by the benchmarks: the machine, the process's memory, timestamps, CSV files,
// command-line numbers.
// Benchmarks report; they never assert a target.
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sphxr::bench {

/// A command-line number: the whole text one finite number (nothing after it).
inline bool ParseNumber(const char* text, double* out) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

/// A command-line integer: the whole text one base-10 integer (nothing after it, no overflow) in [lo, hi].
inline bool ParseInteger(const char* text, long lo, long hi, long* out) {
  char* end = nullptr;
  errno = 0;  // overflow shows only here: strtol clamps the value to LONG_MIN / LONG_MAX
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno == ERANGE || v < lo || v > hi) return false;
  *out = v;
  return true;
}

/// ParseInteger for a command-line option's value: on a bad value prints the one line
/// "<program>: <option> <text>: must be an integer from <lo> to <hi>" to stderr and returns false.
inline bool IntegerOption(const char* program, const std::string& option, const char* text, long lo, long hi,
                          int* out) {
  long n = 0;
  if (!ParseInteger(text, lo, hi, &n)) {
    std::fprintf(stderr, "%s: %s %s: must be an integer from %ld to %ld\n", program, option.c_str(), text, lo, hi);
    return false;
  }
  *out = static_cast<int>(n);
  return true;
}

/// "model name" of the first processor in /proc/cpuinfo ("unknown" when absent).
inline std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) {
        std::string v = line.substr(colon + 1);
        v.erase(0, v.find_first_not_of(" \t"));
        return v;
      }
    }
  }
  return "unknown";
}

/// Online processors (what `nproc` prints without affinity limits).
inline int CpuCount() { return static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN)); }

/// The 1-minute load average (/proc/loadavg), or -1.
inline double LoadAverage() {
  std::ifstream in("/proc/loadavg");
  double v = -1.0;
  in >> v;
  return in ? v : -1.0;
}

/// A field of /proc/self/status in bytes ("VmHWM", "VmRSS"), or -1.
inline int64_t ProcStatusBytes(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) {
      std::istringstream ss(line.substr(key.size() + 1));
      int64_t kb = -1;
      ss >> kb;
      return kb < 0 ? -1 : kb * 1024;
    }
  }
  return -1;
}

/// Returns freed heap memory to the OS and resets the peak resident set (VmHWM) to the current RSS
/// (Linux >= 4.0: writing 5 to /proc/self/clear_refs). False when the reset is not available.
inline bool ResetPeakRss() {
  malloc_trim(0);
  std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
  if (!f) return false;
  const bool ok = std::fputs("5", f) >= 0;
  return (std::fclose(f) == 0) && ok;
}

/// CPU time of the whole process (all threads), s. With one solver thread on a busy machine this is
/// close to what the step would take on an idle core; with several it also counts OpenMP spin-waiting.
inline double ProcessCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// UTC time as 2024-01-31T12:34:56Z.
inline std::string UtcTimestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

/// Quotes a CSV field when it holds a comma or a quote.
inline std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

/// The reason `path` cannot take this bench's table ("" if it can): see OpenCsv. For a bench that writes
/// its CSV at the end, to ask before minutes of measuring. `*empty`: the file is missing or empty.
inline std::string CsvRefusal(const std::string& path, const std::string& header, bool* empty = nullptr) {
  std::ifstream probe(path);
  std::string first;
  if (probe) std::getline(probe, first);
  if (empty) *empty = first.empty();
  if (!first.empty() && first != header) {
    return "--csv " + path + ": its first line is not this bench's header (another file, or an older version's "
           "columns): give a new file";
  }
  return {};
}

/// Opens `path` (appending, or anew) and writes `header` first when the file is new or empty. Returns
/// "" or the reason it cannot: a file that exists with another first line is refused either way, since
/// appended rows would sit under the wrong names, and overwriting it would destroy something that is
/// not this bench's table (a scene given by mistake).
inline std::string OpenCsv(const std::string& path, const std::string& header, bool append, std::ofstream* out) {
  bool empty = true;
  if (std::string why = CsvRefusal(path, header, &empty); !why.empty()) return why;
  empty = empty || !append;  // (a file opened anew is)
  out->open(path, append ? std::ios::app : std::ios::trunc);
  if (!*out) return "--csv " + path + ": cannot open for writing";
  if (empty) *out << header << '\n';
  return {};
}

inline double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// A steady-clock duration in milliseconds.
inline double Ms(std::chrono::steady_clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

/// The q-quantile (0..1) by nearest rank.
inline double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[k];
}

}  // namespace sphxr::bench
