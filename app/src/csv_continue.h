#pragma once
// A continued run (--load-state) appends to the CSV its first half wrote (--stats, --probes): the
// earlier rows are kept, never rewritten; rows after the state (an earlier continuation's) are cut off.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace sphxr::app {

/// What a continued run does with one row of the earlier file.
enum class RowFate { kKeep, kDrop, kForeign };

/// The bytes of the earlier CSV at `path` to keep: its header line, which must equal `header`, and the
/// whole rows `fate(line)` keeps before the first it drops. -1 when the file is not a regular file (a
/// pipe or device is never read), has another header, holds a row `fate` calls foreign, or a kept row
/// is torn (no '\n'): the caller writes it anew. `dropped`: the rows after the kept ones.
template <class Fate>
int64_t CsvBytesToKeep(const std::string& path, const std::string& header, Fate&& fate, int64_t* dropped) {
  *dropped = 0;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return -1;
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!in || !std::getline(in, line) || line != header || in.eof()) return -1;
  int64_t keep = static_cast<int64_t>(line.size()) + 1, at = keep;
  while (std::getline(in, line)) {
    const bool whole = !in.eof();  // ended by '\n' (a torn last row is not)
    at += static_cast<int64_t>(line.size()) + (whole ? 1 : 0);
    switch (fate(line)) {
      case RowFate::kForeign: return -1;
      case RowFate::kKeep:
        if (!whole || *dropped > 0) return -1;
        keep = at;
        break;
      case RowFate::kDrop: ++*dropped; break;
    }
  }
  return keep;
}

}  // namespace sphxr::app
