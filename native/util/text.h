// Text from files: names read from OBJ and MTL files are bytes in whatever encoding the writer
// used (Latin-1 from older tools), while Python, Blender and the log sink take UTF-8.
#pragma once

#include <string>
#include <string_view>

namespace shgi {

// True when `text` is well-formed UTF-8 (no overlong forms, surrogates or code points past
// U+10FFFF).
bool is_utf8(std::string_view text);

// `text` with every byte that is not part of a well-formed UTF-8 sequence written as \xNN, as
// Python's "backslashreplace" decodes it; well-formed text is returned unchanged.
std::string utf8_escaped(std::string_view text);

}  // namespace shgi
