#include "util/text.h"

#include <cstdint>

namespace shgi {
namespace {

// Length of the well-formed UTF-8 sequence starting at text[i], or 0 if none does (the table
// of well-formed byte sequences in the Unicode Standard, ch. 3, table 3-7).
size_t sequence_length(std::string_view text, size_t i) {
    const auto byte = [&](size_t k) { return uint8_t(text[k]); };
    const uint8_t lead = byte(i);
    if (lead < 0x80) return 1;
    size_t length = 0;
    uint8_t low = 0x80, high = 0xBF;  // range of the second byte
    if (lead >= 0xC2 && lead <= 0xDF) {
        length = 2;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
        length = 3;
        if (lead == 0xE0) low = 0xA0;   // no overlong forms
        if (lead == 0xED) high = 0x9F;  // no surrogates
    } else if (lead >= 0xF0 && lead <= 0xF4) {
        length = 4;
        if (lead == 0xF0) low = 0x90;   // no overlong forms
        if (lead == 0xF4) high = 0x8F;  // nothing past U+10FFFF
    } else {
        return 0;
    }
    if (i + length > text.size()) return 0;
    if (byte(i + 1) < low || byte(i + 1) > high) return 0;
    for (size_t k = 2; k < length; ++k)
        if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
    return length;
}

}  // namespace

bool is_utf8(std::string_view text) {
    for (size_t i = 0; i < text.size();) {
        const size_t length = sequence_length(text, i);
        if (length == 0) return false;
        i += length;
    }
    return true;
}

std::string utf8_escaped(std::string_view text) {
    if (is_utf8(text)) return std::string(text);
    static constexpr char kHex[] = "0123456789abcdef";
    std::string escaped;
    for (size_t i = 0; i < text.size();) {
        const size_t length = sequence_length(text, i);
        if (length > 0) {
            escaped.append(text.substr(i, length));
            i += length;
            continue;
        }
        const uint8_t byte = uint8_t(text[i++]);
        escaped += "\\x";
        escaped += kHex[byte >> 4];
        escaped += kHex[byte & 0xF];
    }
    return escaped;
}

}  // namespace shgi
