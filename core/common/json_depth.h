#pragma once
// Untrusted JSON (landmark files, speech documents): whether the text nests
// arrays and objects deeper than max_depth, checked on the bytes before a
// parser builds it (4 MB of '[' would be millions of nested arrays).
#include <string>

namespace lk {

bool json_nested_deeper(const std::string& text, int max_depth);

}  // namespace lk
