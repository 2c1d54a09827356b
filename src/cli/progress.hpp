// Progress on a terminal: one line, rewritten in place, at most ten times a second; nothing at
// all when the error stream is not a terminal (pipes, logs) or with --quiet.
#pragma once

#include <chrono>
#include <ostream>
#include <string>

namespace toposimp::cli {

class Progress {
public:
    Progress(std::ostream& err, bool enabled) : err_(err), enabled_(enabled) {}
    ~Progress() { done(); }

    void phase(const std::string& name) {
        phase_ = name;
        last_ = {};
        show(-1);
    }

    // `share` of the current phase done (0…1).
    void update(double share) {
        const auto now = std::chrono::steady_clock::now();
        if (now - last_ < std::chrono::milliseconds(100)) return;
        last_ = now;
        show(share);
    }

    // Clears the line.
    void done() {
        if (!enabled_ || !shown_) return;
        err_ << "\r\033[K" << std::flush;
        shown_ = false;
    }

private:
    void show(double share) {
        if (!enabled_) return;
        err_ << "\r\033[Ktoposimp: " << phase_;
        if (share >= 0) err_ << ' ' << static_cast<int>(share * 100) << '%';
        err_ << std::flush;
        shown_ = true;
    }

    std::ostream& err_;
    bool enabled_;
    bool shown_ = false;
    std::string phase_;
    std::chrono::steady_clock::time_point last_{};
};

}  // namespace toposimp::cli
