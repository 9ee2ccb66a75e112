// is_utf8 / utf8_escaped against the Unicode Standard's well-formed sequences, and the escapes
// Python's "backslashreplace" gives for the same bytes.
#include <gtest/gtest.h>

#include <string>

#include "util/text.h"

namespace shgi {
namespace {

TEST(Text, WellFormedUtf8IsKept) {
    for (const std::string text : {"", "Material.001", "caf\xc3\xa9", "\xe2\x82\xac 5",
                                   "\xf0\x9f\x98\x80", "\xef\xbf\xbf", "\xf4\x8f\xbf\xbf"}) {
        EXPECT_TRUE(is_utf8(text)) << text;
        EXPECT_EQ(utf8_escaped(text), text);
    }
}

TEST(Text, IllFormedBytesAreEscapedOneByOne) {
    // Latin-1, a lone continuation byte, a truncated sequence, an overlong '/', a surrogate,
    // a code point past U+10FFFF and bytes that never occur in UTF-8.
    const std::pair<std::string, std::string> cases[] = {
        {"caf\xe9", "caf\\xe9"},
        {"\x80x", "\\x80x"},
        {"\xe2\x82", "\\xe2\\x82"},
        {"\xc0\xaf", "\\xc0\\xaf"},
        {"\xed\xa0\x80", "\\xed\\xa0\\x80"},
        {"\xf4\x90\x80\x80", "\\xf4\\x90\\x80\\x80"},
        {"\xff\xfe ok \xc3\xa9", "\\xff\\xfe ok \xc3\xa9"},
    };
    for (const auto& [bytes, escaped] : cases) {
        EXPECT_FALSE(is_utf8(bytes)) << escaped;
        EXPECT_EQ(utf8_escaped(bytes), escaped);
        EXPECT_TRUE(is_utf8(utf8_escaped(bytes)));
    }
}

}  // namespace
}  // namespace shgi
