// Small pieces every subcommand shares: parsing a --keep share, peak memory, elapsed time.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>

namespace toposimp::cli {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

// "10%" or "0.1" as a share in [0, 1]; otherwise nullopt and `problem` says why (`things` names
// what is kept: "vertices", "faces").
inline std::optional<double> parse_share(const std::string& keep, const std::string& things, std::string& problem) {
    std::string text = keep;
    const bool percent = !text.empty() && text.back() == '%';
    if (percent) text.pop_back();
    double value = 0;
    std::istringstream parse(text);
    if (!(parse >> value) || !parse.eof() || !std::isfinite(value) || value < 0) {
        problem = "--keep takes a share such as 10% or 0.1, not '" + keep + "'";
        return std::nullopt;
    }
    if (percent) value /= 100.0;
    if (value > 1.0) {
        problem = "--keep " + keep + " is more than all " + things + (percent ? "" : " (did you mean " + keep + "%?)");
        return std::nullopt;
    }
    return value;
}

// Does glibc's malloc ask for transparent huge pages (GLIBC_TUNABLES has glibc.malloc.hugetlb=1:
// the toposimp command and toposimp.dask set it for themselves unless the user set it)? For -v.
inline const char* heap_pages() {
    const char* tunables = std::getenv("GLIBC_TUNABLES");
    return tunables != nullptr && std::string_view(tunables).find("glibc.malloc.hugetlb=1") != std::string_view::npos
               ? "transparent huge pages asked for (glibc.malloc.hugetlb=1, as toposimp and toposimp.dask set it)"
               : "glibc.malloc.hugetlb is not 1: huge pages only where the system's THP mode is `always`";
}

// Peak resident memory of this process so far, in MiB (Linux /proc; 0 where unknown).
inline double peak_memory_mib() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
    }
    return 0.0;
}

}  // namespace toposimp::cli
