#pragma once
// The default names a running state is saved under: the window's and the headset's save without
// --save-state, and a lost headset session's water.
#include <cstddef>
#include <string>

namespace sphxr::app {

/// Bytes of a scene's name kept in a state file's default name.
inline constexpr size_t kMaxStateStem = 100;
/// "<scene name>.state" for a save without --save-state: the name's letters, digits, '-', '_' and a '.'
/// after a letter or digit only (others become '_'), so a shared scene cannot name a path outside the
/// working directory, its first kMaxStateStem bytes only; "sphxr.state" for a name without any.
std::string DefaultStatePath(const std::string& sceneName);
/// "<scene name>-lost.state" (the same name rule): where a lost headset session's water goes when no
/// --save-state was given, beside, not over, what the save button wrote.
std::string LostStatePath(const std::string& sceneName);

}  // namespace sphxr::app
