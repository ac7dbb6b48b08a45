#include "state_paths.h"

#include <cctype>

namespace sphxr::app {

std::string DefaultStatePath(const std::string& sceneName) {
  // The scene's name comes from a file that may be shared: only its letters, digits, '-', '_' and inner
  // '.' make the file name (a name like "../x" or "/abs/x" saved outside the working directory).
  std::string stem;
  char previous = '\0';
  for (char c : sceneName) {
    const bool safe = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ||
                      (c == '.' && std::isalnum(static_cast<unsigned char>(previous)));
    stem += safe ? c : '_';
    previous = c;
  }
  if (stem.find_first_not_of('_') == std::string::npos) stem = "sphxr";
  // A file name has at most 255 bytes: a long scene name is cut (its "-lost" and ".state" still fit).
  if (stem.size() > kMaxStateStem) stem.resize(kMaxStateStem);
  return stem + ".state";
}

std::string LostStatePath(const std::string& sceneName) {
  const std::string path = DefaultStatePath(sceneName);
  return path.substr(0, path.size() - 6) + "-lost.state";
}

}  // namespace sphxr::app
