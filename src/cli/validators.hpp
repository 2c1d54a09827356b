// The command line's own checks of option values, with messages a user can act on. CLI11's
// NonNegativeNumber lets NaN through (which then meant "not given": --remove-points nan became the
// default --keep 10%) and words its refusals with the largest double, 309 digits long (issue 29).
#pragma once

#include <CLI/Validators.hpp>

#include <charconv>
#include <cmath>
#include <string>

namespace toposimp::cli {

// A finite number, at least `least` (0: any count or size; 1: a band number, a thread count).
inline CLI::Validator number_at_least(double least) {
    return CLI::Validator(
        [least](std::string& text) -> std::string {
            double value = 0;
            const char* begin = text.data() + (text.starts_with('+') ? 1 : 0);
            const char* end = text.data() + text.size();
            const auto [at, error] = std::from_chars(begin, end, value);
            if (error != std::errc() || at != end || !std::isfinite(value)) return "'" + text + "' is not a finite number";
            if (value < least) return "'" + text + "' is less than " + (least == 0 ? "0" : "1");
            return {};
        },
        least == 0 ? "NUMBER >= 0" : "NUMBER >= 1");
}

}  // namespace toposimp::cli
