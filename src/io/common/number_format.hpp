// Shortest round-trip decimal text for doubles: parsing the text gives back the same double.
#pragma once

#include <charconv>
#include <string>
#include <string_view>

namespace toposimp::io {

inline void append_number(std::string& out, double value) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    out.append(buffer, result.ptr);
}

// Parses a whole token as a double (correctly rounded); false if it is not a number.
inline bool parse_number(std::string_view text, double& value) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const auto result = std::from_chars(text.data(), text.data() + text.size(), value);
    return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

}  // namespace toposimp::io
