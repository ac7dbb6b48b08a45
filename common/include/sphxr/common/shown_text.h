#pragma once
// The one way text a user supplied (a scene's names and keys, a state file's scene name, a command
// line's values) reaches a terminal or a log: every code point a terminal could act on instead of
// showing is escaped, and a long value is cut. A probe name of ESC]0;...BEL retitled the terminal, a
// newline in it forged a second "sphxr: error:" line, and U+202E turned the rest of a message around.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace sphxr {

/// Bytes of a value shown in a message before it is cut ("..." and its full length follow).
inline constexpr size_t kShownLength = 80;
/// Names of a list shown before the rest are counted ("and 1,017 more").
inline constexpr size_t kShownNames = 8;

/// Unicode's general categories Cc (C0 controls, DEL, C1 controls such as U+0085 and U+009B), Cf
/// (format characters: the bidi embeddings, overrides and isolates U+202A-U+202E and U+2066-U+2069,
/// zero-width characters, U+FEFF, tag characters) and Zl/Zp (U+2028, U+2029).
bool IsHiddenCodePoint(char32_t c);

/// `text` as it may be printed: valid UTF-8 with every hidden code point written as \xNN (below U+0080),
/// \uNNNN or \U00NNNNNN, and every byte that is not UTF-8 as \xNN. At most `maxBytes` bytes of it are
/// kept (never a part of an escape or of a character), then "... (N bytes)". Applied twice it changes
/// nothing more (the escapes are printable).
std::string ShowText(std::string_view text, size_t maxBytes = kShownLength);

/// The first `maxNames` names, each through ShowText, joined by ", ", then "and N more".
std::string ShowList(const std::vector<std::string>& names, size_t maxNames = kShownNames);

/// `value` in the fewest digits that read back as the same double ("10.0000001", "1e-06", "3600",
/// "nan", "inf"): a bound and a value just past it print differently, as %g's six digits did not.
std::string ShowNumber(double value);

/// Text that ShowText would leave as it is: valid UTF-8 without a hidden code point. The checks of a
/// scene's names refuse what this refuses.
bool IsPlainText(std::string_view text);

}  // namespace sphxr
