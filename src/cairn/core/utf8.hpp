#pragma once
/// \file
/// Text that reaches a renderer or a JSON writer must be valid UTF-8; file names are bytes. Cairo
/// refuses to draw a title holding a Latin-1 file name ("input string not valid UTF-8") and
/// nlohmann's default dump throws: the picture or report of a finished run would be lost.

#include <string>
#include <string_view>

namespace cairn::core {

/// `text` with every byte that does not start or continue a valid UTF-8 sequence (RFC 3629:
/// no overlong forms, no surrogates, at most U+10FFFF) replaced by U+FFFD. Valid text is returned
/// unchanged.
inline std::string valid_utf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  std::size_t i = 0;
  while (i < text.size()) {
    const auto b0 = static_cast<unsigned char>(text[i]);
    std::size_t length = 0;
    unsigned lo = 0x80, hi = 0xBF;  // allowed range of the second byte
    if (b0 < 0x80) length = 1;
    else if (b0 >= 0xC2 && b0 <= 0xDF) length = 2;
    else if (b0 == 0xE0) length = 3, lo = 0xA0;
    else if ((b0 >= 0xE1 && b0 <= 0xEC) || b0 == 0xEE || b0 == 0xEF) length = 3;
    else if (b0 == 0xED) length = 3, hi = 0x9F;
    else if (b0 == 0xF0) length = 4, lo = 0x90;
    else if (b0 >= 0xF1 && b0 <= 0xF3) length = 4;
    else if (b0 == 0xF4) length = 4, hi = 0x8F;
    bool valid = length > 0 && i + length <= text.size();
    for (std::size_t k = 1; valid && k < length; ++k) {
      const auto b = static_cast<unsigned char>(text[i + k]);
      valid = k == 1 ? (b >= lo && b <= hi) : (b >= 0x80 && b <= 0xBF);
    }
    if (valid) {
      out.append(text.substr(i, length));
      i += length;
    } else {
      out += "\xEF\xBF\xBD";  // U+FFFD
      ++i;
    }
  }
  return out;
}

}  // namespace cairn::core
