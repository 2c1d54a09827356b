// JSON text: strings escaped per RFC 8259, numbers in shortest round-trip form (null if not finite).
#pragma once

#include "io/common/number_format.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>

namespace toposimp::io {

inline void append_json_string(std::string& out, std::string_view text) {
    out += '"';
    for (const char c : text) {
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (static_cast<unsigned char>(c) < 0x20) {
                    char escaped[8];
                    std::snprintf(escaped, sizeof escaped, "\\u%04x", static_cast<unsigned char>(c));
                    out += escaped;
                } else {
                    out += c;
                }
        }
    }
    out += '"';
}

inline std::string json_string(std::string_view text) {
    std::string out;
    append_json_string(out, text);
    return out;
}

inline void append_json_number(std::string& out, double value) {
    if (std::isfinite(value)) {
        append_number(out, value);
    } else {
        out += "null";  // JSON has no NaN or infinity
    }
}

inline std::string json_number(double value) {
    std::string out;
    append_json_number(out, value);
    return out;
}

}  // namespace toposimp::io
