#include "sphxr/common/shown_text.h"

#include <algorithm>
#include <charconv>
#include <cstdio>

namespace sphxr {
namespace {

// Unicode 15.1's Cf ranges (DerivedGeneralCategory.txt), inclusive.
constexpr struct {
  char32_t first, last;
} kFormat[] = {{0x00AD, 0x00AD},   {0x0600, 0x0605},   {0x061C, 0x061C},   {0x06DD, 0x06DD},
               {0x070F, 0x070F},   {0x0890, 0x0891},   {0x08E2, 0x08E2},   {0x180E, 0x180E},
               {0x200B, 0x200F},   {0x202A, 0x202E},   {0x2060, 0x2064},   {0x2066, 0x206F},
               {0xFEFF, 0xFEFF},   {0xFFF9, 0xFFFB},   {0x110BD, 0x110BD}, {0x110CD, 0x110CD},
               {0x13430, 0x1343F}, {0x1BCA0, 0x1BCA3}, {0x1D173, 0x1D17A}, {0xE0001, 0xE0001},
               {0xE0020, 0xE007F}};

// The code point at text[i] and its length in bytes; 0 bytes: not UTF-8 there (a stray continuation
// byte, a truncated sequence, an overlong form, a surrogate, past U+10FFFF).
size_t Decode(std::string_view text, size_t i, char32_t* c) {
  const unsigned char b = static_cast<unsigned char>(text[i]);
  if (b < 0x80) {
    *c = b;
    return 1;
  }
  size_t n = 0;
  char32_t v = 0;
  if ((b & 0xE0) == 0xC0) n = 2, v = b & 0x1F;
  else if ((b & 0xF0) == 0xE0) n = 3, v = b & 0x0F;
  else if ((b & 0xF8) == 0xF0) n = 4, v = b & 0x07;
  else return 0;
  if (i + n > text.size()) return 0;
  for (size_t k = 1; k < n; ++k) {
    const unsigned char t = static_cast<unsigned char>(text[i + k]);
    if ((t & 0xC0) != 0x80) return 0;
    v = (v << 6) | (t & 0x3F);
  }
  constexpr char32_t kLeast[] = {0, 0, 0x80, 0x800, 0x10000};
  if (v < kLeast[n] || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return 0;
  *c = v;
  return n;
}

}  // namespace

bool IsHiddenCodePoint(char32_t c) {
  if (c < 0x20 || (c >= 0x7F && c <= 0x9F)) return true;  // Cc
  if (c == 0x2028 || c == 0x2029) return true;            // Zl, Zp
  for (const auto& r : kFormat) {
    if (c >= r.first && c <= r.last) return true;
  }
  return false;
}

std::string ShowText(std::string_view text, size_t maxBytes) {
  std::string out;
  out.reserve(std::min(text.size(), maxBytes) + 16);
  char escape[16];
  for (size_t i = 0; i < text.size();) {
    char32_t c = 0;
    const size_t n = Decode(text, i, &c);
    std::string_view piece;
    if (n == 0) {
      std::snprintf(escape, sizeof(escape), "\\x%02X", static_cast<unsigned char>(text[i]));
      piece = escape;
    } else if (IsHiddenCodePoint(c)) {
      if (c < 0x80) std::snprintf(escape, sizeof(escape), "\\x%02X", static_cast<unsigned>(c));
      else if (c <= 0xFFFF) std::snprintf(escape, sizeof(escape), "\\u%04X", static_cast<unsigned>(c));
      else std::snprintf(escape, sizeof(escape), "\\U%08X", static_cast<unsigned>(c));
      piece = escape;
    } else {
      piece = text.substr(i, n);
    }
    if (out.size() + piece.size() > maxBytes) {
      out += "... (" + std::to_string(text.size()) + " bytes)";
      return out;
    }
    out += piece;
    i += n == 0 ? 1 : n;
  }
  return out;
}

std::string ShowList(const std::vector<std::string>& names, size_t maxNames) {
  std::string out;
  for (size_t k = 0; k < names.size() && k < maxNames; ++k) out += (k ? ", " : "") + ShowText(names[k]);
  if (names.size() > maxNames) out += " and " + std::to_string(names.size() - maxNames) + " more";
  return out;
}

std::string ShowNumber(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  return error == std::errc() ? std::string(text, end) : std::string("?");
}

bool IsPlainText(std::string_view text) {
  for (size_t i = 0; i < text.size();) {
    char32_t c = 0;
    const size_t n = Decode(text, i, &c);
    if (n == 0 || IsHiddenCodePoint(c)) return false;
    i += n;
  }
  return true;
}

}  // namespace sphxr
